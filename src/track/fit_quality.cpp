#include "track/fit_quality.h"

#include <algorithm>
#include <cmath>

namespace dynahand::track {

namespace {

constexpr int kTipTolerancePixels = 3;

// Whether pixel (u, v) or a neighbour within the working stride is segmented (the mask
// holds the samples the segmentation visited, which may be every stride-th pixel).
bool onMask(const CloudFrame& cloud, float uf, float vf, int extra = 0) {
  const int width = cloud.intrinsics.width, height = cloud.intrinsics.height;
  const int u = static_cast<int>(std::lround(uf)), v = static_cast<int>(std::lround(vf));
  const int r = std::max(0, cloud.filterStride - 1) + extra;
  for (int dv = -r; dv <= r; ++dv) {
    for (int du = -r; du <= r; ++du) {
      const int x = u + du, y = v + dv;
      if (x < 0 || y < 0 || x >= width || y >= height) continue;
      if (cloud.mask[static_cast<std::size_t>(y) * static_cast<std::size_t>(width) +
                     static_cast<std::size_t>(x)] != 0)
        return true;
    }
  }
  return false;
}

}  // namespace

FitQuality measureFitQuality(const PosedBodies& bodies, std::span<const float> pointDistances,
                             std::span<const Vec3> points, const WristPlane* wrist,
                             const CloudFrame& cloud, int skipBody, std::span<const Vec3> tips) {
  FitQuality q;
  const bool cut = wrist != nullptr && points.size() == pointDistances.size();
  int counted = 0, near = 0;
  for (std::size_t i = 0; i < pointDistances.size(); ++i) {
    if (cut && (points[i] - wrist->wrist).dot(wrist->towardElbow) > 0.0f) continue;
    ++counted;
    near += pointDistances[i] <= kNearSurfaceM ? 1 : 0;
  }
  if (counted > 0) q.dataNearModel = static_cast<float>(near) / static_cast<float>(counted);
  // Camera-facing faces, by area, whose centre projects onto a segmented pixel.
  double facing = 0.0, onHand = 0.0;
  for (int b = 0; b < bodies.size(); ++b) {
    if (b == skipBody) continue;
    const auto& shape = bodies.shape(b);
    const Pose& pose = bodies.pose(b);
    for (const auto& face : shape.faces()) {
      Vec3 centre = Vec3::Zero();
      Vec3 areaVector = Vec3::Zero();
      const auto& v = shape.vertices();
      const std::size_t count = face.vertices.size();
      for (std::size_t i = 0; i < count; ++i) {
        const Vec3& a = v[static_cast<std::size_t>(face.vertices[i])];
        const Vec3& c = v[static_cast<std::size_t>(face.vertices[(i + 1) % count])];
        centre += a;
        areaVector += a.cross(c);
      }
      centre /= static_cast<float>(count);
      const Vec3 world = pose.transform(centre);
      const float facingCosine = -pose.rotate(face.normal).dot(world.normalized());
      if (facingCosine <= 0.0f || world.z() <= 0.0f) continue;
      const double area = 0.5 * static_cast<double>(areaVector.norm() * facingCosine);
      facing += area;
      const Vec2 uv = cloud.intrinsics.project(world);
      if (onMask(cloud, uv.x(), uv.y())) onHand += area;
    }
  }
  q.modelOnHand = facing > 0.0 ? static_cast<float>(onHand / facing) : 0.0f;
  for (const Vec3& tip : tips) {
    if (tip.z() <= 0.0f) {
      ++q.fingertipsOffHand;
      continue;
    }
    // The tip keypoint is the very end of the finger, where the segmentation's edge (flying
    // pixels removed) stops a pixel or two short: a small tolerance.
    const Vec2 uv = cloud.intrinsics.project(tip);
    if (!onMask(cloud, uv.x(), uv.y(), kTipTolerancePixels)) ++q.fingertipsOffHand;
  }
  return q;
}

}  // namespace dynahand::track
