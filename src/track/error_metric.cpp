#include "track/error_metric.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <limits>

namespace dynahand::track {

bool inFreeSpace(const Vec3& point, const DepthFrame& depth, const Intrinsics& intrinsics) {
  if (!(point.z() > 0.0f)) return false;
  const Vec2 uv = intrinsics.project(point);
  const int u = static_cast<int>(std::lround(uv.x()));
  const int v = static_cast<int>(std::lround(uv.y()));
  if (u < 0 || v < 0 || u >= depth.width || v >= depth.height) return false;
  const std::uint16_t raw = depth.at(u, v);
  return raw == 0 || depth.metres(u, v) >= point.z();
}

namespace {

// The paper's sums, in body order (the same additions whether or not every point was seen).
void sumTotals(ErrorBreakdown& out) {
  out.fitTotal = 0.0f;
  out.occlusionTotal = 0.0f;
  for (std::size_t i = 0; i < out.fit.size(); ++i) {
    out.fitTotal += out.fit[i];
    out.occlusionTotal += out.occlusion[i];
  }
  out.total = out.fitTotal + out.occlusionTotal;
}

}  // namespace

bool computeErrorBounded(const PosedBodies& bodies, std::span<const Vec3> points,
                         const FreeSpaceTest& isFree, float abortAbove, ErrorBreakdown& out,
                         std::span<const int> nearestHints, std::span<const int> order,
                         float settleBelowM) {
  const auto n = static_cast<std::size_t>(bodies.size());
  out.fit.assign(n, 0.0f);
  out.occlusion.assign(n, 0.0f);
  out.pointCount.assign(n, 0);
  out.pointDistance.assign(points.size(), std::numeric_limits<float>::infinity());
  // Occlusion first: it is cheap and raises the bound from the start.
  for (std::size_t i = 0; i < n; ++i) {
    const int body = static_cast<int>(i);
    if (isFree(bodies.worldCentroid(body))) out.occlusion[i] = bodies.shape(body).inscribedRadius();
  }
  const bool hinted = nearestHints.size() == points.size();
  const bool ordered = order.size() == points.size();
  // The points in chunks of kCheckEvery, each chunk queried in bulk (body by body), the bound
  // checked after each: the same answers and the same give-up points as one at a time.
  constexpr std::size_t kCheckEvery = 64;
  std::array<Vec3, kCheckEvery> chunk;
  std::array<int, kCheckEvery> chunkHints, chunkIndex;
  std::array<SurfaceHit, kCheckEvery> hits;
  // Settling (PosedBodies::nearestManySettling): a point within min(errFit_j so far,
  // settleBelowM) of its first body, for every body j that could hold it, cannot raise any
  // errFit: its other bodies are not tested.
  const bool settling = settleBelowM > 0.0f;
  std::array<float, 32> settle{};
  std::array<std::uint8_t, kCheckEvery> settled{};
  assert(n <= settle.size());
  for (std::size_t j0 = 0; j0 < points.size(); j0 += kCheckEvery) {
    const std::size_t count = std::min(kCheckEvery, points.size() - j0);
    for (std::size_t c = 0; c < count; ++c) {
      const std::size_t k = ordered ? static_cast<std::size_t>(order[j0 + c]) : j0 + c;
      chunkIndex[c] = static_cast<int>(k);
      chunk[c] = points[k];
      chunkHints[c] = hinted ? nearestHints[k] : -1;
    }
    if (settling) {
      for (std::size_t i = 0; i < n; ++i) settle[i] = std::min(out.fit[i], settleBelowM);
      bodies.nearestManySettling(std::span(chunk.data(), count),
                                 std::span(chunkHints.data(), count), std::span(settle.data(), n),
                                 std::span(hits.data(), count), std::span(settled.data(), count));
    } else {
      bodies.nearestMany(std::span(chunk.data(), count), std::span(chunkHints.data(), count),
                         std::span(hits.data(), count));
    }
    for (std::size_t c = 0; c < count; ++c) {
      const SurfaceHit& hit = hits[c];
      if (hit.body < 0) continue;
      const auto k = static_cast<std::size_t>(chunkIndex[c]);
      out.pointDistance[k] = hit.distance;
      if (settling && settled[c]) continue;  // its body is unknown; it raises no errFit
      const auto i = static_cast<std::size_t>(hit.body);
      out.fit[i] = std::max(out.fit[i], hit.distance);
      ++out.pointCount[i];
    }
    if (count == kCheckEvery) {
      // Rounding is monotonic: these sums of smaller terms never exceed the final ones.
      sumTotals(out);
      if (out.total > abortAbove) return false;
    }
  }
  sumTotals(out);
  return out.total <= abortAbove;
}

void computeError(const PosedBodies& bodies, std::span<const Vec3> points,
                  const FreeSpaceTest& isFree, ErrorBreakdown& out,
                  std::span<const int> nearestHints) {
  computeErrorBounded(bodies, points, isFree, std::numeric_limits<float>::infinity(), out,
                      nearestHints);
}

}  // namespace dynahand::track
