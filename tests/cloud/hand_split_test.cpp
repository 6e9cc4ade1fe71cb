#include "dynahand/hand_split.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

namespace dynahand {
namespace {

// A deterministic blob of `count` points within +-half of centre on each axis (+-half x
// `tall` along y: a hand and forearm hanging into the view).
void addBlob(std::vector<Vec3>& points, const Vec3& centre, float half, int count,
             float tall = 1.0f) {
  std::uint32_t state = 12345u + static_cast<std::uint32_t>(points.size());
  const auto next = [&state] {
    state = state * 1664525u + 1013904223u;
    return static_cast<float>(state >> 8) / 16777216.0f * 2.0f - 1.0f;
  };
  for (int i = 0; i < count; ++i) {
    const float x = next();
    const float y = next();
    const float z = next();
    points.push_back(centre + Vec3(x, tall * y, z) * half);
  }
}

TEST(HandSplit, SeparatesTwoBlobsAndLabelsLeftByCameraPlacement) {
  std::vector<Vec3> points;
  addBlob(points, Vec3(-0.15f, 0.0f, 0.5f), 0.04f, 200);  // image left
  addBlob(points, Vec3(0.15f, 0.0f, 0.5f), 0.04f, 150);   // image right
  HandSplit split;

  HandSplitter facing;  // default: camera faces the user, their left hand at larger x
  facing.split(points, split);
  ASSERT_EQ(split.handCount, 2);
  EXPECT_EQ(split[Hand::kLeft].pointCount, 150);
  EXPECT_EQ(split[Hand::kRight].pointCount, 200);
  EXPECT_NEAR(split[Hand::kLeft].centroid.x(), 0.15f, 0.01f);
  EXPECT_NEAR(split[Hand::kRight].centroid.x(), -0.15f, 0.01f);
  for (std::size_t i = 0; i < points.size(); ++i) {
    EXPECT_EQ(split.label[i], i < 200 ? Hand::kRight : Hand::kLeft) << "point " << i;
  }

  HandSplitConfig behindConfig;
  behindConfig.placement = CameraPlacement::kBehindUser;
  HandSplitter behind(behindConfig);
  behind.split(points, split);
  ASSERT_EQ(split.handCount, 2);
  EXPECT_EQ(split[Hand::kLeft].pointCount, 200);
  EXPECT_NEAR(split[Hand::kLeft].centroid.x(), -0.15f, 0.01f);
}

TEST(HandSplit, MergesBlobsThatAreTooCloseIntoTheRightHand) {
  std::vector<Vec3> points;
  addBlob(points, Vec3(-0.03f, 0.0f, 0.5f), 0.03f, 200);
  addBlob(points, Vec3(0.03f, 0.0f, 0.5f), 0.03f, 200);
  HandSplitter splitter;
  HandSplit split;
  splitter.split(points, split);
  ASSERT_EQ(split.handCount, 1);
  EXPECT_FALSE(split[Hand::kLeft].present);
  EXPECT_TRUE(split[Hand::kRight].present);
  EXPECT_EQ(split[Hand::kRight].pointCount, 400);
  EXPECT_NEAR(split[Hand::kRight].centroid.x(), 0.0f, 0.01f);
  for (Hand h : split.label) EXPECT_EQ(h, Hand::kRight);
}

// One hand with its forearm, hanging into the view: k-means cuts it across the wrist into two
// clusters 0.14 m apart, each elongated along the line between them. One hand.
TEST(HandSplit, AHandAndItsForearmCutApartAreOneHand) {
  std::vector<Vec3> points;
  addBlob(points, Vec3(0.0f, -0.07f, 0.5f), 0.03f, 200, 2.0f);  // hand
  addBlob(points, Vec3(0.0f, 0.07f, 0.5f), 0.025f, 200, 2.5f);  // forearm
  HandSplitter splitter;
  HandSplit split;
  splitter.split(points, split);
  EXPECT_EQ(split.handCount, 1);
}

// Two hands side by side, touching, each elongated along its arm: their centroids are 0.11 m
// apart, nearer than a hand's from its forearm's above. Two hands.
TEST(HandSplit, TwoHandsSideBySideAreTwoHands) {
  std::vector<Vec3> points;
  addBlob(points, Vec3(-0.055f, 0.0f, 0.5f), 0.035f, 200, 3.0f);
  addBlob(points, Vec3(0.055f, 0.0f, 0.5f), 0.035f, 200, 3.0f);
  HandSplitter splitter;
  HandSplit split;
  splitter.split(points, split);
  ASSERT_EQ(split.handCount, 2);
  EXPECT_EQ(split[Hand::kLeft].pointCount, 200);
  EXPECT_EQ(split[Hand::kRight].pointCount, 200);
}

TEST(HandSplit, TinySecondClusterIsMerged) {
  std::vector<Vec3> points;
  addBlob(points, Vec3(0.0f, 0.0f, 0.5f), 0.04f, 300);
  addBlob(points, Vec3(0.3f, 0.0f, 0.5f), 0.005f, 5);  // a speck, far away
  HandSplitter splitter;
  HandSplit split;
  splitter.split(points, split);
  EXPECT_EQ(split.handCount, 1);
  EXPECT_EQ(split[Hand::kRight].pointCount, 305);
}

TEST(HandSplit, EmptyCloudHasNoHands) {
  HandSplitter splitter;
  HandSplit split;
  splitter.split({}, split);
  EXPECT_EQ(split.handCount, 0);
  EXPECT_FALSE(split[Hand::kLeft].present);
  EXPECT_FALSE(split[Hand::kRight].present);
  EXPECT_TRUE(split.label.empty());
}

TEST(HandSplit, IdentityIsKeptWhenHandsCross) {
  // Hand A starts on the image left (the user's right hand when facing the camera) at
  // 0.5 m; hand B on the image right, 0.7 m away, each with its arm along the image's
  // vertical. They swap sides over 16 frames, passing at different depths, so they never
  // merge.
  HandSplitter splitter;
  HandSplit split;
  for (int frame = 0; frame <= 16; ++frame) {
    const float t = static_cast<float>(frame) / 16.0f;
    const float ax = -0.15f + 0.3f * t;
    std::vector<Vec3> points;
    addBlob(points, Vec3(ax, 0.0f, 0.5f), 0.03f, 120, 3.0f);   // A: points [0, 120)
    addBlob(points, Vec3(-ax, 0.0f, 0.7f), 0.03f, 120, 3.0f);  // B: points [120, 240)
    splitter.split(points, split);
    ASSERT_EQ(split.handCount, 2) << "frame " << frame;
    EXPECT_EQ(split.label[0], Hand::kRight) << "frame " << frame;
    EXPECT_EQ(split.label[200], Hand::kLeft) << "frame " << frame;
    EXPECT_NEAR(split[Hand::kRight].centroid.x(), ax, 0.01f) << "frame " << frame;
  }
  // After a reset, labels follow the sides again: A is now on the image right.
  splitter.reset();
  std::vector<Vec3> points;
  addBlob(points, Vec3(0.15f, 0.0f, 0.5f), 0.03f, 120, 3.0f);
  addBlob(points, Vec3(-0.15f, 0.0f, 0.7f), 0.03f, 120, 3.0f);
  splitter.split(points, split);
  EXPECT_EQ(split.label[0], Hand::kLeft);
}

}  // namespace
}  // namespace dynahand
