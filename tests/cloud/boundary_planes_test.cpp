#include "dynahand/boundary_planes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace dynahand {
namespace {

// Deterministic uniform numbers in [0, 1) (a fixed LCG; std::rand differs by platform).
class Lcg {
 public:
  explicit Lcg(std::uint32_t seed) : state_(seed) {}
  float next() {
    state_ = state_ * 1664525u + 1013904223u;
    return static_cast<float>(state_ >> 8) / 16777216.0f;
  }

 private:
  std::uint32_t state_;
};

std::vector<Vec3> randomBlob(std::uint32_t seed, int count) {
  Lcg rng(seed);
  std::vector<Vec3> points;
  for (int i = 0; i < count; ++i) {
    // An elongated, off-centre cloud 0.4 - 0.7 m from the camera.
    points.emplace_back(0.05f + 0.12f * (rng.next() - 0.5f), -0.03f + 0.06f * (rng.next() - 0.5f),
                        0.4f + 0.3f * rng.next());
  }
  return points;
}

TEST(BoundaryPlanes, ContainEveryInputPoint) {
  BoundaryPlaneBuilder builder;
  BoundaryPlaneConfig config;
  config.omitHalfAngle = 0.0f;
  std::vector<BoundaryPlane> planes;
  for (std::uint32_t seed = 1; seed <= 5; ++seed) {
    const std::vector<Vec3> points = randomBlob(seed, 500);
    builder.buildFromPoints(points, config, Vec2::Zero(), planes);
    ASSERT_EQ(planes.size(), 16u);
    for (const BoundaryPlane& plane : planes) {
      EXPECT_NEAR(plane.normal.norm(), 1.0f, 1e-6f);
      float maxDistance = -1.0f;
      for (const Vec3& p : points) maxDistance = std::max(maxDistance, plane.signedDistance(p));
      EXPECT_LE(maxDistance, 1e-6f);   // contains every point
      EXPECT_GT(maxDistance, -1e-6f);  // and touches one: tight
    }
  }
}

TEST(BoundaryPlanes, PlanesPassThroughTheCameraCentreAndFollowTheHull) {
  // A square of points in the image plane: the hull is the square, and the planes of
  // the four axis directions are its sides.
  const std::vector<Vec2> square = {
      {-0.1f, -0.2f}, {0.3f, -0.2f}, {0.3f, 0.2f}, {-0.1f, 0.2f}, {0.1f, 0.0f}};
  BoundaryPlaneBuilder builder;
  BoundaryPlaneConfig config;
  config.planeCount = 4;
  config.omitHalfAngle = 0.0f;
  std::vector<BoundaryPlane> planes;
  builder.build(square, config, Vec2::Zero(), planes);
  ASSERT_EQ(planes.size(), 4u);
  EXPECT_EQ(builder.hull().size(), 4u);  // the interior point is not on the hull
  // Direction +x: supporting line x = 0.3, plane (1, 0, -0.3) normalised.
  EXPECT_LT((planes[0].normal - Vec3(1.0f, 0.0f, -0.3f).normalized()).norm(), 1e-6f);
  // Direction +y: y = 0.2; -x: x = -0.1; -y: y = -0.2.
  EXPECT_LT((planes[1].normal - Vec3(0.0f, 1.0f, -0.2f).normalized()).norm(), 1e-6f);
  EXPECT_LT((planes[2].normal - Vec3(-1.0f, 0.0f, -0.1f).normalized()).norm(), 1e-6f);
  EXPECT_LT((planes[3].normal - Vec3(0.0f, -1.0f, -0.2f).normalized()).norm(), 1e-6f);
  // A point on the x = 0.3 side at any depth lies on the first plane.
  EXPECT_NEAR(planes[0].signedDistance(Vec3(0.3f * 2.0f, 0.1f, 2.0f)), 0.0f, 1e-6f);
}

TEST(BoundaryPlanes, MarginMovesPlanesOutward) {
  const std::vector<Vec2> square = {{-0.1f, -0.1f}, {0.1f, -0.1f}, {0.1f, 0.1f}, {-0.1f, 0.1f}};
  BoundaryPlaneBuilder builder;
  BoundaryPlaneConfig config;
  config.planeCount = 4;
  config.margin = 0.05f;
  std::vector<BoundaryPlane> planes;
  builder.build(square, config, Vec2::Zero(), planes);
  ASSERT_EQ(planes.size(), 4u);
  EXPECT_LT((planes[0].normal - Vec3(1.0f, 0.0f, -0.15f).normalized()).norm(), 1e-6f);
}

TEST(BoundaryPlanes, ArmSideIsOmitted) {
  const std::vector<Vec3> points = randomBlob(7, 300);
  BoundaryPlaneBuilder builder;
  BoundaryPlaneConfig config;
  config.planeCount = 16;
  config.omitHalfAngle = 0.6f;  // 34 deg: directions at 0 and +-22.5 deg from the arm
  std::vector<BoundaryPlane> planes;
  const Vec2 arm(0.0f, 1.0f);  // arm leaves downward
  builder.buildFromPoints(points, config, arm, planes);
  EXPECT_EQ(planes.size(), 13u);
  for (const BoundaryPlane& plane : planes) {
    EXPECT_LT(plane.imageDirection.dot(arm), std::cos(0.6f));
    for (const Vec3& p : points) EXPECT_LE(plane.signedDistance(p), 1e-6f);
  }
}

// A hull cut by the image's top edge: the planes resting on that edge (outward direction with
// an upward component, supported by a vertex on the edge) are left out, so the hand may go on
// out of view; the others stay, and the view's default bounds leave out nothing.
TEST(BoundaryPlanes, PlanesRestingOnTheViewsEdgeAreOmitted) {
  const std::vector<Vec2> cut = {{-0.1f, -0.2f}, {0.1f, -0.2f}, {0.1f, 0.1f}, {-0.1f, 0.1f}};
  BoundaryPlaneBuilder builder;
  BoundaryPlaneConfig config;
  config.planeCount = 8;
  std::vector<BoundaryPlane> planes;
  builder.build(cut, config, Vec2::Zero(), planes);
  EXPECT_EQ(planes.size(), 8u);
  ViewBounds view;
  view.min = Vec2(-0.7f, -0.2f);  // the top edge runs along the hull's top
  view.max = Vec2(0.7f, 0.5f);
  view.margin = 0.01f;
  builder.build(cut, config, Vec2::Zero(), planes, view);
  // Of 8 directions, up and the two diagonals up rest on the top edge.
  ASSERT_EQ(planes.size(), 5u);
  for (const BoundaryPlane& plane : planes) {
    EXPECT_GE(plane.imageDirection.y(), -1e-6f);
    for (const Vec2& q : cut) EXPECT_LE(plane.signedDistance(Vec3(q.x(), q.y(), 1.0f)), 1e-6f);
  }
  // The same hull well inside the view keeps every plane.
  view.min = Vec2(-0.7f, -0.5f);
  builder.build(cut, config, Vec2::Zero(), planes, view);
  EXPECT_EQ(planes.size(), 8u);
}

TEST(BoundaryPlanes, EmptyInputGivesNoPlanes) {
  BoundaryPlaneBuilder builder;
  std::vector<BoundaryPlane> planes(3);
  builder.build({}, BoundaryPlaneConfig{}, Vec2::Zero(), planes);
  EXPECT_TRUE(planes.empty());
  // Points behind the camera cannot be contained by a cone in front of it: skipped.
  const std::vector<Vec3> behind = {Vec3(0.0f, 0.0f, -1.0f)};
  builder.buildFromPoints(behind, BoundaryPlaneConfig{}, Vec2::Zero(), planes);
  EXPECT_TRUE(planes.empty());
}

TEST(BoundaryPlanes, SinglePointGivesAThinCone) {
  BoundaryPlaneBuilder builder;
  BoundaryPlaneConfig config;
  config.omitHalfAngle = 0.0f;
  std::vector<BoundaryPlane> planes;
  const std::vector<Vec3> one = {Vec3(0.1f, 0.05f, 0.5f)};
  builder.buildFromPoints(one, config, Vec2::Zero(), planes);
  ASSERT_EQ(planes.size(), 16u);
  for (const BoundaryPlane& plane : planes) {
    EXPECT_NEAR(plane.signedDistance(one[0]), 0.0f, 1e-6f);
    // Points along the same ray are contained, points beside it are not (for some plane).
    EXPECT_LE(plane.signedDistance(one[0] * 3.0f), 1e-6f);
  }
  const Vec3 beside(0.12f, 0.05f, 0.5f);
  float worst = -1.0f;
  for (const BoundaryPlane& plane : planes) worst = std::max(worst, plane.signedDistance(beside));
  EXPECT_GT(worst, 0.01f);
}

}  // namespace
}  // namespace dynahand
