// The tracker on the synthetic sensor (smooth render surface, ToF noise), initialised
// from the first frame's ground-truth pose.
#include <gtest/gtest.h>

#include <cstdio>
#include <limits>
#include <string>
#include <utility>

#include "dynahand/synth.h"
#include "dynahand/tracker.h"

namespace dynahand::track {
namespace {

struct ClipRun {
  float meanErrorM = 0;
  int trackedFrames = 0;
  int frames = 0;
};

ClipRun runClip(const std::string& clip, int frames, float speed = 1.0f,
                const TrackerSettings& settings = {}) {
  synth::SynthOptions o;
  o.clip = clip;
  o.profile = "tof";
  o.frameCount = frames;
  o.speed = speed;
  auto seq = synth::SyntheticSequence::create(o);
  EXPECT_TRUE(seq.ok()) << seq.message();
  const auto& hand = seq->model(0);
  auto tracker = Tracker::create(hand, seq->intrinsics(), settings);
  EXPECT_TRUE(tracker.ok()) << tracker.message();
  ClipRun run;
  run.frames = frames;
  double total = 0;
  for (int f = 0; f < frames; ++f) {
    const synth::SyntheticFrame& frame = seq->frame(f);
    if (f == 0) (*tracker)->initialize(frame.hands[0].pose);
    const TrackResult& r = (*tracker)->track(frame.depth);
    const auto& h = r.hands[0];
    run.trackedFrames += h.tracked ? 1 : 0;
    double err = 0;
    for (int k = 0; k < 21; ++k) {
      err += static_cast<double>((h.keypoints21[static_cast<std::size_t>(k)] -
                                  frame.hands[0].keypoints[static_cast<std::size_t>(k)])
                                     .norm());
    }
    total += err / 21.0;
  }
  run.meanErrorM = static_cast<float>(total / frames);
  std::printf("%s: mean 21-keypoint error %.1f mm, tracked %d/%d\n", clip.c_str(),
              1000.0 * static_cast<double>(run.meanErrorM), run.trackedFrames, frames);
  return run;
}

TEST(Tracker, FollowsSlowWave) {
  const ClipRun run = runClip("wave", 40, 0.5f);
  EXPECT_LT(run.meanErrorM, 0.010f);
  EXPECT_EQ(run.trackedFrames, run.frames);
}

// The fingers curl into a fist and open again: the hand must not slide down the arm over the
// curled fingers (it did while boundary planes pushed the forearm, cut by the segmentation,
// to point away from the camera).
TEST(Tracker, FollowsSlowOpenClose) {
  const ClipRun run = runClip("open-close", 80, 0.5f);
  EXPECT_LT(run.meanErrorM, 0.010f);
  EXPECT_EQ(run.trackedFrames, run.frames);
}

// Same input, same output bits: twice on one thread (the simulations two by two, their worlds
// stepped together), and with the simulations spread over three threads (each alone); with every
// simulation's pose and full error kept, and without (then losing simulations stop their metric
// early, in the same order for any thread count). The winner is the same either way.
TEST(Tracker, IsDeterministicForAnyThreadCount) {
  synth::SynthOptions o;
  o.clip = "wave";
  o.frameCount = 6;
  auto seq = synth::SyntheticSequence::create(o);
  ASSERT_TRUE(seq.ok());
  std::uint64_t winners[2] = {0, 0};
  for (const bool keep : {true, false}) {
    std::uint64_t hashes[3];
    const int threads[3] = {1, 1, 3};
    for (int run = 0; run < 3; ++run) {
      TrackerSettings settings;
      settings.threads = threads[run];
      settings.keepCandidates = keep;
      auto tracker = Tracker::create(seq->model(0), seq->intrinsics(), settings);
      ASSERT_TRUE(tracker.ok());
      Fnv1a h, winner;
      int candidates = 0;
      for (int f = 0; f < 6; ++f) {
        const auto& frame = seq->frame(f);
        if (f == 0) (*tracker)->initialize(frame.hands[0].pose);
        const HandResult& hand = (*tracker)->track(frame.depth).hands[0];
        for (const Pose& p : hand.pose.bodies) winner.add(p);
        winner.add(hand.error);
        winner.add(hand.quality.dataNearModel);
        winner.add(hand.quality.modelOnHand);
        for (const Candidate& c : hand.candidates) {
          h.add(c.error);
          for (const Pose& p : c.pose.bodies) h.add(p);
          candidates += c.ran ? 1 : 0;
        }
      }
      EXPECT_GE(candidates, 6 * 4) << "most simulations ran";
      h.add(winner.value());
      hashes[run] = h.value();
      winners[keep ? 0 : 1] = winner.value();
    }
    EXPECT_EQ(hashes[0], hashes[1]);
    EXPECT_EQ(hashes[0], hashes[2]) << "three threads give other bits than one";
  }
  EXPECT_EQ(winners[0], winners[1]) << "keeping the candidates changed the tracking";
}

// Both hands of the two-hands clip (right opening and closing, left waving) and of
// hands-touching (thumbs touching: one connected surface, the right hand closing into a fist),
// acquired automatically, each tracked by the model of its side: seen by a camera facing the
// user, and by one worn on the head (the user's left hand then on the image's left,
// split.placement). Touching hands need each detector crop to leave the other hand out, else
// the network reads the other hand's fingers as its own and the closing hand is lost.
TEST(Tracker, TwoHandsTrackedFromTheDeskAndFromTheHead) {
  for (const auto& [clip, head] :
       {std::pair{"two-hands", false}, std::pair{"two-hands", true},
        std::pair{"hands-touching", false}, std::pair{"hands-touching", true}}) {
    SCOPED_TRACE(std::string(clip) + (head ? " head-mounted" : " desk"));
    synth::SynthOptions o;
    o.clip = clip;
    o.profile = "tof";
    o.frameCount = 60;
    o.scene.placement =
        head ? synth::CameraPlacement::HeadMounted : synth::CameraPlacement::DeskFacing;
    auto seq = synth::SyntheticSequence::create(o);
    ASSERT_TRUE(seq.ok()) << seq.message();
    TrackerSettings settings;
    settings.hands = 2;
    if (head) settings.split.placement = CameraPlacement::kBehindUser;
    auto tracker = Tracker::create(seq->model(0), seq->intrinsics(), settings);
    ASSERT_TRUE(tracker.ok()) << tracker.message();
    double total[2] = {0, 0};
    int tracked[2] = {0, 0};
    for (int f = 0; f < o.frameCount; ++f) {
      const synth::SyntheticFrame& frame = seq->frame(f);
      const TrackResult& r = (*tracker)->track(frame.depth);
      ASSERT_EQ(r.hands.size(), 2u);
      for (std::size_t h = 0; h < 2; ++h) {
        if (!r.hands[h].tracked) continue;
        // hands[0] is the right hand, as the clip's hand 0.
        EXPECT_EQ(r.hands[h].side, h == 0 ? model::Side::Right : model::Side::Left);
        double err = 0;
        for (std::size_t k = 0; k < 21; ++k)
          err +=
              static_cast<double>((r.hands[h].keypoints21[k] - frame.hands[h].keypoints[k]).norm());
        total[h] += err / 21.0;
        ++tracked[h];
      }
    }
    for (int h = 0; h < 2; ++h) {
      const double meanMm = tracked[h] > 0 ? 1000.0 * total[h] / tracked[h] : 0.0;
      std::printf("%s, %s, hand %d: tracked %d/%d frames, mean 21-keypoint error %.1f mm\n", clip,
                  head ? "head-mounted" : "desk", h, tracked[h], o.frameCount, meanMm);
      EXPECT_GE(tracked[h], o.frameCount - 5);
      EXPECT_LT(meanMm, head ? 25.0 : 12.0);
    }
  }
}

TEST(Tracker, EmptyFramesMeanLostNotACrash) {
  synth::SynthOptions o;
  o.frameCount = 1;
  auto seq = synth::SyntheticSequence::create(o);
  ASSERT_TRUE(seq.ok());
  auto tracker = Tracker::create(seq->model(0), seq->intrinsics());
  ASSERT_TRUE(tracker.ok());
  (*tracker)->initialize(seq->frame(0).hands[0].pose);
  DepthFrame empty(seq->intrinsics().width, seq->intrinsics().height, 0.001f);
  const TrackResult& r = (*tracker)->track(empty);
  ASSERT_EQ(r.hands.size(), 1u);
  EXPECT_FALSE(r.hands[0].tracked);
  // The hand comes back: re-acquired from scratch without any call from us.
  const TrackResult& back = (*tracker)->track(seq->frame(0).depth);
  EXPECT_GT(back.hands[0].pointCount, 100);
}

// The segmentation ball grows with a longer hand model (so spread fingers of a large hand are
// not cut off at its edge); a shorter one keeps the reference hand's ball.
TEST(Tracker, SegmentationBallScalesWithALongerHand) {
  const Intrinsics k{320, 240, 300, 300, 160, 120};
  const float base = TrackerSettings{}.cloud.segmentation.handRadiusM;
  auto radius = [&](float length, bool scale) {
    TrackerSettings s;
    s.scaleSegmentationToHand = scale;
    auto tracker = Tracker::create(model::makeDefaultHand({length, 0.45f * length}), k, s);
    EXPECT_TRUE(tracker.ok());
    return (*tracker)->settings().cloud.segmentation.handRadiusM;
  };
  EXPECT_FLOAT_EQ(radius(0.19f, true), base);
  EXPECT_FLOAT_EQ(radius(0.165f, true), base);
  EXPECT_FLOAT_EQ(radius(0.228f, true), base * 1.2f);
  EXPECT_FLOAT_EQ(radius(0.228f, false), base);
}

TEST(Tracker, RejectsBadSettings) {
  const auto hand = model::makeDefaultHand();
  TrackerSettings s;
  s.hands = 3;
  EXPECT_FALSE(Tracker::create(hand, Intrinsics{320, 240, 300, 300, 160, 120}, s).ok());
  EXPECT_FALSE(Tracker::create(hand, Intrinsics{0, 240, 300, 300, 160, 120}).ok());
  TrackerSettings noThreads;
  noThreads.threads = 0;
  EXPECT_FALSE(Tracker::create(hand, Intrinsics{320, 240, 300, 300, 160, 120}, noThreads).ok());
  TrackerSettings noSubsets;
  noSubsets.pointSubsets = 0;  // every step would pull on no point
  EXPECT_FALSE(Tracker::create(hand, Intrinsics{320, 240, 300, 300, 160, 120}, noSubsets).ok());
  TrackerSettings noAcquisitionSweeps;
  noAcquisitionSweeps.acquisitionIterations = 0;
  EXPECT_FALSE(
      Tracker::create(hand, Intrinsics{320, 240, 300, 300, 160, 120}, noAcquisitionSweeps).ok());
  TrackerSettings negativeRelax;
  negativeRelax.relaxIterations = -1;
  EXPECT_FALSE(Tracker::create(hand, Intrinsics{320, 240, 300, 300, 160, 120}, negativeRelax).ok());
  TrackerSettings negativeAcquisitionRelax;
  negativeAcquisitionRelax.acquisitionRelaxIterations = -1;
  EXPECT_FALSE(
      Tracker::create(hand, Intrinsics{320, 240, 300, 300, 160, 120}, negativeAcquisitionRelax)
          .ok());
  TrackerSettings negativePalmCap;
  negativePalmCap.palmPointCap = -1;  // 0 means every point; below it nothing is meant
  EXPECT_FALSE(
      Tracker::create(hand, Intrinsics{320, 240, 300, 300, 160, 120}, negativePalmCap).ok());
  for (const float band : {-0.001f, std::numeric_limits<float>::quiet_NaN()}) {
    TrackerSettings badBand;
    badBand.boundaryBand = band;  // no boundary row would be made
    EXPECT_FALSE(Tracker::create(hand, Intrinsics{320, 240, 300, 300, 160, 120}, badBand).ok());
  }
  for (const float pull :
       {-1.0f, std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity()}) {
    TrackerSettings badPull;
    badPull.pullForce = pull;  // a negative cap: rows whose impulse range is empty
    EXPECT_FALSE(Tracker::create(hand, Intrinsics{320, 240, 300, 300, 160, 120}, badPull).ok());
    TrackerSettings badAcquisitionPull;
    badAcquisitionPull.acquisitionPullForce = pull;
    EXPECT_FALSE(
        Tracker::create(hand, Intrinsics{320, 240, 300, 300, 160, 120}, badAcquisitionPull).ok());
    TrackerSettings badRatio;
    badRatio.detector.replaceMaxErrorRatio = pull;  // no error is a NaN or infinite ratio of one
    EXPECT_FALSE(Tracker::create(hand, Intrinsics{320, 240, 300, 300, 160, 120}, badRatio).ok());
  }
  // The shifted detector crops: 0..4 of them, up to 5 cm off.
  for (const int crops : {-1, 5}) {
    TrackerSettings badCrops;
    badCrops.detector.shiftedCrops = crops;
    const auto tracker = Tracker::create(hand, Intrinsics{320, 240, 300, 300, 160, 120}, badCrops);
    ASSERT_FALSE(tracker.ok());
    EXPECT_NE(tracker.message().find("shiftedCrops"), std::string::npos) << tracker.message();
  }
  for (const float shift : {-0.001f, 0.06f, std::numeric_limits<float>::quiet_NaN()}) {
    TrackerSettings badShift;
    badShift.detector.shiftedCropM = shift;
    EXPECT_FALSE(Tracker::create(hand, Intrinsics{320, 240, 300, 300, 160, 120}, badShift).ok());
  }
}

}  // namespace
}  // namespace dynahand::track
