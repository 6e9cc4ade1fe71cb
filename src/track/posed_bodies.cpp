#include "track/posed_bodies.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <limits>

#include "core/simd/lanes.h"

namespace dynahand::track {

namespace {

#define DYNAHAND_SIMD_KERNELS "track/plane_scan.inl"
#include "core/simd/for_each_level.inl"

// Lane offsets of the set bits of an eight-bit mask, in order (the rest zero): a branch-free
// compress of eight point indices.
struct CompressTable {
  alignas(32) std::int32_t lanes[256][8]{};
  constexpr CompressTable() {
    for (int mask = 0; mask < 256; ++mask) {
      int n = 0;
      for (int k = 0; k < 8; ++k) {
        lanes[mask][k] = 0;
        if (mask >> k & 1) lanes[mask][n++] = k;
      }
    }
  }
};
constexpr CompressTable kCompress;

#define DYNAHAND_SIMD_KERNELS "track/bulk_queries.inl"
#include "core/simd/for_each_level.inl"

// Bit k set for each lane k of the last eight of `padded` SoA slots that holds one of the n
// real points (the rest repeat the last point).
unsigned realLastLanes(std::size_t n, std::size_t padded) {
  return (1u << (n - (padded - simd::kLanes))) - 1u;
}

// The bulk queries body by body over eight points at a time (off: point by point, for tests).
std::atomic<bool> bulkQueries{true};

}  // namespace

void PosedBodies::set(std::span<const physics::ConvexShape* const> shapes,
                      std::span<const Pose> poses) {
  assert(shapes.size() == poses.size() && shapes.size() <= kMaxBodies);
  shapes_.assign(shapes.begin(), shapes.end());
  poses_.assign(poses.begin(), poses.end());
  if (tableShapes_ != shapes_) {  // plane tables are rebuilt only when the shapes change
    tableShapes_ = shapes_;
    planes_.resize(shapes.size());
    for (std::size_t i = 0; i < shapes.size(); ++i) {
      const auto& faces = shapes_[i]->faces();
      const std::size_t padded = (faces.size() + 7) / 8 * 8;
      PlaneTable& t = planes_[i];
      t.nx.assign(padded, 0.0f);
      t.ny.assign(padded, 0.0f);
      t.nz.assign(padded, 0.0f);
      t.offset.assign(padded, 1e30f);  // padding: distance -1e30, never the largest
      for (std::size_t f = 0; f < faces.size(); ++f) {
        t.nx[f] = faces[f].normal.x();
        t.ny[f] = faces[f].normal.y();
        t.nz[f] = faces[f].normal.z();
        t.offset[f] = faces[f].offset;
      }
    }
  }
  for (std::size_t i = 0; i < kMaxBodies; ++i) {  // far spheres pad past the last body
    const bool body = i < shapes.size();
    sphereR_[i] = body ? shapes_[i]->boundingRadius() : 0.0f;
    if (body)
      setCentroid(i, poses_[i].transform(shapes_[i]->centroid()));
    else
      sphereX_[i] = sphereY_[i] = sphereZ_[i] = 1e15f;
  }
}

void PosedBodies::setCentroid(std::size_t body, const Vec3& centroid) {
  sphereX_[body] = centroid.x();
  sphereY_[body] = centroid.y();
  sphereZ_[body] = centroid.z();
}

void PosedBodies::setPose(int body, const Pose& pose) {
  const auto i = static_cast<std::size_t>(body);
  poses_[i] = pose;
  setCentroid(i, pose.transform(shapes_[i]->centroid()));
}

Vec3 PosedBodies::toLocal(std::size_t body, const Vec3& p) const {
  // Pose::inverseTransform's arithmetic spelled out (Eigen's quaternion rotation
  // v + 2w (u x v) + u x 2(u x v) with u the conjugate's vector part), so that the eight-wide
  // path can repeat it operation for operation.
  const Quat& q = poses_[body].q;
  const Vec3& t = poses_[body].p;
  const float w = q.w(), ux = -q.x(), uy = -q.y(), uz = -q.z();
  const float dx = p.x() - t.x(), dy = p.y() - t.y(), dz = p.z() - t.z();
  float cx = uy * dz - uz * dy, cy = uz * dx - ux * dz, cz = ux * dy - uy * dx;
  cx += cx;
  cy += cy;
  cz += cz;
  return {(dx + w * cx) + (uy * cz - uz * cy), (dy + w * cy) + (uz * cx - ux * cz),
          (dz + w * cz) + (ux * cy - uy * cx)};
}

float PosedBodies::sphereGap(std::size_t body, const Vec3& p) const {
  const float dx = p.x() - sphereX_[body], dy = p.y() - sphereY_[body], dz = p.z() - sphereZ_[body];
  return std::sqrt(dx * dx + (dy * dy + dz * dz)) - sphereR_[body];
}

SurfaceHit PosedBodies::planarHit(std::size_t body, const Vec3& p, const Vec3& local, int face,
                                  float sd) const {
  // Outside, the bounding-sphere gap is also a lower bound on the exact distance; taking the
  // larger keeps the sphere culling consistent (the answer is order-free).
  const float d = sd < 0.0f ? -sd : std::max(sd, sphereGap(body, p));
  const auto& f = shapes_[body]->faces()[static_cast<std::size_t>(face)];
  return {static_cast<int>(body), face, d, sd, local - f.normal * sd};
}

SurfaceHit PosedBodies::exactHit(std::size_t body, const Vec3& local, float planeDist,
                                 int planeFace) const {
  Vec3 closest;
  int face = -1;
  const float sd = shapes_[body]->queryFromPlane(local, planeDist, planeFace, &closest, &face);
  return {static_cast<int>(body), face, std::abs(sd), sd, closest};
}

bool PosedBodies::useBulkQueries(bool enabled) {
  bulkQueries.store(enabled);
  return enabled;
}

float PosedBodies::maxPlaneDistance(const PlaneTable& t, const Vec3& q, int* face,
                                    float stopAbove) {
  // Eight independent lanes (maximum and its face per lane, plane_scan.inl), reduced at the
  // end: the same arithmetic on every SIMD level, so the same bits.
  const std::size_t n = t.offset.size();
  const float* nx = t.nx.data();
  const float* ny = t.ny.data();
  const float* nz = t.nz.data();
  const float* o = t.offset.data();
  float best[simd::kLanes];
  std::int32_t index[simd::kLanes];
  DYNAHAND_SIMD_DISPATCH(maxPlaneDistanceLanes, nx, ny, nz, o, n, q, stopAbove, best, index);
  float result = best[0];
  std::int32_t which = index[0];
  simd::foldLargestLane(best, index, result, which);  // ties go to the lower face index
  *face = which;
  return result;
}

namespace {
// (distance, body) in lexicographic order: the planar answer is the least over all bodies.
bool beats(const SurfaceHit& a, const SurfaceHit& b) {
  return a.distance < b.distance || (a.distance == b.distance && a.body < b.body);
}
}  // namespace

SurfaceHit PosedBodies::nearestPlanar(const Vec3& p, BodyMask mask, int hint) const {
  SurfaceHit best;
  best.distance = std::numeric_limits<float>::infinity();
  auto test = [&](int i) {
    const auto bi = static_cast<std::size_t>(i);
    const Vec3 local = toLocal(bi, p);
    int face = 0;
    // A body farther than the best so far cannot win: stop its planes early.
    const float sd = maxPlaneDistance(planes_[bi], local, &face, best.distance);
    if (sd > best.distance) return;
    const SurfaceHit hit = planarHit(bi, p, local, face, sd);
    if (beats(hit, best)) best = hit;
  };
  // The hint (usually last pass's body) gives a tight bound first; every other body is
  // tested only when its bounding sphere could still reach the best (ties included: the
  // lower index wins them), so the answer does not depend on the hint.
  if (hint >= 0 && hint < size() && (mask >> hint & 1u)) test(hint);
  for (int i = 0; i < size(); ++i) {
    if (!(mask >> i & 1u) || i == hint) continue;
    const float gap = sphereGap(static_cast<std::size_t>(i), p);
    if (gap > best.distance || (gap == best.distance && i > best.body)) continue;
    test(i);
  }
  return best;
}

void PosedBodies::nearestPlanarMany(std::span<const Vec3> points, std::span<int> hints,
                                    std::span<SurfaceHit> hits) const {
  nearestMany(points, hints, hits, false);
  for (std::size_t i = 0; i < points.size(); ++i) hints[i] = hits[i].body;
}

void PosedBodies::nearestMany(std::span<const Vec3> points, std::span<const int> hints,
                              std::span<SurfaceHit> hits) const {
  nearestMany(points, hints, hits, true);
}

void PosedBodies::nearestManySettling(std::span<const Vec3> points, std::span<const int> hints,
                                      std::span<const float> settle, std::span<SurfaceHit> hits,
                                      std::span<std::uint8_t> settled) const {
  assert(settle.size() == static_cast<std::size_t>(size()) && settled.size() == points.size());
  std::fill(settled.begin(), settled.end(), std::uint8_t{0});
  nearestMany(points, hints, hits, true, settle.data(), settled.data());
}

void PosedBodies::nearestMany(std::span<const Vec3> points, std::span<const int> hints,
                              std::span<SurfaceHit> hits, bool exact, const float* settle,
                              std::uint8_t* settled) const {
  assert(hints.size() == points.size() && hits.size() == points.size());
  const std::size_t n = points.size();
  if (!bulkQueries.load(std::memory_order_relaxed)) {
    for (std::size_t i = 0; i < n; ++i)
      hits[i] = exact ? nearest(points[i], kAllBodies, hints[i])
                      : nearestPlanar(points[i], kAllBodies, hints[i]);
    return;
  }
  const std::size_t padded = loadPoints(points);
  for (SurfaceHit& h : hits) h = SurfaceHit{-1, -1, std::numeric_limits<float>::infinity()};
  if (n == 0) return;
  listFirstBodies(points, hints, padded);
  testListed(points, padded, exact, hits);
  if (settle != nullptr) settleFirstHits(n, padded, settle, settled);
  listReachablePoints(n, padded);
  testListed(points, padded, exact, hits);
}

std::size_t PosedBodies::loadPoints(std::span<const Vec3> points) const {
  const std::size_t n = points.size();
  const auto bodyCount = static_cast<std::size_t>(size());
  // Points as SoA, padded to eight with copies of the last (never reported).
  const std::size_t padded = (n + 7) / 8 * 8;
  px_.resize(padded);
  py_.resize(padded);
  pz_.resize(padded);
  first_.assign(padded, -1.0f);
  bestDistance_.assign(padded, std::numeric_limits<float>::infinity());
  for (std::size_t i = 0; i < padded; ++i) {
    const Vec3& p = points[std::min(i, n - 1)];
    px_[i] = p.x();
    py_[i] = p.y();
    pz_[i] = p.z();
  }
  // Each body's list of points to test: row b of a (bodies x padded) table (a list never
  // holds more than the n points, and the branch-free appends of listReachablePoints write at
  // most seven entries past its end, still inside the row).
  tests_.resize(bodyCount * padded);
  testCount_.assign(bodyCount, 0);
  return padded;
}

void PosedBodies::listFirstBodies(std::span<const Vec3> points, std::span<const int> hints,
                                  std::size_t padded) const {
  const auto bodyCount = static_cast<std::size_t>(size());
  // Each point's hint (or the body whose sphere is nearest): a tight bound.
  for (std::size_t i = 0; i < points.size(); ++i) {
    int first = hints[i];
    if (first < 0 || first >= size()) {
      float nearest = std::numeric_limits<float>::infinity();
      for (std::size_t b = 0; b < bodyCount; ++b) {
        const float gap = sphereGap(b, points[i]);
        if (gap < nearest) {
          nearest = gap;
          first = static_cast<int>(b);
        }
      }
    }
    // No body to try (none at all, or the point or every pose is not finite): no hit, as the
    // one-point queries answer.
    if (first < 0) continue;
    first_[i] = static_cast<float>(first);
    const auto b = static_cast<std::size_t>(first);
    tests_[b * padded + static_cast<std::size_t>(testCount_[b]++)] = static_cast<int>(i);
  }
}

void PosedBodies::testListed(std::span<const Vec3> points, std::size_t padded, bool exact,
                             std::span<SurfaceHit> hits) const {
  // Tests every point listed for each body, eight per scan, keeping each point's least
  // (distance, body): the planar answer, or the exact one from the plane scan's bound.
  const auto bodyCount = static_cast<std::size_t>(size());
  constexpr std::size_t kChunk = 64;  // points per kernel call (a multiple of eight)
  alignas(32) float stop[kChunk], lx[kChunk], ly[kChunk], lz[kChunk], largest[kChunk];
  alignas(32) std::int32_t face[kChunk];
  for (std::size_t b = 0; b < bodyCount; ++b) {
    const int* list = tests_.data() + b * padded;
    const auto count = static_cast<std::size_t>(testCount_[b]);
    const PlaneTable& table = planes_[b];
    const std::size_t planes = table.nx.size();  // padded to a multiple of eight
    // A point is listed once per body, so the stops of one body's scans do not change while
    // they run.
    for (std::size_t start = 0; start < count; start += kChunk) {
      const std::size_t lanes = std::min(kChunk, count - start);
      DYNAHAND_SIMD_DISPATCH(scanListedLanes, poses_[b].q, poses_[b].p, px_.data(), py_.data(),
                             pz_.data(), bestDistance_.data(), list + start, lanes, table.nx.data(),
                             table.ny.data(), table.nz.data(), table.offset.data(), planes, stop,
                             lx, ly, lz, largest, face);
      for (std::size_t k = 0; k < lanes; ++k) {
        // Farther than the best (outside, the exact distance is at least the plane's).
        const float sd = largest[k];
        if (sd > stop[k]) continue;
        const auto i = static_cast<std::size_t>(list[start + k]);
        const Vec3 local(lx[k], ly[k], lz[k]);
        const SurfaceHit hit =
            exact ? exactHit(b, local, sd, face[k]) : planarHit(b, points[i], local, face[k], sd);
        if (beats(hit, hits[i])) {
          hits[i] = hit;
          bestDistance_[i] = hit.distance;
        }
      }
    }
  }
}

void PosedBodies::settleFirstHits(std::size_t n, std::size_t padded, const float* settle,
                                  std::uint8_t* settled) const {
  // Settling (nearestManySettling): a point stays settled unless some body that could hold
  // it at its first body's distance has a running errFit below that distance. A settled
  // point is tested against no other body (a best of -infinity reaches no sphere).
  const auto bodyCount = static_cast<std::size_t>(size());
  for (std::size_t i = 0; i < n; ++i) settled[i] = first_[i] >= 0.0f ? 1 : 0;
  const unsigned lastLanes = realLastLanes(n, padded);
  for (std::size_t b = 0; b < bodyCount; ++b)
    DYNAHAND_SIMD_DISPATCH(unsettleByBodyLanes, px_.data(), py_.data(), pz_.data(),
                           bestDistance_.data(), first_.data(), padded, lastLanes,
                           static_cast<float>(b), sphereX_[b], sphereY_[b], sphereZ_[b],
                           sphereR_[b], settle[b], settled);
  for (std::size_t i = 0; i < n; ++i)
    if (settled[i]) bestDistance_[i] = -std::numeric_limits<float>::infinity();
}

void PosedBodies::listReachablePoints(std::size_t n, std::size_t padded) const {
  // Every other body whose sphere could still beat or tie a point's best (a tie goes to the
  // lower index, as in the one-point queries; testing a body that cannot win changes
  // nothing). The sphere gap is a lower bound on both the planar and the exact distance.
  // Appended without branches (the reachable lanes are unpredictable): eight indices
  // compressed by a table, written whole, the count advanced by the mask's bits.
  const auto bodyCount = static_cast<std::size_t>(size());
  const unsigned lastLanes = realLastLanes(n, padded);
  for (std::size_t b = 0; b < bodyCount; ++b) {
    DYNAHAND_SIMD_DISPATCH(reachablePointsLanes, px_.data(), py_.data(), pz_.data(),
                           bestDistance_.data(), first_.data(), padded, lastLanes,
                           static_cast<float>(b), sphereX_[b], sphereY_[b], sphereZ_[b],
                           sphereR_[b], tests_.data() + b * padded, &testCount_[b]);
  }
}

SurfaceHit PosedBodies::nearest(const Vec3& p, BodyMask mask, int hint) const {
  // Bounding-sphere lower bounds; the body with the smallest goes first for a tight best
  // distance, then every other body whose bound does not exceed it (index order: ties
  // still go to the lower index, as the answer is the same in any order).
  std::array<float, kMaxBodies> bounds;
  DYNAHAND_SIMD_DISPATCH(sphereBoundsLanes, p, sphereX_.data(), sphereY_.data(), sphereZ_.data(),
                         sphereR_.data(), size(), bounds.data());
  int first = -1;
  for (int i = 0; i < size(); ++i) {
    if (!(mask >> i & 1u)) continue;
    if (first < 0 || bounds[static_cast<std::size_t>(i)] < bounds[static_cast<std::size_t>(first)])
      first = i;
  }
  SurfaceHit best;
  best.distance = std::numeric_limits<float>::infinity();
  auto test = [&](int i) {
    const auto bi = static_cast<std::size_t>(i);
    if (bounds[bi] > best.distance) return;
    const Vec3 local = toLocal(bi, p);
    int planeFace = 0;
    // Outside, the exact distance is at least the largest plane distance. Not above the
    // best, the scan ran over every plane: its maximum is the one query() would find.
    const float planeDist = maxPlaneDistance(planes_[bi], local, &planeFace, best.distance);
    if (planeDist > best.distance) return;
    const SurfaceHit hit = exactHit(bi, local, planeDist, planeFace);
    if (beats(hit, best)) best = hit;
  };
  if (first < 0) return best;
  if (hint < 0 || hint >= size() || !(mask >> hint & 1u)) hint = first;
  test(hint);
  if (hint != first) test(first);
  for (int i = 0; i < size(); ++i) {
    if ((mask >> i & 1u) && i != first && i != hint) test(i);
  }
  return best;
}

}  // namespace dynahand::track
