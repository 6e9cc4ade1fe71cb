// The fingertip free-space pull: a point over empty space is pushed in the image plane onto
// the nearest segmented pixel; points on the hand, hidden behind nearer data or too far off
// get nothing.
#include <gtest/gtest.h>

#include "dynahand/cloud.h"
#include "track/silhouette.h"

namespace dynahand::track {
namespace {

// An 8 cm square "hand" 0.5 m away in front of a wall 0.9 m away: pixels 48..111 in both axes.
struct Scene {
  Intrinsics camera{160, 160, 400.0f, 400.0f, 80.0f, 80.0f};
  CloudFrame cloud;
  Scene() {
    DepthFrame depth(160, 160, 0.001f);
    for (int v = 0; v < 160; ++v)
      for (int u = 0; u < 160; ++u)
        depth.at(u, v) = (u >= 48 && u < 112 && v >= 48 && v < 112) ? 500 : 900;
    CloudPipeline pipeline(camera, CloudConfig{});
    EXPECT_TRUE(pipeline.process(depth, cloud).ok());
  }
  Vec3 at(float u, float v, float z) const { return camera.deproject(u, v, z); }
  // The rightmost segmented pixel of row v (the segmentation trims an edge pixel or two).
  int rightEdge(int v) const {
    int edge = -1;
    for (int u = 0; u < 160; ++u)
      if (cloud.mask[static_cast<std::size_t>(v * 160 + u)] != 0) edge = u;
    return edge;
  }
};

TEST(SilhouettePull, PullsAPointOverTheWallOntoTheNearestHandPixel) {
  const Scene s;
  ASSERT_GT(s.cloud.segment.pixelCount, 1000) << "the square is segmented";
  const int edge = s.rightEdge(80);
  ASSERT_GE(edge, 108);
  // 15 pixels right of the square's edge, at the square's depth: the wall behind is farther.
  const auto pull =
      silhouettePull(s.cloud, s.at(static_cast<float>(edge + 15), 80.0f, 0.5f), 1, 40);
  ASSERT_TRUE(pull.has_value());
  const Vec2 target = s.camera.project(pull->target);
  EXPECT_NEAR(target.x(), static_cast<float>(edge), 1e-3f) << "the square's right column";
  EXPECT_NEAR(target.y(), 80.0f, 1.0f);
  EXPECT_FLOAT_EQ(pull->target.z(), 0.5f) << "in the plane of the point's depth";
  EXPECT_NEAR(pull->inward.x(), -1.0f, 1e-3f);
  EXPECT_NEAR(pull->inward.norm(), 1.0f, 1e-5f);
}

TEST(SilhouettePull, NothingOnTheHandHiddenOrTooFarOff) {
  const Scene s;
  EXPECT_FALSE(silhouettePull(s.cloud, s.at(80.0f, 80.0f, 0.5f), 1, 40)) << "on the square";
  EXPECT_FALSE(
      silhouettePull(s.cloud, s.at(static_cast<float>(s.rightEdge(80) + 2), 80.0f, 0.5f), 2, 40))
      << "within the tolerance of its edge";
  EXPECT_FALSE(silhouettePull(s.cloud, s.at(130.0f, 80.0f, 0.95f), 1, 40))
      << "behind the wall: the wall may hide it";
  EXPECT_FALSE(
      silhouettePull(s.cloud, s.at(static_cast<float>(s.rightEdge(80) + 45), 80.0f, 0.5f), 1, 40))
      << "45 pixels off: beyond the search radius";
  EXPECT_FALSE(silhouettePull(s.cloud, Vec3(0.0f, 0.0f, -0.1f), 1, 40)) << "behind the camera";
}

}  // namespace
}  // namespace dynahand::track
