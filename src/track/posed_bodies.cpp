#include "track/posed_bodies.h"

#include "core/cpu_features.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <limits>

#include "core/simd/lanes.h"

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#define DYNAHAND_PLANE_SCAN_AVX 1
#endif

namespace dynahand::track {

namespace {

// The largest of the eight lanes' maxima; ties go to the lower face index.
float reduceLanes(const float best[8], const std::int32_t index[8], int* face) {
  float result = best[0];
  int which = index[0];
  for (int k = 1; k < 8; ++k) {
    if (best[k] > result || (best[k] == result && index[k] < which)) {
      result = best[k];
      which = index[k];
    }
  }
  *face = which;
  return result;
}

#define DYNAHAND_SIMD_KERNELS "track/plane_scan.inl"
#include "core/simd/for_each_level.inl"

#if defined(DYNAHAND_PLANE_SCAN_AVX)
// ((nx qx + ny qy) + nz qz) - o lane by lane: a plane distance in the scalar paths' order.
__attribute__((target("avx"), always_inline)) inline __m256 planeDistance8(__m256 nx, __m256 ny,
                                                                           __m256 nz, __m256 o,
                                                                           __m256 qx, __m256 qy,
                                                                           __m256 qz) {
  return _mm256_sub_ps(_mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(nx, qx), _mm256_mul_ps(ny, qy)),
                                     _mm256_mul_ps(nz, qz)),
                       o);
}

// Plane f of a table (SoA) for the eight lanes.
__attribute__((target("avx"), always_inline)) inline __m256 planeDistance8(
    const float* nx, const float* ny, const float* nz, const float* o, std::size_t f, __m256 qx,
    __m256 qy, __m256 qz) {
  return planeDistance8(_mm256_broadcast_ss(nx + f), _mm256_broadcast_ss(ny + f),
                        _mm256_broadcast_ss(nz + f), _mm256_broadcast_ss(o + f), qx, qy, qz);
}

// |p - c| - r lane by lane (sphereGap's arithmetic: x^2 + (y^2 + z^2), Eigen's order for a
// 3-vector's squared norm, so the scalar paths give the same bits).
__attribute__((target("avx"), always_inline)) inline __m256 sphereGap8(__m256 px, __m256 py,
                                                                       __m256 pz, __m256 cx,
                                                                       __m256 cy, __m256 cz,
                                                                       __m256 r) {
  const __m256 dx = _mm256_sub_ps(px, cx), dy = _mm256_sub_ps(py, cy), dz = _mm256_sub_ps(pz, cz);
  const __m256 d2 = _mm256_add_ps(_mm256_mul_ps(dx, dx),
                                  _mm256_add_ps(_mm256_mul_ps(dy, dy), _mm256_mul_ps(dz, dz)));
  return _mm256_sub_ps(_mm256_sqrt_ps(d2), r);
}

// Each lane's largest distance so far and the index of the first plane holding it.
__attribute__((target("avx"), always_inline)) inline void keepLargest(__m256 d, __m256 at,
                                                                      __m256& best, __m256& index) {
  const __m256 better = _mm256_cmp_ps(d, best, _CMP_GT_OQ);
  best = _mm256_max_ps(d, best);  // == better ? d : best (no NaNs here)
  // A bitwise select: GCC turns blendv with a compare mask into per-lane branches.
  index = _mm256_or_ps(_mm256_and_ps(better, at), _mm256_andnot_ps(better, index));
}
#endif

#if defined(DYNAHAND_PLANE_SCAN_AVX)
// Bounding-sphere lower bounds max(0, |p - c_i| - r_i) for `blocks` blocks of eight bodies
// (SoA, padded with far spheres); returns the smallest over the first `count` bodies and
// writes the lowest index holding it to *first (-1 when count is 0).
__attribute__((target("avx"))) float sphereBoundsAvx(const Vec3& p, const float* cx,
                                                     const float* cy, const float* cz,
                                                     const float* r, int count, float* bounds,
                                                     int* first) {
  const __m256 px = _mm256_set1_ps(p.x()), py = _mm256_set1_ps(p.y()), pz = _mm256_set1_ps(p.z());
  const __m256 zero = _mm256_setzero_ps();
  __m256 smallest = _mm256_set1_ps(std::numeric_limits<float>::infinity());
  const int blocks = (count + 7) / 8;
  for (int b = 0; b < blocks; ++b) {
    const int o = 8 * b;
    const __m256 bound =
        _mm256_max_ps(sphereGap8(px, py, pz, _mm256_loadu_ps(cx + o), _mm256_loadu_ps(cy + o),
                                 _mm256_loadu_ps(cz + o), _mm256_loadu_ps(r + o)),
                      zero);
    _mm256_storeu_ps(bounds + o, bound);
    smallest = _mm256_min_ps(smallest, bound);
  }
  smallest = _mm256_min_ps(smallest, _mm256_permute2f128_ps(smallest, smallest, 1));
  smallest = _mm256_min_ps(smallest, _mm256_permute_ps(smallest, 0x4E));
  smallest = _mm256_min_ps(smallest, _mm256_permute_ps(smallest, 0xB1));
  const float m = _mm256_cvtss_f32(smallest);
  *first = -1;
  for (int i = 0; i < count; ++i) {
    if (bounds[i] == m) {
      *first = i;
      break;
    }
  }
  return m;
}

// Plane numbers as floats, for the AVX-512 scan's index: shapes of up to kMaskedScanPlanes
// planes (the hand's have at most 136 with padding) take that scan.
constexpr std::size_t kMaskedScanPlanes = 512;
struct PlaneNumbers {
  float value[kMaskedScanPlanes]{};
  constexpr PlaneNumbers() {
    for (std::size_t f = 0; f < kMaskedScanPlanes; ++f) value[f] = static_cast<float>(f);
  }
};
constexpr PlaneNumbers kPlaneNumber;

// toLocal, eight points at once (one per lane), operation for operation: the same bits.
__attribute__((target("avx"), always_inline)) inline void toLocal8(const Quat& rotation,
                                                                   const Vec3& t, __m256 px,
                                                                   __m256 py, __m256 pz, __m256& qx,
                                                                   __m256& qy, __m256& qz) {
  const __m256 w = _mm256_set1_ps(rotation.w());
  const __m256 ux = _mm256_set1_ps(-rotation.x()), uy = _mm256_set1_ps(-rotation.y()),
               uz = _mm256_set1_ps(-rotation.z());
  const __m256 dx = _mm256_sub_ps(px, _mm256_set1_ps(t.x()));
  const __m256 dy = _mm256_sub_ps(py, _mm256_set1_ps(t.y()));
  const __m256 dz = _mm256_sub_ps(pz, _mm256_set1_ps(t.z()));
  __m256 cx = _mm256_sub_ps(_mm256_mul_ps(uy, dz), _mm256_mul_ps(uz, dy));
  __m256 cy = _mm256_sub_ps(_mm256_mul_ps(uz, dx), _mm256_mul_ps(ux, dz));
  __m256 cz = _mm256_sub_ps(_mm256_mul_ps(ux, dy), _mm256_mul_ps(uy, dx));
  cx = _mm256_add_ps(cx, cx);
  cy = _mm256_add_ps(cy, cy);
  cz = _mm256_add_ps(cz, cz);
  qx = _mm256_add_ps(_mm256_add_ps(dx, _mm256_mul_ps(w, cx)),
                     _mm256_sub_ps(_mm256_mul_ps(uy, cz), _mm256_mul_ps(uz, cy)));
  qy = _mm256_add_ps(_mm256_add_ps(dy, _mm256_mul_ps(w, cy)),
                     _mm256_sub_ps(_mm256_mul_ps(uz, cx), _mm256_mul_ps(ux, cz)));
  qz = _mm256_add_ps(_mm256_add_ps(dz, _mm256_mul_ps(w, cz)),
                     _mm256_sub_ps(_mm256_mul_ps(ux, cy), _mm256_mul_ps(uy, cx)));
}

// toLocal8 of the eight points (wx, wy, wz), also stored to (lx, ly, lz).
__attribute__((target("avx"), always_inline)) inline void localPoints8(
    const Quat& rotation, const Vec3& t, const float* wx, const float* wy, const float* wz,
    float* lx, float* ly, float* lz, __m256& qx, __m256& qy, __m256& qz) {
  toLocal8(rotation, t, _mm256_load_ps(wx), _mm256_load_ps(wy), _mm256_load_ps(wz), qx, qy, qz);
  _mm256_store_ps(lx, qx);
  _mm256_store_ps(ly, qy);
  _mm256_store_ps(lz, qz);
}

// Eight points at once (one per lane), for one body: the points in the body frame (toLocal's
// arithmetic), each one's largest plane distance and its face, lowest index on ties
// (maxPlaneDistance's answer: the first plane holding a lane's maximum). Stops early once
// every lane has seen a plane farther than its `stop`; such a lane then only has a distance
// above its stop, not the largest.
__attribute__((target("avx"))) void scanEightAvx(const Quat& rotation, const Vec3& t,
                                                 const float* wx, const float* wy, const float* wz,
                                                 const float* nx, const float* ny, const float* nz,
                                                 const float* o, std::size_t count,
                                                 const float* stop, float* lx, float* ly, float* lz,
                                                 float* largest, std::int32_t* face) {
  __m256 qx, qy, qz;
  localPoints8(rotation, t, wx, wy, wz, lx, ly, lz, qx, qy, qz);
  __m256 best = _mm256_set1_ps(-1e30f);
  __m256 index = _mm256_setzero_ps();
  __m256 plane = _mm256_setzero_ps();
  const __m256 one = _mm256_set1_ps(1.0f);
  const __m256 stopAbove = _mm256_load_ps(stop);
  // Eight planes per trip, unrolled (count is a multiple of eight: the tables' padding
  // planes never hold a maximum), the give-up test after each eight as before.
  for (std::size_t group = 0; group < count; group += 8) {
#pragma GCC unroll 8
    for (std::size_t f = group; f < group + 8; ++f) {
      const __m256 d = planeDistance8(nx, ny, nz, o, f, qx, qy, qz);
      keepLargest(d, plane, best, index);
      plane = _mm256_add_ps(plane, one);
    }
    // Once every lane has a plane beyond its stop (its largest so far is), none of them can
    // win: give up (the caller sees a distance above the stop, as with maxPlaneDistance's
    // early return).
    if (_mm256_movemask_ps(_mm256_cmp_ps(best, stopAbove, _CMP_GT_OQ)) == 0xFF) break;
  }
  // The lane's maximum is its face's distance by the scalar formula's arithmetic (same
  // operations in the same order), so callers need not recompute it.
  _mm256_store_ps(largest, best);
  alignas(32) float indexOut[8];
  _mm256_store_ps(indexOut, index);
  for (int k = 0; k < 8; ++k) face[k] = static_cast<std::int32_t>(indexOut[k]);
}

// scanEightAvx with AVX-512's mask registers on the same eight lanes (where the CPU has
// AVX-512VL): the compare writes a mask and one masked blend keeps the index (three fewer
// vector operations per plane, the scan's bottleneck), and the plane numbers come from a
// table. Same operations on the distances in the same order: the same bits.
__attribute__((target("avx512f,avx512vl"))) void scanEightAvx512(
    const Quat& rotation, const Vec3& t, const float* wx, const float* wy, const float* wz,
    const float* nx, const float* ny, const float* nz, const float* o, std::size_t count,
    const float* stop, float* lx, float* ly, float* lz, float* largest, std::int32_t* face) {
  __m256 qx, qy, qz;
  localPoints8(rotation, t, wx, wy, wz, lx, ly, lz, qx, qy, qz);
  __m256 best = _mm256_set1_ps(-1e30f);
  __m256 index = _mm256_setzero_ps();
  const __m256 stopAbove = _mm256_load_ps(stop);
  for (std::size_t group = 0; group < count; group += 8) {
#pragma GCC unroll 8
    for (std::size_t f = group; f < group + 8; ++f) {
      const __m256 d = planeDistance8(nx, ny, nz, o, f, qx, qy, qz);
      const __mmask8 better = _mm256_cmp_ps_mask(d, best, _CMP_GT_OQ);
      best = _mm256_max_ps(d, best);
      index = _mm256_mask_blend_ps(better, index, _mm256_broadcast_ss(kPlaneNumber.value + f));
    }
    if (_mm256_cmp_ps_mask(best, stopAbove, _CMP_GT_OQ) == 0xFF) break;
  }
  _mm256_store_ps(largest, best);
  _mm256_storeu_si256(reinterpret_cast<__m256i*>(face), _mm256_cvttps_epi32(index));
}

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

// The points (of `padded`, the last eight holding `lastLanes` real ones) that body b (centre c,
// radius r) could still beat or tie, i.e. not sphereGap > best (sphereGap's arithmetic), and
// that were not tested against it first (`first`, as floats): their indices, in order, into
// `list` (which has room for seven more past the count); returns the count.
__attribute__((target("avx"))) int reachablePointsAvx(const float* px, const float* py,
                                                      const float* pz, const float* best,
                                                      const float* first, std::size_t padded,
                                                      int lastLanes, float b, float cx, float cy,
                                                      float cz, float r, int* list) {
  const __m256 vcx = _mm256_set1_ps(cx), vcy = _mm256_set1_ps(cy), vcz = _mm256_set1_ps(cz);
  const __m256 vr = _mm256_set1_ps(r), vb = _mm256_set1_ps(b);
  int count = 0;
  for (std::size_t start = 0; start < padded; start += 8) {
    const __m256 gap = sphereGap8(_mm256_loadu_ps(px + start), _mm256_loadu_ps(py + start),
                                  _mm256_loadu_ps(pz + start), vcx, vcy, vcz, vr);
    const __m256 reachable = _mm256_cmp_ps(gap, _mm256_loadu_ps(best + start), _CMP_LE_OQ);
    const __m256 other = _mm256_cmp_ps(_mm256_loadu_ps(first + start), vb, _CMP_NEQ_UQ);
    int mask = _mm256_movemask_ps(_mm256_and_ps(reachable, other));
    if (start + 8 == padded) mask &= lastLanes;
    const __m128i base = _mm_set1_epi32(static_cast<int>(start));
    const auto* lanes = reinterpret_cast<const __m128i*>(kCompress.lanes[mask]);
    _mm_storeu_si128(reinterpret_cast<__m128i*>(list + count),
                     _mm_add_epi32(base, _mm_load_si128(lanes)));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(list + count + 4),
                     _mm_add_epi32(base, _mm_load_si128(lanes + 1)));
    count += __builtin_popcount(static_cast<unsigned>(mask));
  }
  return count;
}

// The error metric's settling (nearestManySettling): clears settled[i] for every point i
// that body b could still hold at its best distance (its sphere bound does not exceed it,
// or b is its first body) while that distance is above settle (b's running errFit).
__attribute__((target("avx"))) void unsettleByBody(const float* px, const float* py,
                                                   const float* pz, const float* best,
                                                   const float* first, std::size_t padded, float b,
                                                   float cx, float cy, float cz, float r,
                                                   float settle, std::uint8_t* settled) {
  const __m256 vcx = _mm256_set1_ps(cx), vcy = _mm256_set1_ps(cy), vcz = _mm256_set1_ps(cz);
  const __m256 vr = _mm256_set1_ps(r), vb = _mm256_set1_ps(b), vs = _mm256_set1_ps(settle);
  for (std::size_t start = 0; start < padded; start += 8) {
    const __m256 d = _mm256_loadu_ps(best + start);
    const __m256 gap = sphereGap8(_mm256_loadu_ps(px + start), _mm256_loadu_ps(py + start),
                                  _mm256_loadu_ps(pz + start), vcx, vcy, vcz, vr);
    const __m256 holds =
        _mm256_or_ps(_mm256_cmp_ps(gap, d, _CMP_LE_OQ),
                     _mm256_cmp_ps(_mm256_loadu_ps(first + start), vb, _CMP_EQ_OQ));
    const int mask = _mm256_movemask_ps(_mm256_and_ps(holds, _mm256_cmp_ps(vs, d, _CMP_LT_OQ)));
    if (mask == 0) continue;
    for (int k = 0; k < 8; ++k)
      if (mask >> k & 1) settled[start + static_cast<std::size_t>(k)] = 0;
  }
}

std::atomic<bool> wideScan{cpuHasAvx()};
std::atomic<bool> maskScan{cpuHasAvx512vl()};  // the bulk scan's AVX-512 variant
#endif

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

#if defined(DYNAHAND_PLANE_SCAN_AVX)
bool PosedBodies::useMaskedPlaneScan(bool enabled) {
  maskScan.store(enabled && cpuHasAvx512vl());
  return maskScan.load();
}
bool PosedBodies::useWidePlaneScan(bool enabled) {
  wideScan.store(enabled && cpuHasAvx());
  return wideScan.load();
}
#else
bool PosedBodies::useMaskedPlaneScan(bool) {
  return false;
}
bool PosedBodies::useWidePlaneScan(bool) {
  return false;
}
#endif

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
  return reduceLanes(best, index, face);
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
#if defined(DYNAHAND_PLANE_SCAN_AVX)
  if (wideScan.load(std::memory_order_relaxed)) {
    nearestMany(points, hints, hits, true, settle.data(), settled.data());
    return;
  }
#endif
  nearestMany(points, hints, hits, true);
}

void PosedBodies::nearestMany(std::span<const Vec3> points, std::span<const int> hints,
                              std::span<SurfaceHit> hits, bool exact, const float* settle,
                              std::uint8_t* settled) const {
  assert(hints.size() == points.size() && hits.size() == points.size());
  const std::size_t n = points.size();
#if defined(DYNAHAND_PLANE_SCAN_AVX)
  const bool wide = wideScan.load(std::memory_order_relaxed);
#else
  const bool wide = false;
#endif
  if (!wide) {
    for (std::size_t i = 0; i < n; ++i)
      hits[i] = exact ? nearest(points[i], kAllBodies, hints[i])
                      : nearestPlanar(points[i], kAllBodies, hints[i]);
    return;
  }
#if defined(DYNAHAND_PLANE_SCAN_AVX)
  const std::size_t padded = loadPoints(points);
  for (SurfaceHit& h : hits) h = SurfaceHit{-1, -1, std::numeric_limits<float>::infinity()};
  if (n == 0) return;
  listFirstBodies(points, hints, padded);
  testListed(points, padded, exact, hits);
  if (settle != nullptr) settleFirstHits(n, padded, settle, settled);
  listReachablePoints(n, padded);
  testListed(points, padded, exact, hits);
#else
  (void)settle;
  (void)settled;
#endif
}

#if defined(DYNAHAND_PLANE_SCAN_AVX)
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
  const bool masked = maskScan.load(std::memory_order_relaxed);
  alignas(32) float wx[8], wy[8], wz[8], lx[8], ly[8], lz[8], stop[8], largest[8];
  alignas(32) std::int32_t face[8];
  for (std::size_t b = 0; b < bodyCount; ++b) {
    const int* list = tests_.data() + b * padded;
    const auto count = static_cast<std::size_t>(testCount_[b]);
    const PlaneTable& table = planes_[b];
    const std::size_t planes = table.nx.size();  // padded to a multiple of eight
    for (std::size_t start = 0; start < count; start += 8) {
      const std::size_t lanes = std::min<std::size_t>(8, count - start);
      for (std::size_t k = 0; k < 8; ++k) {
        const auto i = static_cast<std::size_t>(list[start + std::min(k, lanes - 1)]);
        wx[k] = px_[i];
        wy[k] = py_[i];
        wz[k] = pz_[i];
        stop[k] = bestDistance_[i];
      }
      if (masked && planes <= kMaskedScanPlanes)
        scanEightAvx512(poses_[b].q, poses_[b].p, wx, wy, wz, table.nx.data(), table.ny.data(),
                        table.nz.data(), table.offset.data(), planes, stop, lx, ly, lz, largest,
                        face);
      else
        scanEightAvx(poses_[b].q, poses_[b].p, wx, wy, wz, table.nx.data(), table.ny.data(),
                     table.nz.data(), table.offset.data(), planes, stop, lx, ly, lz, largest, face);
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
  for (std::size_t b = 0; b < bodyCount; ++b)
    unsettleByBody(px_.data(), py_.data(), pz_.data(), bestDistance_.data(), first_.data(), padded,
                   static_cast<float>(b), sphereX_[b], sphereY_[b], sphereZ_[b], sphereR_[b],
                   settle[b], settled);
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
  const int lastLanes = (1 << (n - (padded - 8))) - 1;  // the real points of the last eight
  for (std::size_t b = 0; b < bodyCount; ++b) {
    testCount_[b] =
        reachablePointsAvx(px_.data(), py_.data(), pz_.data(), bestDistance_.data(), first_.data(),
                           padded, lastLanes, static_cast<float>(b), sphereX_[b], sphereY_[b],
                           sphereZ_[b], sphereR_[b], tests_.data() + b * padded);
  }
}
#endif

SurfaceHit PosedBodies::nearest(const Vec3& p, BodyMask mask, int hint) const {
  // Bounding-sphere lower bounds; the body with the smallest goes first for a tight best
  // distance, then every other body whose bound does not exceed it (index order: ties
  // still go to the lower index, as the answer is the same in any order).
  std::array<float, kMaxBodies> bounds;
  int first = -1;
#if defined(DYNAHAND_PLANE_SCAN_AVX)
  if (mask == kAllBodies && wideScan.load(std::memory_order_relaxed)) {
    sphereBoundsAvx(p, sphereX_.data(), sphereY_.data(), sphereZ_.data(), sphereR_.data(), size(),
                    bounds.data(), &first);
  } else
#endif
    for (int i = 0; i < size(); ++i) {
      if (!(mask >> i & 1u)) continue;
      const auto bi = static_cast<std::size_t>(i);
      bounds[bi] = std::max(0.0f, sphereGap(bi, p));
      if (first < 0 || bounds[bi] < bounds[static_cast<std::size_t>(first)]) first = i;
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
