// The automatic hand-size estimate (hand_size.h) on short synthetic clips of a small and a
// large hand, tracked from the first frame's keypoints: the default (medium) model is 15 %
// off either way, so an estimate that stays near the model's size fails.
#include <gtest/gtest.h>

#include <vector>

#include "dynahand/hand_size.h"
#include "dynahand/synth.h"

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

Clip makeClip(const model::HandDimensions& size, bool headMounted = false) {
  synth::SynthOptions o;
  o.clip = "wave";
  o.profile = "tof";
  o.frameCount = kFrames;
  o.hand = size;
  if (headMounted) o.scene.placement = synth::CameraPlacement::HeadMounted;
  auto seq = synth::SyntheticSequence::create(o);
  EXPECT_TRUE(seq) << seq.message();
  Clip clip;
  clip.intrinsics = seq->intrinsics();
  clip.start = seq->frame(0).hands[0].keypoints;
  for (int f = 0; f < kFrames; ++f) clip.frames.push_back(seq->frame(f).depth);
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
    EXPECT_EQ(e->candidates, 13);
    EXPECT_GT(e->fitScore, 0.95f);
  }
}

// From a head-mounted camera the forearm comes toward the camera and the segmentation keeps
// much of it: the score leaves the samples beyond the model's wrist out, else the candidate with
// the longest forearm covers the most of them and wins.
// From the head the fingers point away and show less of their length: 10 %.
TEST(HandSize, EstimatesASmallHandSeenFromTheHead) {
  const model::HandDimensions truth{0.165f, 0.075f};
  const Clip clip = makeClip(truth, true);
  auto e = estimateHandSize(clip.frames, clip.intrinsics, clip.start);
  ASSERT_TRUE(e) << e.message();
  EXPECT_NEAR(e->dimensions.length / truth.length, 1.0f, 0.10f) << e->dimensions.length << " m";
  EXPECT_NEAR(e->dimensions.width / truth.width, 1.0f, 0.10f) << e->dimensions.width << " m";
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
  EXPECT_EQ(e->candidates, 7);
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
  EXPECT_FALSE(estimateHandSize(clip.frames, clip.intrinsics, clip.start, o));
  EXPECT_FALSE(estimateHandSize(clip.frames, Intrinsics{}, clip.start));
}

}  // namespace
}  // namespace dynahand::track
