// The default hand: hulls, overlaps, limits, scaling, mirroring, dimensions.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "dynahand/model.h"
#include "dynahand/model_pose.h"
#include "model/model_test_util.h"

namespace dynahand::model {
namespace {

constexpr float kDeg = std::numbers::pi_v<float> / 180.0f;

const ArticulatedModel& rightHand() {
  static const ArticulatedModel hand = makeDefaultHand();
  return hand;
}

TEST(DefaultHand, SeventeenBodiesInTheIntelOrder) {
  const ArticulatedModel& hand = rightHand();
  const char* names[17] = {
      "forearm",        "palm",          "thumb_metacarpal", "thumb_proximal",  "thumb_distal",
      "index_proximal", "index_middle",  "index_distal",     "middle_proximal", "middle_middle",
      "middle_distal",  "ring_proximal", "ring_middle",      "ring_distal",     "pinky_proximal",
      "pinky_middle",   "pinky_distal"};
  ASSERT_EQ(hand.bodyCount(), 17);
  ASSERT_EQ(hand.jointCount(), 16);
  for (int b = 0; b < 17; ++b) EXPECT_EQ(hand.bodies()[static_cast<size_t>(b)].name, names[b]);
  for (int j = 0; j < 16; ++j) EXPECT_EQ(hand.joints()[static_cast<size_t>(j)].child, j + 1);
  EXPECT_EQ(hand.root(), 0);
  EXPECT_EQ(hand.metadata().handedness, Handedness::Right);
  EXPECT_TRUE(hand.hasKeypoints21());
  EXPECT_TRUE(hand.hasOpenXrJoints());
}

TEST(DefaultHand, EveryBodyIsAValidHullWithPlausibleMass) {
  float total = 0.0f;
  for (const Body& body : rightHand().bodies()) {
    EXPECT_GE(body.shape.vertices().size(), 4u) << body.name;
    EXPECT_GT(body.shape.volume(), 1e-6f) << body.name;            // > 1 cm^3
    EXPECT_GT(body.shape.inscribedRadius(), 0.004f) << body.name;  // no sliver
    EXPECT_NEAR(body.mass, kDefaultDensity * body.shape.volume(), 1e-6f) << body.name;
    total += body.mass;
  }
  // Hand plus the modelled piece of forearm: a few hundred grams.
  EXPECT_GT(total, 0.3f);
  EXPECT_LT(total, 0.8f);
}

TEST(DefaultHand, AdjacentBonesOverlapAroundEveryJoint) {
  const ArticulatedModel& hand = rightHand();
  for (const Joint& joint : hand.joints()) {
    const Body& parent = hand.bodies()[static_cast<size_t>(joint.parent)];
    const Body& child = hand.bodies()[static_cast<size_t>(joint.child)];
    // The joint centre lies at least 4 mm deep inside both bodies, so a ball of 4 mm around
    // it is shared by both at every angle: no gap can open.
    EXPECT_LT(parent.shape.signedDistance(joint.anchorParent), -0.004f)
        << parent.name << " / " << child.name;
    EXPECT_LT(child.shape.signedDistance(joint.anchorChild), -0.004f)
        << parent.name << " / " << child.name;
    EXPECT_FALSE(hand.collides(joint.parent, joint.child));
  }
  std::mt19937 rng(7);
  for (int trial = 0; trial < 50; ++trial) {
    const ModelPose pose = forwardKinematics(hand, fixtures::randomValidAngles(hand, rng));
    for (const Joint& joint : hand.joints()) {
      EXPECT_TRUE(fixtures::overlaps(hand.bodies()[static_cast<size_t>(joint.parent)].shape,
                                     pose.bodies[static_cast<size_t>(joint.parent)],
                                     hand.bodies()[static_cast<size_t>(joint.child)].shape,
                                     pose.bodies[static_cast<size_t>(joint.child)], 0.001f));
    }
  }
}

TEST(DefaultHand, NoCollidingPairInterpenetratesAtRest) {
  const ArticulatedModel& hand = rightHand();
  const ModelPose rest = forwardKinematics(hand, zeroAngles(hand));
  for (int a = 0; a < hand.bodyCount(); ++a) {
    for (int b = a + 1; b < hand.bodyCount(); ++b) {
      if (!hand.collides(a, b)) continue;
      EXPECT_FALSE(fixtures::overlaps(
          hand.bodies()[static_cast<size_t>(a)].shape, rest.bodies[static_cast<size_t>(a)],
          hand.bodies()[static_cast<size_t>(b)].shape, rest.bodies[static_cast<size_t>(b)], 0.0f))
          << hand.bodies()[static_cast<size_t>(a)].name << " / "
          << hand.bodies()[static_cast<size_t>(b)].name;
    }
  }
}

TEST(DefaultHand, DimensionsMatchTheParameters) {
  const HandDimensions dims{0.18f, 0.08f};
  const ArticulatedModel hand = makeDefaultHand(dims);
  const auto kp = keypoints21(hand, forwardKinematics(hand, zeroAngles(hand)));
  // Hand length: wrist crease to middle fingertip along the hand (body z of the flat hand).
  EXPECT_NEAR(kp[12].z() - kp[0].z(), 0.18f, 1e-5f);
  // Palm width: the outer knuckles' surfaces (index MCP to pinky MCP plus their radii).
  const float width =
      (kp[5] - kp[17]).norm() +
      hand.keypoints()[static_cast<size_t>(hand.keypointIndex("index_mcp"))].radius +
      hand.keypoints()[static_cast<size_t>(hand.keypointIndex("pinky_mcp"))].radius;
  EXPECT_NEAR(width, 0.08f, 0.005f);
  EXPECT_FLOAT_EQ(hand.metadata().referenceLength, 0.18f);
}

TEST(DefaultHand, LimitsAreRealistic) {
  const ArticulatedModel& hand = rightHand();
  for (int f = 0; f < 4; ++f) {
    const Joint& mcp = hand.joints()[static_cast<size_t>(4 + 3 * f)];
    const Joint& pip = hand.joints()[static_cast<size_t>(5 + 3 * f)];
    EXPECT_GE(mcp.maxAngle.x(), 85 * kDeg);                     // MCP flexion ~90 degrees
    EXPECT_LT(mcp.minAngle.x(), 0.0f);                          // some hyperextension
    EXPECT_GT(mcp.maxAngle.y() - mcp.minAngle.y(), 20 * kDeg);  // abduction / adduction
    EXPECT_GE(pip.maxAngle.x(), 100 * kDeg);
    EXPECT_EQ(pip.minAngle.y(), pip.maxAngle.y());  // hinge: no abduction, no twist
    EXPECT_EQ(pip.minAngle.z(), pip.maxAngle.z());
  }
  // Thumb CMC: flexion, abduction and axial rotation (opposition).
  const Joint& cmc = hand.joints()[1];
  for (int axis = 0; axis < 3; ++axis)
    EXPECT_GT(cmc.maxAngle[axis] - cmc.minAngle[axis], 40 * kDeg);
}

TEST(DefaultHand, ThumbOpposesEachFingertip) {
  // Opposition: within the limits the thumb tip can touch every fingertip (closest approach
  // of the two tip surfaces over random thumb and finger angles).
  const ArticulatedModel& hand = rightHand();
  std::mt19937 rng(3);
  std::array<float, 4> closest;
  closest.fill(1.0f);
  std::vector<Vec3> kps;
  for (int trial = 0; trial < 6000; ++trial) {
    JointAngles angles = fixtures::randomValidAngles(hand, rng);
    angles.angles[0] = Vec3::Zero();
    const auto kp = keypoints21(hand, forwardKinematics(hand, angles));
    for (int f = 0; f < 4; ++f)
      closest[static_cast<size_t>(f)] = std::min(
          closest[static_cast<size_t>(f)], (kp[4] - kp[static_cast<size_t>(8 + 4 * f)]).norm());
  }
  for (int f = 0; f < 4; ++f) EXPECT_LT(closest[static_cast<size_t>(f)], 0.02f) << "finger " << f;
}

TEST(DefaultHand, RandomAnglesStayWithinLimitsThroughPoses) {
  const ArticulatedModel& hand = rightHand();
  std::mt19937 rng(11);
  std::normal_distribution<float> wild(0.0f, 1.5f);
  for (int trial = 0; trial < 300; ++trial) {
    JointAngles angles = zeroAngles(hand);
    for (Vec3& a : angles.angles) a = Vec3(wild(rng), wild(rng), wild(rng));
    clampToLimits(hand, angles);
    ASSERT_TRUE(withinLimits(hand, angles, 0.0f));
    const JointAngles recovered = jointAngles(hand, forwardKinematics(hand, angles));
    EXPECT_TRUE(withinLimits(hand, recovered, 1e-4f));
  }
}

TEST(DefaultHand, ScalingBySScalesAllLengthsByS) {
  const ArticulatedModel& hand = rightHand();
  const float s = 1.25f;
  const ArticulatedModel big = scaleModel(hand, s);
  for (size_t b = 0; b < hand.bodies().size(); ++b) {
    const Body& a = hand.bodies()[b];
    const Body& c = big.bodies()[b];
    ASSERT_EQ(a.vertices.size(), c.vertices.size());
    for (size_t v = 0; v < a.vertices.size(); ++v)
      EXPECT_LT((c.vertices[v] - s * a.vertices[v]).norm(), 1e-6f);
    EXPECT_NEAR(c.shape.volume(), s * s * s * a.shape.volume(), 1e-4f * c.shape.volume());
    EXPECT_NEAR(c.mass, s * s * s * a.mass, 1e-4f * c.mass);
  }
  for (size_t j = 0; j < hand.joints().size(); ++j) {
    EXPECT_LT((big.joints()[j].anchorParent - s * hand.joints()[j].anchorParent).norm(), 1e-6f);
    EXPECT_EQ(big.joints()[j].minAngle, hand.joints()[j].minAngle);  // angles are not lengths
  }
  std::mt19937 rng(5);
  const JointAngles angles = fixtures::randomValidAngles(hand, rng);
  const auto k1 = keypoints21(hand, forwardKinematics(hand, angles));
  const auto k2 = keypoints21(big, forwardKinematics(big, angles));
  for (size_t i = 0; i < 21; ++i) {
    EXPECT_LT(((k2[i] - angles.root.p) - s * (k1[i] - angles.root.p)).norm(), 1e-5f);
  }
  // The generator is proportional: a hand made s times larger is the scaled hand.
  const ArticulatedModel made = makeDefaultHand({0.19f * s, 0.085f * s});
  const auto k3 = keypoints21(made, forwardKinematics(made, angles));
  for (size_t i = 0; i < 21; ++i) EXPECT_LT((k3[i] - k2[i]).norm(), 1e-5f);
}

TEST(DefaultHand, LeftHandIsTheMirrorImage) {
  const ArticulatedModel& right = rightHand();
  const ArticulatedModel left = makeDefaultHand({}, Side::Left);
  EXPECT_EQ(left.metadata().handedness, Handedness::Left);
  std::mt19937 rng(9);
  for (int trial = 0; trial < 20; ++trial) {
    const JointAngles angles = fixtures::randomValidAngles(right, rng);
    const JointAngles mirrored = mirrorAngles(angles);
    EXPECT_TRUE(withinLimits(left, mirrored, 1e-6f));
    const auto kr = keypoints21(right, forwardKinematics(right, angles));
    const auto kl = keypoints21(left, forwardKinematics(left, mirrored));
    for (size_t i = 0; i < 21; ++i)
      EXPECT_LT((kl[i] - Vec3(-kr[i].x(), kr[i].y(), kr[i].z())).norm(), 1e-5f);
  }
  // At rest the right thumb is on +x, the left thumb on -x.
  const auto rest = keypoints21(left, forwardKinematics(left, zeroAngles(left)));
  EXPECT_LT(rest[4].x(), -0.05f);
}

}  // namespace
}  // namespace dynahand::model
