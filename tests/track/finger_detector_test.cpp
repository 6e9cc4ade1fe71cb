// The five-finger detector on rendered hands: fires on a spread open hand at any turn in
// the image plane, with each fingertip where the finger ends; stays quiet on a fist.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstdio>
#include <numbers>
#include <random>
#include <utility>
#include <vector>

#include "core/simd/simd.h"
#include "dynahand/cloud.h"
#include "dynahand/model.h"
#include "track/finger_detector.h"
#include "track/synthetic_hand.h"

namespace dynahand::track {
namespace {

constexpr float kDeg = std::numbers::pi_v<float> / 180.0f;

model::JointAngles spreadAngles(const model::ArticulatedModel& m) {
  model::JointAngles a = model::zeroAngles(m);
  a.angles[1].y() = 35.0f * kDeg;    // thumb metacarpal out
  a.angles[4].y() = 15.0f * kDeg;    // index
  a.angles[10].y() = -12.0f * kDeg;  // ring
  a.angles[13].y() = -25.0f * kDeg;  // pinky
  model::clampToLimits(m, a);
  return a;
}

model::JointAngles fistAngles(const model::ArticulatedModel& m) {
  model::JointAngles a = model::zeroAngles(m);
  for (std::size_t j = 4; j < 16; ++j) a.angles[j].x() = 90.0f * kDeg;
  a.angles[1].x() = 40.0f * kDeg;
  model::clampToLimits(m, a);
  return a;
}

struct Detected {
  bool fired = false;
  float worstTipErrorM = 1.0f;
  FingerDetection detection;
};

Detected detectAt(model::JointAngles angles, float turnDeg, float distanceM = 0.40f) {
  const auto hand = model::makeDefaultHand();
  test::SyntheticCamera camera("tof");
  const Pose upright = test::facingCamera(hand, Vec3(0.0f, 0.0f, distanceM));
  const Quat turn(Eigen::AngleAxisf(turnDeg * kDeg, Vec3::UnitZ()));
  angles.root = Pose{turn * upright.p, turn * upright.q};
  const model::ModelPose pose = model::forwardKinematics(hand, angles);
  const DepthFrame depth = camera.render(hand, pose, 0, 0.0);
  // The spread hand spans about 22 cm from its thumb tip (the nearest point) to the little
  // fingertip: more than the default segmentation radius, which would cut the little finger.
  CloudConfig config;
  config.segmentation.handRadiusM = 0.24f;
  CloudPipeline pipeline(camera.intrinsics(), config);
  CloudFrame cloud;
  EXPECT_TRUE(pipeline.process(depth, cloud).ok());
  FingerDetector detector;
  const FingerDetection& d = detector.detect(cloud);
  Detected out;
  out.fired = d.fired;
  out.detection = d;
  if (d.fired) {
    const auto k = model::keypoints21(hand, pose);
    out.worstTipErrorM = 0.0f;
    for (std::size_t f = 0; f < 5; ++f) {
      out.worstTipErrorM = std::max(out.worstTipErrorM, (d.tips[f] - k[4 + 4 * f]).norm());
    }
  }
  return out;
}

TEST(FingerDetector, FindsTheFiveFingertipsOfASpreadHandAtAnyTurn) {
  const auto hand = model::makeDefaultHand();
  for (float turn : {0.0f, 30.0f, -45.0f, 70.0f}) {
    const Detected d = detectAt(spreadAngles(hand), turn);
    EXPECT_TRUE(d.fired) << "turned " << turn << " degrees";
    // The tip sample sits a little inside the finger and on its front surface.
    EXPECT_LT(d.worstTipErrorM, 0.018f) << "turned " << turn << " degrees";
  }
}

// The scanlines sampled on every SIMD level the CPU has (core/simd) give the scalar level's
// detections, bit for bit: hands spread and in a fist, turned, near and far.
TEST(FingerDetector, EverySimdLevelDetectsLikeTheScalarOne) {
  const auto hand = model::makeDefaultHand();
  const simd::Level best = simd::bestLevel();
  int fired = 0, compared = 0;
  for (const bool spread : {true, false}) {
    for (const float turn : {0.0f, 25.0f, -45.0f, 70.0f, 180.0f}) {
      for (const float distance : {0.3f, 0.45f}) {
        const model::JointAngles angles = spread ? spreadAngles(hand) : fistAngles(hand);
        simd::forceLevel(simd::Level::Scalar);
        const Detected reference = detectAt(angles, turn, distance);
        ++compared;
        fired += reference.fired;
        for (int l = 1; l <= static_cast<int>(best); ++l) {
          const auto level = static_cast<simd::Level>(l);
          ASSERT_EQ(simd::forceLevel(level), level);
          const Detected wide = detectAt(angles, turn, distance);
          SCOPED_TRACE(testing::Message() << simd::levelName(level) << ": spread " << spread
                                          << " turn " << turn << " at " << distance);
          ASSERT_EQ(reference.fired, wide.fired);
          if (!reference.fired) continue;
          for (std::size_t f = 0; f < 5; ++f) {
            for (int c = 0; c < 3; ++c)
              EXPECT_EQ(reference.detection.tips[f][c], wide.detection.tips[f][c]) << "tip " << f;
            for (int c = 0; c < 2; ++c)
              EXPECT_EQ(reference.detection.tipPixels[f][c], wide.detection.tipPixels[f][c])
                  << "tip " << f;
          }
        }
      }
    }
  }
  simd::forceLevel(best);
  std::printf("compared the scalar level with %d wider level(s)\n", static_cast<int>(best));
  EXPECT_EQ(compared, 20);
  EXPECT_GE(fired, 4);  // spread hands are found (the comparison is not all "not fired")
}

// scanlineRuns against the sample-by-sample rule it implements, on random scanlines of 1 to
// 200 samples (several 64-bit words), sparse and dense.
TEST(FingerDetector, ScanlineRunsFollowTheSampleBySampleRule) {
  std::mt19937 rng(7);
  std::vector<ScanlineRun> runs;
  for (int trial = 0; trial < 3000; ++trial) {
    const int columns = 1 + static_cast<int>(rng() % 200);
    const float density = static_cast<float>(rng() % 100) / 100.0f;
    std::vector<bool> sample(static_cast<std::size_t>(columns));
    std::vector<std::uint64_t> on(static_cast<std::size_t>(columns + 63) / 64, 0);
    for (int c = 0; c < columns; ++c) {
      sample[static_cast<std::size_t>(c)] = static_cast<float>(rng() % 1000) < 1000 * density;
      if (sample[static_cast<std::size_t>(c)])
        on[static_cast<std::size_t>(c / 64)] |= std::uint64_t{1} << (c % 64);
    }
    // The rule: a run ends at the second off sample after it; one whose last sample is on
    // (still open at the end) is left out.
    std::vector<std::pair<int, int>> expected;
    int begin = -1, gap = 0;
    for (int col = 0; col <= columns; ++col) {
      if (col < columns && sample[static_cast<std::size_t>(col)]) {
        if (begin < 0) begin = col;
        gap = 0;
      } else if (begin >= 0 && ++gap > 1) {
        expected.emplace_back(begin, col - gap + 1);
        begin = -1;
        gap = 0;
      }
    }
    scanlineRuns(on.data(), columns, runs);
    ASSERT_EQ(runs.size(), expected.size()) << "trial " << trial;
    for (std::size_t i = 0; i < runs.size(); ++i) {
      ASSERT_EQ(runs[i].begin, expected[i].first) << "trial " << trial << " run " << i;
      ASSERT_EQ(runs[i].end, expected[i].second) << "trial " << trial << " run " << i;
    }
  }
}

TEST(FingerDetector, StaysQuietOnAFist) {
  const auto hand = model::makeDefaultHand();
  EXPECT_FALSE(detectAt(fistAngles(hand), 0.0f).fired);
}

}  // namespace
}  // namespace dynahand::track
