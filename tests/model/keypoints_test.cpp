// 21 MediaPipe keypoints and 26 OpenXR joints: order and anatomical facts.
#include <gtest/gtest.h>

#include <random>
#include <string>

#include "dynahand/model.h"
#include "dynahand/model_pose.h"
#include "model/model_test_util.h"

namespace dynahand::model {
namespace {

const ArticulatedModel& hand() {
  static const ArticulatedModel model = makeDefaultHand();
  return model;
}

TEST(Keypoints21, NamesAreMediaPipeOrder) {
  const auto& names = keypoint21Names();
  EXPECT_STREQ(names[0], "wrist");
  EXPECT_STREQ(names[4], "thumb_tip");
  EXPECT_STREQ(names[5], "index_mcp");
  EXPECT_STREQ(names[8], "index_tip");
  EXPECT_STREQ(names[12], "middle_tip");
  EXPECT_STREQ(names[17], "pinky_mcp");
  EXPECT_STREQ(names[20], "pinky_tip");
}

TEST(Keypoints21, FingertipIsTheFarthestKeypointOfItsFingerAtRest) {
  const auto kp = keypoints21(hand(), forwardKinematics(hand(), zeroAngles(hand())));
  for (size_t finger = 0; finger < 5; ++finger) {
    const size_t first = 1 + 4 * finger;
    float previous = 0.0f;
    for (size_t k = first; k < first + 4; ++k) {
      const float d = (kp[k] - kp[0]).norm();
      EXPECT_GT(d, previous) << keypoint21Names()[k];  // monotone along the chain, tip last
      previous = d;
    }
  }
  // The middle fingertip is the farthest of all; the pinky the shortest finger.
  for (size_t k = 1; k < 21; ++k) {
    if (k != 12) {
      EXPECT_LT((kp[k] - kp[0]).norm(), (kp[12] - kp[0]).norm()) << keypoint21Names()[k];
    }
  }
  EXPECT_LT((kp[20] - kp[17]).norm(), (kp[8] - kp[5]).norm());
}

TEST(Keypoints21, RightHandLayoutAcrossThePalm) {
  const auto kp = keypoints21(hand(), forwardKinematics(hand(), zeroAngles(hand())));
  // Body frame of the flat right hand: +x toward the thumb. Knuckles run index -> pinky
  // toward -x; the thumb is the most radial digit.
  EXPECT_GT(kp[5].x(), kp[9].x());
  EXPECT_GT(kp[9].x(), kp[13].x());
  EXPECT_GT(kp[13].x(), kp[17].x());
  EXPECT_GT(kp[4].x(), kp[8].x());
  // Flexing the index MCP moves its tip toward the palm side (-y).
  JointAngles bent = zeroAngles(hand());
  bent.angles[4].x() = 1.2f;
  const auto kb = keypoints21(hand(), forwardKinematics(hand(), bent));
  EXPECT_LT(kb[8].y(), kp[8].y() - 0.03f);
  EXPECT_EQ(kb[12], kp[12]);  // other fingers unaffected
}

TEST(Keypoints21, FollowTheRootPose) {
  std::mt19937 rng(1);
  const JointAngles angles = fixtures::randomValidAngles(hand(), rng);
  JointAngles atOrigin = angles;
  atOrigin.root = Pose::identity();
  const auto moved = keypoints21(hand(), forwardKinematics(hand(), angles));
  const auto local = keypoints21(hand(), forwardKinematics(hand(), atOrigin));
  for (size_t k = 0; k < 21; ++k)
    EXPECT_LT((moved[k] - angles.root.transform(local[k])).norm(), 1e-5f);
}

TEST(OpenXr26, OrderPositionsAndAxes) {
  std::mt19937 rng(2);
  const ModelPose pose = forwardKinematics(hand(), fixtures::randomValidAngles(hand(), rng));
  const auto xr = openxr26(hand(), pose);
  const auto kp = keypoints21(hand(), pose);
  const auto& names = openXrJointNames();
  EXPECT_STREQ(names[0], "palm");
  EXPECT_STREQ(names[1], "wrist");
  EXPECT_STREQ(names[25], "little_tip");
  // Joints shared with MediaPipe sit at the same places.
  EXPECT_LT((xr[1].pose.p - kp[0]).norm(), 1e-6f);                                         // wrist
  for (size_t t = 0; t < 4; ++t) EXPECT_LT((xr[2 + t].pose.p - kp[1 + t]).norm(), 1e-6f);  // thumb
  for (size_t f = 0; f < 4; ++f) {
    for (size_t k = 0; k < 4; ++k) {
      EXPECT_LT((xr[7 + 5 * f + k].pose.p - kp[5 + 4 * f + k]).norm(), 1e-6f)
          << names[7 + 5 * f + k];
    }
  }
  // +z is parallel to the joint's bone (the one starting at the joint) and points away from
  // the tip: at each intermediate and distal joint it points from the next joint back.
  for (size_t f = 0; f < 4; ++f) {
    for (size_t k = 7; k <= 9; ++k) {
      const XrJoint& joint = xr[k + 5 * f];
      const Vec3 awayFromTip = (joint.pose.p - xr[k + 1 + 5 * f].pose.p).normalized();
      EXPECT_GT((joint.pose.q * Vec3::UnitZ()).dot(awayFromTip), 0.9999f) << names[k + 5 * f];
    }
    // Metacarpal joints are closer to the wrist than the proximal ones.
    EXPECT_LT((xr[6 + 5 * f].pose.p - kp[0]).norm(), (xr[7 + 5 * f].pose.p - kp[0]).norm());
  }
  for (const XrJoint& j : xr) {
    EXPECT_GT(j.radius, 0.003f);
    EXPECT_LT(j.radius, 0.03f);
    EXPECT_NEAR(j.pose.q.norm(), 1.0f, 1e-5f);
  }
  EXPECT_LT(xr[10].radius, xr[7].radius);  // fingertip thinner than the knuckle
}

TEST(OpenXr26, YPointsOutOfTheBackOfTheFlatHand) {
  for (const Side side : {Side::Right, Side::Left}) {
    const ArticulatedModel model = makeDefaultHand({}, side);
    const ModelPose rest = forwardKinematics(model, zeroAngles(model));
    const auto xr = openxr26(model, rest);
    // The flat hand's back faces +y (body frames: +y dorsal), for both hands.
    for (size_t i = 6; i < 26; ++i)
      EXPECT_GT((xr[i].pose.q * Vec3::UnitY()).y(), 0.95f) << openXrJointNames()[i];
    // x = y cross z: right-handed frames.
    for (const XrJoint& j : xr) {
      const Mat3 r = j.pose.q.toRotationMatrix();
      EXPECT_NEAR(r.determinant(), 1.0f, 1e-5f);
    }
  }
}

TEST(Keypoints21, NonHandModelHasNoHandLayout) {
  ModelSpec spec;
  spec.bodies.push_back({"box",
                         {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)},
                         std::nullopt,
                         std::nullopt});
  const Result<ArticulatedModel> model = buildModel(spec);
  ASSERT_TRUE(model.ok()) << model.message();
  EXPECT_FALSE(model->hasKeypoints21());
  EXPECT_FALSE(model->hasOpenXrJoints());
}

}  // namespace
}  // namespace dynahand::model
