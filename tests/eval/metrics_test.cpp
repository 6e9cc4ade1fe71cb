#include <gtest/gtest.h>

#include <cmath>

#include "dynahand/metrics.h"

namespace dynahand::eval {
namespace {

Keypoints21 handAt(float x) {
  Keypoints21 k;
  for (int j = 0; j < 21; ++j) k[j] = Vec3(x + 0.01f * j, 0.002f * j, 0.5f);
  return k;
}

Keypoints21 shifted(const Keypoints21& k, const Vec3& d) {
  Keypoints21 out = k;
  for (auto& p : out) p += d;
  return out;
}

TEST(KeypointMetrics, ConstantOffsetGivesThatError) {
  SequenceKeypoints s;
  for (int f = 0; f < 10; ++f) {
    s.groundTruth.push_back(handAt(0.001f * f));
    s.predicted.push_back(shifted(handAt(0.001f * f), Vec3(0, 0, 0.004f)));  // 4 mm
  }
  auto m = computeKeypointMetrics(s);
  ASSERT_TRUE(m.ok()) << m.message();
  EXPECT_NEAR(m->meanMm, 4.0, 1e-3);
  EXPECT_NEAR(m->medianMm, 4.0, 1e-3);
  EXPECT_NEAR(m->p95Mm, 4.0, 1e-3);
  EXPECT_NEAR(m->perJointMeanMm[8], 4.0, 1e-3);
  EXPECT_NEAR(m->jitterMm, 0.0, 1e-3);  // the offset is constant: no extra motion
  EXPECT_EQ(m->lostFrames, 0);
  ASSERT_EQ(m->successFraction.size(), 5u);
  EXPECT_DOUBLE_EQ(m->successFraction[0], 1.0);  // 4 mm < 10 mm on every frame
}

// Joints left out of the score (hidden behind a held object) count in no error figure.
TEST(KeypointMetrics, UnscoredJointsAreLeftOut) {
  SequenceKeypoints s;
  const Keypoints21 gt = handAt(0);
  Keypoints21 off = shifted(gt, Vec3(0.002f, 0, 0));  // 2 mm everywhere ...
  off[4] += Vec3(0.1f, 0, 0);                         // ... and the thumb tip 10 cm more
  s.groundTruth = {gt, gt};
  s.predicted = {off, off};
  std::array<bool, 21> all;
  all.fill(true);
  std::array<bool, 21> noThumbTip = all;
  noThumbTip[4] = false;
  s.scored = {noThumbTip, all};
  auto m = computeKeypointMetrics(s);
  ASSERT_TRUE(m.ok()) << m.message();
  EXPECT_NEAR(m->perFrameMaxMm[0], 2.0, 1e-3);
  EXPECT_NEAR(m->perFrameMaxMm[1], 102.0, 1e-2);
  EXPECT_NEAR(m->perFrameMeanMm[0], 2.0, 1e-3);
  EXPECT_NEAR(m->perJointMeanMm[4], 102.0, 1e-2);           // scored on frame 1 only
  EXPECT_NEAR(m->meanMm, (40 * 2.0 + 102.0) / 41.0, 1e-2);  // 20 + 21 joints scored
  s.scored.pop_back();
  EXPECT_FALSE(computeKeypointMetrics(s).ok());
}

TEST(KeypointMetrics, SuccessCurveUsesMaximumJointError) {
  SequenceKeypoints s;
  // Frame 0: one joint 25 mm off; frame 1: all within 5 mm.
  Keypoints21 gt = handAt(0);
  Keypoints21 bad = gt;
  bad[4] += Vec3(0.025f, 0, 0);
  s.groundTruth = {gt, gt};
  s.predicted = {bad, shifted(gt, Vec3(0.005f, 0, 0))};
  auto m = computeKeypointMetrics(s);
  ASSERT_TRUE(m.ok());
  EXPECT_DOUBLE_EQ(m->successFraction[0], 0.5);  // <= 10 mm: only frame 1
  EXPECT_DOUBLE_EQ(m->successFraction[1], 0.5);  // <= 20 mm
  EXPECT_DOUBLE_EQ(m->successFraction[2], 1.0);  // <= 30 mm: both
  EXPECT_NEAR(m->perFrameMaxMm[0], 25.0, 1e-3);
  EXPECT_NEAR(m->maxMm, 25.0, 1e-3);
}

TEST(KeypointMetrics, JitterMeasuresExtraMotionOnStaticClip) {
  SequenceKeypoints s;
  for (int f = 0; f < 11; ++f) {
    s.groundTruth.push_back(handAt(0));
    // Alternates +-1 mm in x: 2 mm frame-to-frame motion on every joint.
    s.predicted.push_back(shifted(handAt(0), Vec3(f % 2 ? 0.001f : -0.001f, 0, 0)));
  }
  auto m = computeKeypointMetrics(s);
  ASSERT_TRUE(m.ok());
  EXPECT_NEAR(m->jitterMm, 2.0, 1e-3);
  EXPECT_NEAR(m->meanMm, 1.0, 1e-3);
}

TEST(KeypointMetrics, LostEpisodesAndRecoveryTime) {
  SequenceKeypoints s;
  s.fps = 10;
  for (int f = 0; f < 20; ++f) {
    s.groundTruth.push_back(handAt(0));
    if (f >= 5 && f < 8) {
      s.predicted.push_back(std::nullopt);  // reported lost for 3 frames
    } else if (f >= 12 && f < 14) {
      s.predicted.push_back(shifted(handAt(0), Vec3(0.08f, 0, 0)));  // 80 mm: lost
    } else if (f >= 18) {
      s.predicted.push_back(std::nullopt);  // lost at the end
    } else {
      s.predicted.push_back(handAt(0));
    }
  }
  auto m = computeKeypointMetrics(s);
  ASSERT_TRUE(m.ok());
  EXPECT_EQ(m->lostFrames, 3 + 2 + 2);
  EXPECT_EQ(m->lostEpisodes, 3);
  EXPECT_EQ(m->unrecoveredEpisodes, 1);
  EXPECT_NEAR(m->meanRecoverySeconds, (0.3 + 0.2) / 2, 1e-9);
  EXPECT_NEAR(m->maxRecoverySeconds, 0.3, 1e-9);
  EXPECT_EQ(m->evaluatedFrames, 20 - 3 - 2);
  EXPECT_TRUE(std::isnan(m->perFrameMeanMm[6]));
}

TEST(KeypointMetrics, FramesWithoutVisibleHandAreNotCounted) {
  SequenceKeypoints s;
  s.groundTruth = {handAt(0), std::nullopt, handAt(0)};
  s.predicted = {handAt(0), std::nullopt, handAt(0)};
  auto m = computeKeypointMetrics(s);
  ASSERT_TRUE(m.ok());
  EXPECT_EQ(m->visibleFrames, 2);
  EXPECT_EQ(m->lostFrames, 0);
  EXPECT_DOUBLE_EQ(m->successFraction[0], 1.0);
}

TEST(KeypointMetrics, RejectsMismatchedLengthsAndNonFinite) {
  SequenceKeypoints s;
  s.groundTruth = {handAt(0)};
  auto m = computeKeypointMetrics(s);
  ASSERT_FALSE(m.ok());
  EXPECT_NE(m.message().find("1 frames"), std::string::npos);
  Keypoints21 nan = handAt(0);
  nan[3].x() = std::nanf("");
  s.predicted = {nan};
  auto m2 = computeKeypointMetrics(s);
  ASSERT_FALSE(m2.ok());
  EXPECT_NE(m2.message().find("not finite"), std::string::npos);
}

TEST(Report, MarkdownAndSvgContainTheNumbers) {
  SequenceKeypoints s;
  for (int f = 0; f < 5; ++f) {
    s.groundTruth.push_back(handAt(0));
    s.predicted.push_back(shifted(handAt(0), Vec3(0, 0.003f, 0)));
  }
  auto m = computeKeypointMetrics(s);
  ASSERT_TRUE(m.ok());
  const std::string md = markdownReport(*m, "clip");
  EXPECT_NE(md.find("| mean 21-keypoint error | 3.00 mm |"), std::string::npos);
  EXPECT_NE(md.find("index_tip"), std::string::npos);
  const std::string svg = svgErrorOverTime(*m, "clip");
  EXPECT_EQ(svg.rfind("<svg", 0), 0u);
  EXPECT_NE(svg.find("<polyline"), std::string::npos);
  EXPECT_NE(svg.find("</svg>"), std::string::npos);
  EXPECT_NE(svgSuccessCurve(*m, "clip").find("<polyline"), std::string::npos);
  const std::string text = summaryText(*m);
  EXPECT_EQ(text.rfind("frames 5 (hand visible 5, evaluated 5)\n", 0), 0u);
  EXPECT_NE(text.find("21-keypoint error  mean 3.00 mm  median 3.00 mm"), std::string::npos);
  EXPECT_NE(text.find("  10 mm: 100.0%"), std::string::npos);
  EXPECT_EQ(text.back(), '\n');
}

}  // namespace
}  // namespace dynahand::eval
