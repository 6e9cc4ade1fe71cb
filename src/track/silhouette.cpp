#include "track/silhouette.h"

#include <algorithm>
#include <cmath>

namespace dynahand::track {

namespace {
constexpr float kHiddenToleranceM = 0.01f;  // data this much nearer than the point may hide it
}  // namespace

std::optional<SilhouettePull> silhouettePull(const CloudFrame& cloud, const Vec3& point,
                                             int tolerancePixels, int maxPixels) {
  if (cloud.mask.empty() || !cloud.isFree(point, kHiddenToleranceM)) return std::nullopt;
  const int width = cloud.intrinsics.width, height = cloud.intrinsics.height;
  const Vec2 uv = cloud.intrinsics.project(point);
  const int u0 = static_cast<int>(std::lround(uv.x())), v0 = static_cast<int>(std::lround(uv.y()));
  // The mask may hold every filterStride-th pixel only: a tip between two samples is on it.
  const int onHand = tolerancePixels + std::max(0, cloud.filterStride - 1);
  // Nearest mask pixel by growing square rings; stop once a ring cannot hold anything
  // nearer than the best found.
  int bestD2 = maxPixels * maxPixels + 1, bestU = 0, bestV = 0;
  for (int r = 0; r <= maxPixels && r * r < bestD2; ++r) {
    for (int dv = -r; dv <= r; ++dv) {
      const int v = v0 + dv;
      if (v < 0 || v >= height) continue;
      const int step = (dv == -r || dv == r) ? 1 : 2 * r;  // ring only
      for (int du = -r; du <= r; du += std::max(step, 1)) {
        const int u = u0 + du;
        if (u < 0 || u >= width) continue;
        if (cloud.mask[static_cast<std::size_t>(v) * static_cast<std::size_t>(width) +
                       static_cast<std::size_t>(u)] == 0)
          continue;
        const int d2 = du * du + dv * dv;
        if (d2 < bestD2) {
          bestD2 = d2;
          bestU = u;
          bestV = v;
        }
      }
    }
  }
  if (bestD2 > maxPixels * maxPixels) return std::nullopt;
  if (bestD2 <= onHand * onHand) return std::nullopt;
  const Vec3 target =
      cloud.intrinsics.deproject(static_cast<float>(bestU), static_cast<float>(bestV), point.z());
  const Vec3 offset = target - point;
  const float length = offset.norm();
  if (!(length > 1e-6f)) return std::nullopt;
  return SilhouettePull{target, offset / length};
}

}  // namespace dynahand::track
