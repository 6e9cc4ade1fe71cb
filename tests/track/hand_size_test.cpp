// The automatic hand-size estimate (hand_size.h) on short synthetic clips of a small and a
// large hand, tracked from the first frame's keypoints: the default (medium) model is 15 %
// off either way, so an estimate that stays near the model's size fails. And the metacarpal
// lengths of a hand shaped unlike the model.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <iterator>
#include <vector>

#include "dynahand/hand_size.h"
#include "dynahand/synth.h"
#include "dynahand/synth_render.h"
#include "synth_support.h"
#include "test_support.h"

namespace dynahand::track {
namespace {

// 10 frames (1/3 s) keep the test short (13 trackers); over 30 frames the search comes within
// 5.3 % on three clips of each size from their first keypoints (docs/tracker.md, "Hand size").
// 5 % is the target, and well outside the default model's 13-15 % difference.
constexpr int kFrames = 10;
constexpr float kTolerance = 0.05f;

struct Clip {
  std::vector<DepthFrame> frames;
  Intrinsics intrinsics;
  Keypoints21 start{};
};

Clip makeClip(const model::HandDimensions& size, bool headMounted = false,
              const synth::HandProportions& proportions = {}, int frames = kFrames) {
  synth::SynthOptions o;
  o.clip = "wave";
  o.profile = "tof";
  o.frameCount = frames;
  o.hand = size;
  o.proportions = proportions;
  if (headMounted) o.scene.placement = synth::CameraPlacement::HeadMounted;
  auto seq = synth::SyntheticSequence::create(o);
  EXPECT_TRUE(seq) << seq.message();
  Clip clip;
  clip.intrinsics = seq->intrinsics();
  clip.start = seq->frame(0).hands[0].keypoints;
  for (int f = 0; f < frames; ++f) clip.frames.push_back(seq->frame(f).depth);
  return clip;
}

void expectNear(float estimated, float truth, const char* what) {
  EXPECT_NEAR(estimated / truth, 1.0f, kTolerance)
      << what << " " << estimated << " m, truth " << truth << " m";
}

TEST(HandSize, EstimatesASmallAndALargeHand) {
  for (const model::HandDimensions truth :
       {model::HandDimensions{0.165f, 0.075f}, model::HandDimensions{0.215f, 0.095f}}) {
    const Clip clip = makeClip(truth);
    auto e = estimateHandSize(clip.frames, clip.intrinsics, clip.start);
    ASSERT_TRUE(e) << e.message();
    expectNear(e->dimensions.length, truth.length, "length");
    expectNear(e->dimensions.width, truth.width, "width");
    EXPECT_EQ(e->framesUsed, kFrames);
    EXPECT_EQ(e->candidates, 13 + 24);  // the size, then two steps of the metacarpals
    EXPECT_GT(e->fitScore, 0.95f);
  }
}

// From a head-mounted camera (the back of the hand toward it) the size is the default
// proportions scaled to the palm the learned detector sees: the error metric says little of
// the size there (its estimate ran 6-11 % long). Over 30 frames, as `dynahand track
// --hand-size auto`; one candidate scored, one tracked for the metacarpals.
TEST(HandSize, EstimatesHandsSeenFromTheHeadFromTheDetectedPalm) {
  for (const model::HandDimensions truth :
       {model::HandDimensions{0.165f, 0.075f}, model::HandDimensions{0.215f, 0.095f}}) {
    const Clip clip = makeClip(truth, true, {}, 30);
    auto e = estimateHandSize(clip.frames, clip.intrinsics, clip.start);
    ASSERT_TRUE(e) << e.message();
    expectNear(e->dimensions.length, truth.length, "length");
    expectNear(e->dimensions.width, truth.width, "width");
    EXPECT_LE(e->candidates, 2);
    // The back of the hand toward the camera: no frame to judge the metacarpals by.
    EXPECT_TRUE(e->shape.identity());
  }
}

// Root mean square over the five digits of the metacarpal factors' differences.
float metacarpalDifference(const model::HandShape& a, const model::HandShape& b) {
  float sum = 0.0f;
  for (std::size_t d = 0; d < 5; ++d) {
    const float x = a.boneLength[d][0] - b.boneLength[d][0];
    sum += x * x;
  }
  return std::sqrt(sum / 5.0f);
}

// A medium hand whose knuckles sit unlike the model's (the synthesiser's proportions, seed 3:
// metacarpals 1.05 / 0.87 / 0.86 / 1.05 / 1.02, every other factor within 15 %): the estimated
// metacarpals come closer to them than the default shape (0.091 root mean square); over 30
// frames, as `dynahand track --hand-size auto`.
TEST(HandSize, EstimatesTheMetacarpalsOfAHandShapedUnlikeTheModel) {
  const synth::HandProportions truth = synth::randomProportions(3, 0.15f);
  const Clip clip = makeClip({}, false, truth, 30);
  auto e = estimateHandSize(clip.frames, clip.intrinsics, clip.start);
  ASSERT_TRUE(e) << e.message();
  const float estimated = metacarpalDifference(e->shape, truth);
  const float byDefault = metacarpalDifference(model::HandShape{}, truth);
  EXPECT_LT(estimated, byDefault - 0.01f) << "default " << byDefault;
  // Only the metacarpals are estimated.
  for (std::size_t d = 0; d < 5; ++d)
    for (std::size_t b = 1; b < 4; ++b) EXPECT_EQ(e->shape.boneLength[d][b], 1.0f);
  EXPECT_EQ(e->shape.fingerThickness, model::HandShape{}.fingerThickness);
  HandSizeOptions sizeOnly;
  sizeOnly.metacarpals = false;
  auto s = estimateHandSize(clip.frames, clip.intrinsics, clip.start, sizeOnly);
  ASSERT_TRUE(s) << s.message();
  EXPECT_TRUE(s->shape.identity());
  EXPECT_EQ(s->candidates, 13);
  EXPECT_EQ(s->dimensions.length, e->dimensions.length);
}

// Without start keypoints on captured motion (animbank.pose, tof, the default hand's size, three
// segments that start in no open hand facing the camera and show the palm): the candidates
// start from the keypoints the tracker with the learned detector reports once it has the hand.
// With the shipped weights the lengths come out 95.5 / 96.2 / 86.5 % of the truth (frames 600 /
// 1200 / 1800); acquiring by themselves (the detector off) each candidate takes the hand its own
// way: 87.9 / 110.3 / 120.7 %. One segment's estimate moves by up to 8 % with changes that only
// move the detections a little (one detector crop a frame instead of three: 98.8 / 103.2 /
// 89.9 %); over 16 segments of 30 frames (every 150th frame) the length is off by 4.0 % on
// average, at most 13.5 % (3.7 %, at most 10.2 %, with one crop), hence the bounds below.
// Another segment shows the back of the hand: the size from the detected palm.
TEST(HandSize, EstimatesWithoutStartKeypointsOnCapturedMotion) {
  DYNAHAND_REQUIRE_SHARED_DATA(data);
  const model::HandDimensions truth{};
  HandSizeOptions o;
  o.metacarpals = false;
  const auto framesFrom = [&](int start, Intrinsics& intrinsics) {
    auto seq = synth::SyntheticSequence::create(test::animbankOptions(data, start, 30, "tof"));
    EXPECT_TRUE(seq) << seq.message();
    std::vector<DepthFrame> frames;
    if (!seq) return frames;
    intrinsics = seq->intrinsics();
    for (int f = 0; f < 30; ++f) frames.push_back(seq->frame(f).depth);
    return frames;
  };
  Intrinsics intrinsics;
  const std::vector<DepthFrame> behind = framesFrom(300, intrinsics);
  auto fromPalm = estimateHandSize(behind, intrinsics, std::nullopt, o);
  ASSERT_TRUE(fromPalm) << fromPalm.message();
  EXPECT_EQ(fromPalm->candidates, 1);
  expectNear(fromPalm->dimensions.length, truth.length, "length from behind");
  expectNear(fromPalm->dimensions.width, truth.width, "width from behind");
  double lengthErrorSum = 0.0;
  constexpr int kStarts[] = {600, 1200, 1800};
  for (const int start : kStarts) {
    const std::vector<DepthFrame> frames = framesFrom(start, intrinsics);
    o.tracker.detector.enabled = true;
    auto detected = estimateHandSize(frames, intrinsics, std::nullopt, o);
    ASSERT_TRUE(detected) << detected.message();
    const double lengthRatio = static_cast<double>(detected->dimensions.length / truth.length);
    std::printf("frame %d: length %.1f %% of the truth, width %.1f %%\n", start,
                100.0 * lengthRatio,
                100.0 * static_cast<double>(detected->dimensions.width / truth.width));
    lengthErrorSum += std::abs(lengthRatio - 1.0);
    EXPECT_EQ(detected->candidates, 13) << "frame " << start << ": the candidates' search";
    EXPECT_NEAR(lengthRatio, 1.0, 0.15)
        << "frame " << start << ": " << detected->dimensions.length << " m";
    EXPECT_NEAR(detected->dimensions.width / truth.width, 1.0f, 0.15f)
        << "frame " << start << ": " << detected->dimensions.width << " m";
    o.tracker.detector.enabled = false;
    auto byThemselves = estimateHandSize(frames, intrinsics, std::nullopt, o);
    ASSERT_TRUE(byThemselves) << byThemselves.message();
    std::printf("frame %d, the detector off: length %.1f %% of the truth\n", start,
                100.0 * static_cast<double>(byThemselves->dimensions.length / truth.length));
    EXPECT_LT(std::abs(lengthRatio - 1.0),
              std::abs(static_cast<double>(byThemselves->dimensions.length / truth.length) - 1.0))
        << "frame " << start << ": " << byThemselves->dimensions.length << " m";
  }
  EXPECT_LT(lengthErrorSum / static_cast<double>(std::size(kStarts)), 0.08)
      << "the length's mean error over the segments";
}

// A given length is kept; the width alone is searched.
TEST(HandSize, KeepsAGivenLength) {
  const model::HandDimensions truth{0.165f, 0.075f};
  const Clip clip = makeClip(truth);
  HandSizeOptions o;
  o.length = truth.length;
  auto e = estimateHandSize(clip.frames, clip.intrinsics, clip.start, o);
  ASSERT_TRUE(e) << e.message();
  EXPECT_EQ(e->dimensions.length, truth.length);
  expectNear(e->dimensions.width, truth.width, "width");
  EXPECT_EQ(e->candidates, 7 + 24);
}

// Length and width both given: they are kept and the metacarpals alone are estimated (one
// candidate for the score, then step 4's 24).
TEST(HandSize, KeepsAGivenSizeAndEstimatesTheMetacarpals) {
  const synth::HandProportions truth = synth::randomProportions(3, 0.15f);
  const Clip clip = makeClip({}, false, truth, 30);
  HandSizeOptions o;
  o.length = 0.19f;
  o.width = 0.085f;
  auto e = estimateHandSize(clip.frames, clip.intrinsics, clip.start, o);
  ASSERT_TRUE(e) << e.message();
  EXPECT_EQ(e->dimensions.length, 0.19f);
  EXPECT_EQ(e->dimensions.width, 0.085f);
  EXPECT_EQ(e->candidates, 1 + 24);
  EXPECT_GT(e->fitScore, 0.9f);
  EXPECT_LT(metacarpalDifference(e->shape, truth),
            metacarpalDifference(model::HandShape{}, truth) - 0.01f);
}

TEST(HandSize, RefusesTooFewFramesAndNothingToEstimate) {
  const Clip clip = makeClip({});
  // Without start keypoints the first acquisitionFrames (6) frames are not scored.
  const std::span<const DepthFrame> three(clip.frames.data(), 3);
  auto few = estimateHandSize(three, clip.intrinsics, std::nullopt);
  ASSERT_FALSE(few);
  EXPECT_NE(few.message().find("3 frames"), std::string::npos) << few.message();
  EXPECT_FALSE(estimateHandSize({}, clip.intrinsics, clip.start));
  HandSizeOptions o;
  o.length = 0.19f;
  o.width = 0.085f;
  o.metacarpals = false;
  EXPECT_FALSE(estimateHandSize(clip.frames, clip.intrinsics, clip.start, o));
  EXPECT_FALSE(estimateHandSize(clip.frames, Intrinsics{}, clip.start));
}

}  // namespace
}  // namespace dynahand::track
