// Forward kinematics, angle recovery, interpolation and pose sequences.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <numbers>
#include <random>

#include "dynahand/model.h"
#include "dynahand/model_pose.h"
#include "model/model_test_util.h"
#include "test_support.h"

namespace dynahand::model {
namespace {

const ArticulatedModel& hand() {
  static const ArticulatedModel model = makeDefaultHand();
  return model;
}

float angleBetween(const Quat& a, const Quat& b) {
  return a.angularDistance(b);
}

TEST(Kinematics, JointRotationIsSwingTwistInModelAxes) {
  constexpr float kHalfPi = std::numbers::pi_v<float> / 2;
  // Pure flexion: about +x; the bone (+z) turns toward -y (the palm side).
  EXPECT_LT(
      angleBetween(jointRotation(Vec3(0.7f, 0, 0)), Quat(Eigen::AngleAxisf(0.7f, Vec3::UnitX()))),
      1e-6f);
  EXPECT_LT((jointRotation(Vec3(kHalfPi, 0, 0)) * Vec3::UnitZ() - Vec3(0, -1, 0)).norm(), 1e-6f);
  // Pure abduction: about +y; the bone turns toward +x (the thumb side of a right hand).
  EXPECT_LT(
      angleBetween(jointRotation(Vec3(0, 0.4f, 0)), Quat(Eigen::AngleAxisf(0.4f, Vec3::UnitY()))),
      1e-6f);
  // Pure twist: about +z.
  EXPECT_LT(
      angleBetween(jointRotation(Vec3(0, 0, 0.9f)), Quat(Eigen::AngleAxisf(0.9f, Vec3::UnitZ()))),
      1e-6f);
  // Combined: the bone direction is (sin a, -cos a sin f, cos a cos f) whatever the twist,
  // and the twist is a rotation about the bone after the shortest swing.
  const float f = 1.2f, a = -0.35f, t = 0.5f;
  const Quat r = jointRotation(Vec3(f, a, t));
  const Vec3 d(std::sin(a), -std::cos(a) * std::sin(f), std::cos(a) * std::cos(f));
  EXPECT_LT((r * Vec3::UnitZ() - d).norm(), 1e-6f);
  const Quat swing = shortestRotation(Vec3::UnitZ(), d);
  EXPECT_LT(angleBetween(r, swing * Quat(Eigen::AngleAxisf(t, Vec3::UnitZ()))), 1e-6f);
  EXPECT_LT((jointRotationAngles(r) - Vec3(f, a, t)).norm(), 1e-5f);
}

TEST(Kinematics, AnglesPoseAnglesRoundTripWithin1e5) {
  std::mt19937 rng(1);
  float worst = 0.0f;
  for (int trial = 0; trial < 500; ++trial) {
    const JointAngles angles = fixtures::randomValidAngles(hand(), rng);
    const JointAngles back = jointAngles(hand(), forwardKinematics(hand(), angles));
    for (size_t j = 0; j < angles.angles.size(); ++j) {
      worst = std::max(worst, (back.angles[j] - angles.angles[j]).cwiseAbs().maxCoeff());
    }
    EXPECT_LT((back.root.p - angles.root.p).norm(), 1e-7f);
    EXPECT_LT(angleBetween(back.root.q, angles.root.q), 1e-6f);
  }
  EXPECT_LT(worst, 1e-5f);
}

TEST(Kinematics, PoseAnglesPoseRoundTrip) {
  std::mt19937 rng(2);
  const ModelPose pose = forwardKinematics(hand(), fixtures::randomValidAngles(hand(), rng));
  const ModelPose again = forwardKinematics(hand(), jointAngles(hand(), pose));
  for (size_t b = 0; b < pose.bodies.size(); ++b) {
    EXPECT_LT((again.bodies[b].p - pose.bodies[b].p).norm(), 1e-6f);
    EXPECT_LT(angleBetween(again.bodies[b].q, pose.bodies[b].q), 1e-5f);
  }
}

TEST(Kinematics, JointsStayAttached) {
  std::mt19937 rng(3);
  const ModelPose pose = forwardKinematics(hand(), fixtures::randomValidAngles(hand(), rng));
  for (const Joint& j : hand().joints()) {
    const Vec3 a = pose.bodies[static_cast<size_t>(j.parent)].transform(j.anchorParent);
    const Vec3 b = pose.bodies[static_cast<size_t>(j.child)].transform(j.anchorChild);
    EXPECT_LT((a - b).norm(), 1e-6f);
  }
}

TEST(Kinematics, ForwardKinematicsIntoReusesTheBuffer) {
  std::mt19937 rng(4);
  ModelPose pose;
  forwardKinematicsInto(hand(), fixtures::randomValidAngles(hand(), rng), pose);
  const Pose* data = pose.bodies.data();
  JointAngles angles = fixtures::randomValidAngles(hand(), rng);
  JointAngles recovered;
  jointAnglesInto(hand(), pose, recovered);
  const Vec3* angleData = recovered.angles.data();
  forwardKinematicsInto(hand(), angles, pose);
  jointAnglesInto(hand(), pose, recovered);
  EXPECT_EQ(pose.bodies.data(), data);
  EXPECT_EQ(recovered.angles.data(), angleData);
}

TEST(Kinematics, InterpolationKeepsJointsAttachedAndHitsEndpoints) {
  std::mt19937 rng(5);
  const JointAngles a = fixtures::randomValidAngles(hand(), rng);
  const JointAngles b = fixtures::randomValidAngles(hand(), rng);
  const ModelPose pa = forwardKinematics(hand(), a);
  const ModelPose pb = forwardKinematics(hand(), b);
  const ModelPose start = interpolate(hand(), pa, pb, 0.0f);
  const ModelPose end = interpolate(hand(), pa, pb, 1.0f);
  for (size_t i = 0; i < pa.bodies.size(); ++i) {
    EXPECT_LT((start.bodies[i].p - pa.bodies[i].p).norm(), 1e-5f);
    EXPECT_LT((end.bodies[i].p - pb.bodies[i].p).norm(), 1e-5f);
  }
  const JointAngles mid = interpolate(a, b, 0.5f);
  for (size_t j = 0; j < a.angles.size(); ++j) {
    EXPECT_LT((mid.angles[j] - 0.5f * (a.angles[j] + b.angles[j])).norm(), 1e-6f);
  }
  EXPECT_TRUE(withinLimits(hand(), mid));  // the limits are boxes: convex
  const ModelPose half = interpolate(hand(), pa, pb, 0.5f);
  for (const Joint& j : hand().joints()) {
    EXPECT_LT((half.bodies[static_cast<size_t>(j.parent)].transform(j.anchorParent) -
               half.bodies[static_cast<size_t>(j.child)].transform(j.anchorChild))
                  .norm(),
              1e-6f);
  }
}

TEST(PoseSequence, SaveLoadRoundTripIsExact) {
  std::mt19937 rng(6);
  PoseSequence seq;
  for (const Body& b : hand().bodies()) seq.bodyNames.push_back(b.name);
  for (int f = 0; f < 5; ++f)
    seq.frames.push_back(forwardKinematics(hand(), fixtures::randomValidAngles(hand(), rng)));
  const std::filesystem::path path = test::scratchDir("pose_sequence") / "poses.jsonl";
  ASSERT_TRUE(savePoseSequence(seq, path).ok());
  const Result<PoseSequence> loaded = loadPoseSequence(path);
  ASSERT_TRUE(loaded.ok()) << loaded.message();
  EXPECT_TRUE(checkPoseSequence(*loaded, hand()).ok());
  ASSERT_EQ(loaded->frames.size(), 5u);
  for (size_t f = 0; f < 5; ++f) {
    for (size_t b = 0; b < 17; ++b) {
      EXPECT_EQ(loaded->frames[f].bodies[b].p, seq.frames[f].bodies[b].p);
      EXPECT_LT(angleBetween(loaded->frames[f].bodies[b].q, seq.frames[f].bodies[b].q), 1e-6f);
    }
  }
}

// Writes `text` and returns the loader's error ("" when it loaded).
std::string poseError(const std::string& name, const std::string& text) {
  const std::filesystem::path path = test::scratchDir("pose_sequence_errors") / name;
  std::ofstream(path) << text;
  const Result<PoseSequence> seq = loadPoseSequence(path);
  return seq.ok() ? std::string() : seq.message().substr(seq.message().find(name));
}

const char* kHeader = R"({"format": "dynahand-pose", "version": 1, "bodies": ["a", "b"]})";

TEST(PoseSequenceErrors, EmptyFile) {
  EXPECT_EQ(poseError("e.jsonl", ""), "e.jsonl: empty pose sequence (no header line)");
}

TEST(PoseSequenceErrors, WrongFormatName) {
  EXPECT_EQ(poseError("f.jsonl", R"({"format": "x", "version": 1, "bodies": ["a"]})"),
            "f.jsonl:1: format: 'x' is not 'dynahand-pose'");
}

TEST(PoseSequenceErrors, FrameOutOfOrder) {
  const std::string text =
      std::string(kHeader) + "\n" + R"({"frame": 1, "poses": [[0,0,0,1,0,0,0],[0,0,0,1,0,0,0]]})";
  EXPECT_EQ(poseError("o.jsonl", text),
            "o.jsonl:2: frame: 1, expected 0 (frames are numbered in order from 0)");
}

TEST(PoseSequenceErrors, WrongBodyCount) {
  const std::string text =
      std::string(kHeader) + "\n" + R"({"frame": 0, "poses": [[0,0,0,1,0,0,0]]})";
  EXPECT_EQ(poseError("c.jsonl", text), "c.jsonl:2: poses: 1 poses for 2 bodies");
}

TEST(PoseSequenceErrors, NotUnitQuaternion) {
  const std::string text =
      std::string(kHeader) + "\n" + R"({"frame": 0, "poses": [[0,0,0,1,0,0,0],[0,0,0,0,0,0,0]]})";
  EXPECT_EQ(poseError("q.jsonl", text),
            "q.jsonl:2: poses[1]: orientation is not a unit quaternion");
}

TEST(PoseSequenceErrors, TruncatedLine) {
  const std::string text = std::string(kHeader) + "\n" + R"({"frame": 0, "poses": [[0,0,0,1,0)";
  EXPECT_NE(poseError("t.jsonl", text).find("t.jsonl:2: not valid JSON"), std::string::npos);
}

TEST(PoseSequenceErrors, NaN) {
  const std::string text =
      std::string(kHeader) + "\n" + R"({"frame": 0, "poses": [[NaN,0,0,1,0,0,0],[0,0,0,1,0,0,0]]})";
  EXPECT_NE(poseError("n.jsonl", text).find("n.jsonl:2: not valid JSON"), std::string::npos);
}

TEST(PoseSequenceErrors, BodiesOfAnotherModel) {
  PoseSequence seq;
  seq.bodyNames = {"a", "b"};
  const Status status = checkPoseSequence(seq, hand());
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.message().find("2 bodies"), std::string::npos);
}

}  // namespace
}  // namespace dynahand::model
