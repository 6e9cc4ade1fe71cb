#include "dynahand/boundary_planes.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <numbers>

namespace dynahand {
namespace {

float cross(const Vec2& o, const Vec2& a, const Vec2& b) {
  return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
}

// Andrew's monotone chain over lexicographically sorted points; collinear points dropped.
void convexHull(std::span<const Vec2> sorted, std::vector<Vec2>& hull) {
  hull.clear();
  const std::size_t n = sorted.size();
  if (n < 3) {
    hull.assign(sorted.begin(), sorted.end());
    return;
  }
  hull.resize(2 * n);
  std::size_t k = 0;
  for (std::size_t i = 0; i < n; ++i) {  // lower chain
    while (k >= 2 && cross(hull[k - 2], hull[k - 1], sorted[i]) <= 0.0f) --k;
    hull[k++] = sorted[i];
  }
  for (std::size_t i = n - 1, lower = k + 1; i-- > 0;) {  // upper chain
    while (k >= lower && cross(hull[k - 2], hull[k - 1], sorted[i]) <= 0.0f) --k;
    hull[k++] = sorted[i];
  }
  hull.resize(k - 1);  // the last point repeats the first
}

}  // namespace

bool BoundaryPlaneBuilder::restsOnViewEdge(const Vec2& d, float support,
                                           const ViewBounds& view) const {
  // The vertices the supporting line touches (within the margin): on an edge that d faces
  // (beyond rounding: a direction along the edge is the hull's side, seen whole), the hull is
  // cut by the image there.
  constexpr float kFacing = 1e-3f;
  for (const Vec2& h : hull_) {
    if (d.dot(h) < support - view.margin) continue;
    if ((d.x() < -kFacing && h.x() <= view.min.x() + view.margin) ||
        (d.x() > kFacing && h.x() >= view.max.x() - view.margin) ||
        (d.y() < -kFacing && h.y() <= view.min.y() + view.margin) ||
        (d.y() > kFacing && h.y() >= view.max.y() - view.margin))
      return true;
  }
  return false;
}

void BoundaryPlaneBuilder::build(std::span<const Vec2> normalisedPoints,
                                 const BoundaryPlaneConfig& config, const Vec2& armDirection,
                                 std::vector<BoundaryPlane>& out, const ViewBounds& view) {
  assert(config.planeCount >= 3 && "a cone needs at least three planes");
  out.clear();
  hull_.clear();
  if (normalisedPoints.empty()) return;
  sorted_.assign(normalisedPoints.begin(), normalisedPoints.end());
  // Ties are identical points, so the unstable sort cannot change the result.
  std::sort(sorted_.begin(), sorted_.end(), [](const Vec2& a, const Vec2& b) {
    return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
  });
  convexHull(sorted_, hull_);

  const float armNorm = armDirection.norm();
  const bool omitArmSide = config.omitHalfAngle > 0.0f && armNorm > 0.0f;
  const Vec2 arm = omitArmSide ? Vec2(armDirection / armNorm) : Vec2::Zero();
  const float omitCos = std::cos(config.omitHalfAngle);
  for (int i = 0; i < config.planeCount; ++i) {
    const float angle = 2.0f * std::numbers::pi_v<float> * static_cast<float>(i) /
                        static_cast<float>(config.planeCount);
    const Vec2 d(std::cos(angle), std::sin(angle));
    if (omitArmSide && d.dot(arm) >= omitCos) continue;
    float support = -std::numeric_limits<float>::infinity();
    for (const Vec2& h : hull_) support = std::max(support, d.dot(h));
    if (restsOnViewEdge(d, support, view)) continue;
    support += config.margin;
    BoundaryPlane plane;
    plane.imageDirection = d;
    plane.normal = Vec3(d.x(), d.y(), -support).normalized();
    out.push_back(plane);
  }
}

void BoundaryPlaneBuilder::buildFromPoints(std::span<const Vec3> points,
                                           const BoundaryPlaneConfig& config,
                                           const Vec2& armDirection,
                                           std::vector<BoundaryPlane>& out) {
  projected_.clear();
  for (const Vec3& p : points) {
    if (p.z() > 0.0f) projected_.emplace_back(p.x() / p.z(), p.y() / p.z());
  }
  build(projected_, config, armDirection, out);
}

}  // namespace dynahand
