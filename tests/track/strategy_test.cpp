// Each simulation strategy on a case built for it (tracker issue, "Must show"): the same
// synthetic frames tracked with and without the strategy, the difference measured.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <numbers>

#include "dynahand/model.h"
#include "dynahand/model_pose.h"
#include "dynahand/tracker.h"
#include "track/synthetic_hand.h"

namespace dynahand::track {
namespace {

constexpr float kDeg = std::numbers::pi_v<float> / 180.0f;

model::JointAngles openAngles(const model::ArticulatedModel& m) {
  model::JointAngles a = model::zeroAngles(m);
  model::clampToLimits(m, a);
  return a;
}

model::ModelPose posed(const model::ArticulatedModel& m, model::JointAngles angles,
                       const Pose& root) {
  angles.root = root;
  return model::forwardKinematics(m, angles);
}

float meanErrorM(const Keypoints21& a, const Keypoints21& b) {
  float sum = 0.0f;
  for (std::size_t k = 0; k < 21; ++k) sum += (a[k] - b[k]).norm();
  return sum / 21.0f;
}

TrackerSettings only(std::initializer_list<StrategyKind> kinds) {
  TrackerSettings s;
  s.strategies = {false, false, false, false, false};
  for (StrategyKind k : kinds) s.strategies[static_cast<std::size_t>(k)] = true;
  return s;
}

// A fast jump of the whole hand, 4 cm along the fingers between two frames: each
// finger's samples are nearest to other bones of the finger (or to the next finger), so
// the plain fit settles folded or shifted; welded into one body, the hand moves as a whole
// first and is then refitted.
float afterJump(const TrackerSettings& settings) {
  const Vec3 offset(0.0f, 0.04f, 0.0f);  // image down: toward the wrist
  const auto hand = model::makeDefaultHand();
  test::SyntheticCamera camera("tof");
  const Pose root = test::facingCamera(hand, Vec3(0.0f, 0.0f, 0.40f));
  const model::ModelPose start = posed(hand, openAngles(hand), root);
  const Pose jumped{root.p + offset, root.q};
  const model::ModelPose moved = posed(hand, openAngles(hand), jumped);
  auto tracker = Tracker::create(hand, camera.intrinsics(), settings);
  EXPECT_TRUE(tracker.ok());
  (*tracker)->initialize(start);
  (*tracker)->track(camera.render(hand, start, 0, 0.0));
  float error = 0.0f;
  for (int f = 1; f <= 8; ++f) {
    const auto& r = (*tracker)->track(camera.render(hand, moved, f, f / 30.0));
    // The tracked skeleton's: the report's blend toward the detector is not a simulation's.
    error = meanErrorM(r.hands[0].skeletonKeypoints21, model::keypoints21(hand, moved));
  }
  return error;
}

TEST(Strategies, GrossMotionRecoversAFastJumpThatNormalAloneLoses) {
  const float normal = afterJump(only({StrategyKind::Normal}));
  const float gross = afterJump(only({StrategyKind::Normal, StrategyKind::GrossMotion}));
  std::printf("4 cm jump, error after 8 frames: normal only %.1f mm, with gross motion %.1f mm\n",
              1000.0 * static_cast<double>(normal), 1000.0 * static_cast<double>(gross));
  EXPECT_GT(normal, 0.015f);
  EXPECT_LT(gross, 0.010f);
}

// The tracker starts with the index finger curled while the data shows it straight, the hand
// `distance` in front of the camera.
float wronglyBentIndex(const TrackerSettings& settings, int frames, float distance) {
  const auto hand = model::makeDefaultHand();
  test::SyntheticCamera camera("tof");
  const Pose root = test::facingCamera(hand, Vec3(0.0f, 0.0f, distance));
  const model::ModelPose truth = posed(hand, openAngles(hand), root);
  model::JointAngles bent = openAngles(hand);
  // Curled fully into the palm (the joints' limits): its bones then lie on the palm's samples.
  for (int j : {4, 5, 6}) bent.angles[static_cast<std::size_t>(j)].x() = 110.0f * kDeg;
  model::clampToLimits(hand, bent);
  auto tracker = Tracker::create(hand, camera.intrinsics(), settings);
  EXPECT_TRUE(tracker.ok());
  (*tracker)->initialize(posed(hand, bent, root));
  const auto k = model::keypoints21(hand, truth);
  float tipError = 0.0f;
  for (int f = 0; f < frames; ++f) {
    const auto& r = (*tracker)->track(camera.render(hand, truth, f, f / 30.0));
    tipError = (r.hands[0].keypoints21[8] - k[8]).norm();
  }
  return tipError;
}

// Whether the plain fit frees the curled finger is chaotic: it does when a straight finger's
// sample happens to catch the right bone, which any change of rounding or segmentation edge
// can decide (normal only: 3 or 100 mm). So three placements: finger flip fixes the finger
// in every one, the plain fit loses it in most.
TEST(Strategies, FingerFlipFixesAWronglyBentFingerWithinOneSecond) {
  int normalLost = 0;
  for (const float distance : {0.35f, 0.40f, 0.45f}) {
    const float normal = wronglyBentIndex(only({StrategyKind::Normal}), 30, distance);
    const float flip =
        wronglyBentIndex(only({StrategyKind::Normal, StrategyKind::FingerFlip}), 30, distance);
    std::printf(
        "hand at %.2f m, index tip error after 1 s: normal only %.1f mm, with finger "
        "flip %.1f mm\n",
        static_cast<double>(distance), 1000.0 * static_cast<double>(normal),
        1000.0 * static_cast<double>(flip));
    if (normal > 0.03f) ++normalLost;
    EXPECT_LT(flip, 0.010f) << "hand at " << distance << " m";
  }
  EXPECT_GE(normalLost, 2) << "the case must be one the plain fit does not solve";
}

// A grasp seen from the thumb side: the ring and little fingers are hidden behind the index
// and middle fingers. The tracker starts with those two straight; nothing in the data pulls
// them, and only the grasp bias (neighbouring middle and distal bones within 10 degrees of
// parallel) curls them with their neighbours. Returns the worse of their two tip errors.
float hiddenStraightFingers(const TrackerSettings& settings, int frames) {
  const auto hand = model::makeDefaultHand();
  test::SyntheticCamera camera("tof");
  const Pose facing = test::facingCamera(hand, Vec3(0.0f, 0.0f, 0.40f));
  const Quat turn(Eigen::AngleAxisf(90.0f * kDeg, Vec3::UnitY()));  // thumb side to the camera
  const Pose root{facing.p, turn * facing.q};
  model::JointAngles grasp = openAngles(hand);
  for (std::size_t j = 4; j < 16; j += 3) {  // index .. little finger: MCP, PIP, DIP
    grasp.angles[j].x() = 60.0f * kDeg;
    grasp.angles[j + 1].x() = 80.0f * kDeg;
    grasp.angles[j + 2].x() = 50.0f * kDeg;
  }
  model::clampToLimits(hand, grasp);
  const model::ModelPose truth = posed(hand, grasp, root);
  model::JointAngles straight = grasp;
  for (std::size_t j = 10; j < 16; ++j) straight.angles[j].x() = 0.0f;  // ring and little
  model::clampToLimits(hand, straight);
  auto tracker = Tracker::create(hand, camera.intrinsics(), settings);
  EXPECT_TRUE(tracker.ok());
  (*tracker)->initialize(posed(hand, straight, root));
  const auto k = model::keypoints21(hand, truth);
  EXPECT_LT(k[5].z(), k[17].z()) << "the index side faces the camera";
  float error = 0.0f;
  for (int f = 0; f < frames; ++f) {
    const auto& tips =
        (*tracker)->track(camera.render(hand, truth, f, f / 30.0)).hands[0].keypoints21;
    error = std::max((tips[16] - k[16]).norm(), (tips[20] - k[20]).norm());
  }
  return error;
}

TEST(Strategies, GraspBiasCurlsHiddenFingersWithTheirNeighbours) {
  const float normal = hiddenStraightFingers(only({StrategyKind::Normal}), 45);
  const float grasp =
      hiddenStraightFingers(only({StrategyKind::Normal, StrategyKind::GraspBias}), 45);
  std::printf(
      "hidden ring and little tips after 1.5 s: normal only %.1f mm, with grasp bias %.1f mm\n",
      1000.0 * static_cast<double>(normal), 1000.0 * static_cast<double>(grasp));
  EXPECT_GT(normal, 0.03f);
  EXPECT_LT(grasp, 0.010f);
}

// The hand leaves the view and comes back elsewhere, turned 60 degrees in the image plane:
// lost while away, then re-acquired from scratch (no call from the caller).
struct Reentry {
  bool lostWhileAway = false;
  int framesToAcquire = -1;  // after re-entering
  float error = 1.0f;        // mean keypoint error at the end, m
};

Reentry leaveAndReenter(const TrackerSettings& settings) {
  const auto hand = model::makeDefaultHand();
  test::SyntheticCamera camera("tof");
  const Pose root = test::facingCamera(hand, Vec3(0.0f, 0.0f, 0.40f));
  const model::ModelPose start = posed(hand, openAngles(hand), root);
  const Quat turn(Eigen::AngleAxisf(60.0f * kDeg, Vec3::UnitZ()));
  const Pose back{Vec3(0.03f, 0.02f, 0.42f), turn * root.q};
  const model::ModelPose returned = posed(hand, openAngles(hand), back);
  auto tracker = Tracker::create(hand, camera.intrinsics(), settings);
  EXPECT_TRUE(tracker.ok());
  (*tracker)->initialize(start);
  Reentry out;
  int f = 0;
  for (; f < 3; ++f) (*tracker)->track(camera.render(hand, start, f, f / 30.0));
  DepthFrame empty(camera.intrinsics().width, camera.intrinsics().height, 0.001f);
  for (; f < 6; ++f) {
    empty.timestamp = f / 30.0;
    out.lostWhileAway = !(*tracker)->track(empty).hands[0].tracked;
  }
  for (int k = 0; k < 10; ++k, ++f) {
    const auto& r = (*tracker)->track(camera.render(hand, returned, f, f / 30.0));
    const auto& h = r.hands[0];
    if (h.tracked && out.framesToAcquire < 0) {
      out.framesToAcquire = k + 1;
    }
    out.error = h.tracked ? meanErrorM(h.keypoints21, model::keypoints21(hand, returned)) : 1.0f;
  }
  return out;
}

TEST(Strategies, ReacquiresAfterTheHandLeavesAndReentersTheView) {
  const Reentry r = leaveAndReenter(TrackerSettings{});
  std::printf("re-entry: lost while away %d, acquired after %d frames, error %.1f mm\n",
              r.lostWhileAway, r.framesToAcquire, 1000.0 * static_cast<double>(r.error));
  EXPECT_TRUE(r.lostWhileAway);
  EXPECT_GE(r.framesToAcquire, 1);
  EXPECT_LE(r.framesToAcquire, 3);
  EXPECT_LT(r.error, 0.010f);
}

}  // namespace
}  // namespace dynahand::track
