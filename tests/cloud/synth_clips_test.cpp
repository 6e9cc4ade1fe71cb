// The pipeline on rendered clips (synth module) with sensor noise: on every frame the
// segmented cloud must be the hand (and forearm), hand-sized, never nothing or a fragment.
// Regression: wrist-flex-roll (tof) frame 18, fingers pointing at the camera split into
// fragments a few cm in front of each other, gave no points at all, and frames 19-23 only
// the forearm.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "dynahand/cloud.h"
#include "dynahand/hand_split.h"
#include "dynahand/synth.h"
#include "dynahand/synth_render.h"
#include "synth_support.h"
#include "test_support.h"

namespace dynahand {
namespace {

struct FrameCheck {
  int frame = 0;
  std::size_t points = 0;
  float reachCoverage = 0.0f;  // segmented share of the hand's pixels within the hand radius
  float offHandShare = 0.0f;   // segmented pixels with depth not on the hand or forearm
  float extentXY = 0.0f;       // largest image-plane extent of the cloud, m
};

// Runs the pipeline on frames first, first + every, ... of a clip and measures each result
// against the renderer's pixel labels.
std::vector<FrameCheck> runClip(const std::string& clip, const std::string& profile, int every) {
  constexpr int kFrames = 90;
  synth::SynthOptions options;
  options.clip = clip;
  options.profile = profile;
  options.frameCount = kFrames;
  Result<synth::SyntheticSequence> seq = synth::SyntheticSequence::create(options);
  EXPECT_TRUE(seq.ok()) << seq.error().message;
  if (!seq.ok()) return {};
  const Intrinsics k = seq->intrinsics();
  CloudPipeline pipeline(k);
  const float radius = pipeline.config().segmentation.handRadiusM;
  CloudFrame out;
  std::vector<FrameCheck> checks;
  for (int i = 0; i < kFrames; i += every) {
    const DepthFrame& depth = seq->frame(i).depth;
    EXPECT_TRUE(pipeline.process(depth, out).ok());
    const std::span<const synth::PixelLabel> labels = seq->labels();
    const auto onHand = [&](std::size_t p) { return labels[p] == synth::PixelLabel::Hand0; };
    // The hand's nearest measured point: what the segmentation's ball should start from.
    Vec3 nearest(0.0f, 0.0f, 1e9f);
    for (int v = 0; v < k.height; ++v) {
      for (int u = 0; u < k.width; ++u) {
        const std::size_t p = static_cast<std::size_t>(v) * k.width + u;
        const float z = depth.metres(u, v);
        if (z > 0.0f && onHand(p) && z < nearest.z()) nearest = k.deproject(u, v, z);
      }
    }
    int reach = 0, reachSegmented = 0, segmented = 0, offHand = 0;
    for (int v = 0; v < k.height; ++v) {
      for (int u = 0; u < k.width; ++u) {
        const std::size_t p = static_cast<std::size_t>(v) * k.width + u;
        const bool masked = out.mask[p] != 0;
        const float z = depth.metres(u, v);
        if (z == 0.0f) continue;  // mask blocks (stride x stride) overhang the silhouette
        segmented += masked;
        if (masked && !onHand(p)) ++offHand;
        if (z > 0.0f && onHand(p) && (k.deproject(u, v, z) - nearest).norm() <= radius) {
          ++reach;
          reachSegmented += masked;
        }
      }
    }
    FrameCheck c;
    c.frame = i;
    c.points = out.pointCount();
    c.reachCoverage = reach > 0 ? static_cast<float>(reachSegmented) / reach : 0.0f;
    c.offHandShare = segmented > 0 ? static_cast<float>(offHand) / segmented : 1.0f;
    if (!out.points.empty()) {
      Vec3 lo = out.points.front(), hi = out.points.front();
      for (const Vec3& q : out.points) {
        lo = lo.cwiseMin(q);
        hi = hi.cwiseMax(q);
      }
      c.extentXY = (hi - lo).head<2>().maxCoeff();
    }
    checks.push_back(c);
  }
  return checks;
}

// Hand-sized on every frame: found, on the hand, covering most of the hand within the
// segmentation radius, and no larger than the radius allows.
void expectHandOnEveryFrame(const std::string& clip, const std::string& profile, int every,
                            float minReachCoverage) {
  SCOPED_TRACE(profile + " " + clip);
  const std::vector<FrameCheck> checks = runClip(clip, profile, every);
  ASSERT_FALSE(checks.empty());
  std::vector<std::size_t> counts;
  for (const FrameCheck& c : checks) counts.push_back(c.points);
  std::nth_element(counts.begin(), counts.begin() + counts.size() / 2, counts.end());
  const std::size_t median = counts[counts.size() / 2];
  const float radius = CloudConfig{}.segmentation.handRadiusM;
  for (const FrameCheck& c : checks) {
    SCOPED_TRACE("frame " + std::to_string(c.frame));
    // A hand seen end-on (fingers toward the camera) shows about a third of its face-on
    // area; a fragment (a fingertip) or nothing at all is far below.
    EXPECT_GE(c.points, median * 3 / 10);
    EXPECT_GE(c.reachCoverage, minReachCoverage);
    EXPECT_LE(c.offHandShare, 0.01f);
    EXPECT_GT(c.extentXY, 0.06f);
    EXPECT_LE(c.extentXY, 2.0f * radius);
  }
}

const char* const kClips[] = {"wave",          "open-close",      "count",
                              "pinch",         "wrist-flex-roll", "fast-translation",
                              "grasp-cylinder"};

TEST(CloudSynthClips, WristFlexRollTofFindsTheHandOnEveryFrame) {
  expectHandOnEveryFrame("wrist-flex-roll", "tof", 1, 0.6f);
}

TEST(CloudSynthClips, EveryClipTofFindsTheHandOnEveryFrame) {
  for (const char* clip : kClips) expectHandOnEveryFrame(clip, "tof", 1, 0.6f);
}

TEST(CloudSynthClips, EveryClipStructuredLightFindsTheHand) {
  // 640x480 frames render slower: every 6th frame keeps the test short. Frames 20-21 of
  // wrist-flex-roll are a known limit here (docs/cloud.md) and not among them.
  for (const char* clip : kClips) expectHandOnEveryFrame(clip, "structured-light", 6, 0.6f);
}

// Shares of the frames checked where the segment holds the palm, where a limb end is found,
// and where that end lies on the hand.
struct HeadViewShares {
  int frames = 0;
  double palmSegmented = 0.0;
  double endFound = 0.0;
  double endOnHand = 0.0;  // of the frames with an end found
};

// Frames 0, every, 2 every, ... of a head-mounted sequence through a pipeline configured with
// the sensor's near range: the segment must hold the hand (its palm), not only the forearm
// around the nearest point, and the limb's free end must lie on the hand (the tracker centres
// the detector's crop there).
HeadViewShares checkHeadView(synth::SyntheticSequence& seq, int every, float sensorMinRangeM,
                             bool supportPlanes = true) {
  CloudConfig config;
  config.segmentation.sensorMinRangeM = sensorMinRangeM;
  config.segmentation.supportPlanes.enabled = supportPlanes;
  CloudPipeline pipeline(seq.intrinsics(), config);
  CloudFrame out;
  // The palm's centre this near (m) to a segmented point is on the segment (the skin is 1-2 cm
  // from it).
  constexpr float kReachM = 0.03f;
  // A limb end this near (m) to the centre of the keypoints' box is on the hand (a fingertip
  // lies 8-10 cm from it).
  constexpr float kEndOnHandM = 0.10f;
  int frames = 0, onHand = 0, endFound = 0, endOnHand = 0;
  for (int i = 0; i < seq.frameCount(); i += every, ++frames) {
    const synth::SyntheticFrame& frame = seq.frame(i);
    EXPECT_TRUE(pipeline.process(frame.depth, out).ok());
    const Keypoints21& kp = frame.hands[0].keypoints;
    const Vec3 palm = (kp[0] + kp[5] + kp[9] + kp[13] + kp[17]) / 5.0f;
    const auto reached = [&](const Vec3& target) {
      for (const Vec3& p : out.points)
        if ((p - target).norm() < kReachM) return true;
      return false;
    };
    onHand += out.segment.found && reached(palm);
    if (out.segment.found && out.segment.limbEndFound) {
      ++endFound;
      Vec3 lo = kp[0], hi = kp[0];
      for (const Vec3& p : kp) {
        lo = lo.cwiseMin(p);
        hi = hi.cwiseMax(p);
      }
      endOnHand += (out.segment.limbEnd - (lo + hi) * 0.5f).norm() < kEndOnHandM;
    }
  }
  HeadViewShares shares;
  shares.frames = frames;
  if (frames == 0) return shares;
  shares.palmSegmented = static_cast<double>(onHand) / frames;
  shares.endFound = static_cast<double>(endFound) / frames;
  shares.endOnHand = endFound > 0 ? static_cast<double>(endOnHand) / endFound : 0.0;
  return shares;
}

// The original authors' captured motion seen from a head-mounted camera: the forearm comes from
// the image's bottom toward the camera, is often nearer than the hand and is cut off by the
// sensor's near range inside the image.
TEST(CloudSynthClips, AnimbankSeenFromTheHeadSegmentsTheHand) {
  DYNAHAND_REQUIRE_SHARED_DATA(data);
  synth::SynthOptions options;
  options.poseFile = data / "intel" / "animbank.pose";
  options.profile = "tof";
  options.frameCount = 2336;
  options.scene.placement = synth::CameraPlacement::HeadMounted;
  Result<synth::SyntheticSequence> seq = synth::SyntheticSequence::create(options);
  ASSERT_TRUE(seq.ok()) << seq.error().message;
  const HeadViewShares s = checkHeadView(*seq, 8, seq->profile().minRange);
  std::printf(
      "animbank head tof: palm segmented on %.1f%% of %d frames; limb end found on %.1f%%, "
      "on the hand on %.1f%% of those\n",
      100.0 * s.palmSegmented, s.frames, 100.0 * s.endFound, 100.0 * s.endOnHand);
  EXPECT_GE(s.palmSegmented, 0.95);
  EXPECT_GE(s.endFound, 0.95);
  EXPECT_GE(s.endOnHand, 0.95);
}

// animbank.pose frames 600-699 from the desk with a table 8 cm below the rest wrist: the
// forearm rises out of the table toward the camera, nearer than the hand. With the table left
// out, the forearm's only attachment is where it meets the table, and the hand is its other end
// (with no attachment at all, the nearest point, on the forearm, would be taken for the hand).
TEST(CloudSynthClips, AForearmRisingFromATableEndsAtTheHand) {
  DYNAHAND_REQUIRE_SHARED_DATA(data);
  synth::SynthOptions options;
  options.poseFile = data / "intel" / "animbank.pose";
  options.poseStart = 600;
  options.profile = "tof";
  options.frameCount = 100;
  options.scene.table = true;
  options.scene.tableDrop = 0.08f;
  Result<synth::SyntheticSequence> seq = synth::SyntheticSequence::create(options);
  ASSERT_TRUE(seq.ok()) << seq.error().message;
  const HeadViewShares s = checkHeadView(*seq, 2, seq->profile().minRange);
  const HeadViewShares without = checkHeadView(*seq, 2, seq->profile().minRange, false);
  std::printf(
      "animbank 600-699 desk tof, table: palm segmented on %.1f%% of %d frames (%.1f%% "
      "without support planes), limb end found on %.1f%% (%.1f%%) and on the hand on "
      "%.1f%% (%.1f%%) of those\n",
      100.0 * s.palmSegmented, s.frames, 100.0 * without.palmSegmented, 100.0 * s.endFound,
      100.0 * without.endFound, 100.0 * s.endOnHand, 100.0 * without.endOnHand);
  EXPECT_GE(s.endFound, 0.95);
  EXPECT_GE(s.endOnHand, 0.95);
  // The palm's centre lies more than 3 cm from every sample seen when the hand turns its edge
  // to the camera: about one frame in seven here, with the table left out or not.
  EXPECT_GE(s.palmSegmented, 0.8);
}

// A structured-light camera measures nothing nearer than 0.5 m: worn on the head, it sees the
// forearm from that cut up to the hand 0.7 m away, longer than the limb search's ball. Told its
// near range, the pipeline takes the cut as the forearm's attached end and finds the hand at the
// other; with a near range of 0.2 m (a time-of-flight camera's) the cut at 0.5 m is not one,
// the fingers leaving the ball are taken for the attachment and the segment is the forearm.
// (wrist-flex-roll is left out: on 3 of its 10 frames checked here the palm's centre lies more
// than 3 cm from every segmented point even when told.)
TEST(CloudSynthClips, StructuredLightHeadMountedFindsTheHandAtTheArmsFarEnd) {
  for (const char* clip : {"wave", "count", "open-close", "pinch", "grasp-cylinder", "point"}) {
    SCOPED_TRACE(clip);
    synth::SynthOptions options;
    options.clip = clip;
    options.profile = "structured-light";
    options.frameCount = 60;
    options.scene.placement = synth::CameraPlacement::HeadMounted;
    Result<synth::SyntheticSequence> seq = synth::SyntheticSequence::create(options);
    ASSERT_TRUE(seq.ok()) << seq.error().message;
    const HeadViewShares told = checkHeadView(*seq, 6, seq->profile().minRange);
    EXPECT_GE(told.palmSegmented, 0.9);
    EXPECT_GE(told.endOnHand, 0.9);
    const HeadViewShares untold = checkHeadView(*seq, 6, 0.20f);
    std::printf(
        "%s structured-light head: palm segmented on %.0f%% of %d frames told the near range, "
        "%.0f%% not told\n",
        clip, 100.0 * told.palmSegmented, told.frames, 100.0 * untold.palmSegmented);
    EXPECT_LT(untold.palmSegmented, 0.5);
  }
}

// Over frames 0, every, 2 every, ... of a sequence: the share of frames whose segment holds
// the palm, and the share of the segmented pixels (with depth) that show something other than
// the hand and its forearm.
struct SceneShares {
  double palmSegmented = 0.0;
  double offHand = 0.0;
};

SceneShares checkScene(synth::SyntheticSequence& seq, int every, bool supportPlanes) {
  CloudConfig config;
  config.segmentation.sensorMinRangeM = seq.profile().minRange;
  config.segmentation.supportPlanes.enabled = supportPlanes;
  CloudPipeline pipeline(seq.intrinsics(), config);
  CloudFrame out;
  constexpr float kReachM = 0.03f;  // as checkHeadView
  long segmented = 0, offHand = 0;
  int frames = 0, palms = 0;
  for (int i = 0; i < seq.frameCount(); i += every, ++frames) {
    const synth::SyntheticFrame& frame = seq.frame(i);
    EXPECT_TRUE(pipeline.process(frame.depth, out).ok());
    const std::span<const synth::PixelLabel> labels = seq.labels();
    const Keypoints21& kp = frame.hands[0].keypoints;
    const Vec3 palm = (kp[0] + kp[5] + kp[9] + kp[13] + kp[17]) / 5.0f;
    bool reached = false;
    for (const Vec3& p : out.points) reached = reached || (p - palm).norm() < kReachM;
    palms += out.segment.found && reached;
    for (std::size_t p = 0; p < labels.size(); ++p) {
      if (out.mask[p] == 0 || frame.depth.depth[p] == 0) continue;
      ++segmented;
      offHand += labels[p] != synth::PixelLabel::Hand0;
    }
  }
  SceneShares shares;
  if (frames > 0) shares.palmSegmented = static_cast<double>(palms) / frames;
  if (segmented > 0) shares.offHand = static_cast<double>(offHand) / static_cast<double>(segmented);
  return shares;
}

// A hand reaching to a table 4 or 8 cm below its wrist, seen from the desk and from the head:
// the table is one surface with the hand where they meet, and without the support planes a
// third to three quarters of the segment is table (the forearm's ball grows over it). With
// them the table is left out and the palm stays in the segment.
TEST(CloudSynthClips, ATableUnderTheHandStaysOutOfTheSegment) {
  for (const auto placement :
       {synth::CameraPlacement::DeskFacing, synth::CameraPlacement::HeadMounted}) {
    for (const char* clip : {"wave", "open-close", "count", "reach-grasp-lift", "grasp-cylinder"}) {
      for (const float drop : {0.08f, 0.04f}) {
        SCOPED_TRACE(std::string(clip) +
                     (placement == synth::CameraPlacement::DeskFacing ? " desk" : " head-mounted") +
                     " table " + std::to_string(drop) + " m below the wrist");
        synth::SynthOptions options;
        options.clip = clip;
        options.profile = "tof";
        options.frameCount = 90;
        options.scene.placement = placement;
        options.scene.table = true;
        options.scene.tableDrop = drop;
        Result<synth::SyntheticSequence> seq = synth::SyntheticSequence::create(options);
        ASSERT_TRUE(seq.ok()) << seq.error().message;
        const SceneShares with = checkScene(*seq, 3, true);
        EXPECT_GE(with.palmSegmented, 0.95);
        EXPECT_LE(with.offHand, 0.05);
        if (drop < 0.05f) {
          const SceneShares without = checkScene(*seq, 3, false);
          EXPECT_GE(without.offHand, 0.3) << "the table should flood the segment without planes";
        }
      }
    }
  }
}

// Two hands side by side with their thumbs touching (the hands-touching clip: one connected
// surface), seen from the desk and from the head, split as the tracker splits them with two
// hands (the second region searched 0.2 m deep, k-means): both hands found in every frame, each
// cluster's points on its own hand. The centroids are 10-14 cm apart, no farther than a hand's
// from its own forearm's, so distance alone merged them into one hand.
TEST(CloudSynthClips, TwoTouchingHandsAreSplitIntoTheirOwnPoints) {
  for (const bool head : {false, true}) {
    SCOPED_TRACE(head ? "head-mounted" : "desk");
    synth::SynthOptions options;
    options.clip = "hands-touching";
    options.profile = "tof";
    options.frameCount = 60;
    options.scene.placement =
        head ? synth::CameraPlacement::HeadMounted : synth::CameraPlacement::DeskFacing;
    Result<synth::SyntheticSequence> seq = synth::SyntheticSequence::create(options);
    ASSERT_TRUE(seq.ok()) << seq.error().message;
    CloudConfig config;
    config.segmentation.sensorMinRangeM = seq->profile().minRange;
    config.segmentation.secondRegionDepthBandM = 0.2f;  // as the tracker with two hands
    CloudPipeline pipeline(seq->intrinsics(), config);
    HandSplitConfig splitConfig;
    splitConfig.placement = head ? CameraPlacement::kBehindUser : CameraPlacement::kFacingUser;
    HandSplitter splitter(splitConfig);
    CloudFrame out;
    HandSplit split;
    int bothFound = 0;
    long own = 0, all = 0;
    for (int i = 0; i < seq->frameCount(); ++i) {
      const synth::SyntheticFrame& frame = seq->frame(i);
      ASSERT_TRUE(pipeline.process(frame.depth, out).ok());
      splitter.split(out.points, split);
      bothFound += split.handCount == 2;
      if (split.handCount != 2) continue;
      const std::span<const synth::PixelLabel> labels = seq->labels();
      for (std::size_t p = 0; p < out.points.size(); ++p) {
        // The clip's hand 0 is the right hand, hand 1 the left.
        const synth::PixelLabel label = labels[static_cast<std::size_t>(out.pointPixels[p])];
        const synth::PixelLabel expected =
            split.label[p] == Hand::kRight ? synth::PixelLabel::Hand0 : synth::PixelLabel::Hand1;
        own += label == expected;
        ++all;
      }
    }
    EXPECT_GE(bothFound, seq->frameCount() - 2);
    ASSERT_GT(all, 0);
    EXPECT_GE(static_cast<double>(own) / static_cast<double>(all), 0.9);
  }
}

// A hand whose fingers go on out of view past the image's top edge, seen from the head and from
// the desk with the forearm entering from the bottom: the limb touches the image at both ends.
// It is attached where it enters lowest (the body is below the view), so the hand's visible
// part, up to the top edge, is segmented. With every border contact an attachment, the limb's
// free end lay between them on the forearm and the fingers were cut off.
TEST(CloudSynthClips, FingersGoingOutOfViewAtTheTopStayInTheSegment) {
  for (const auto placement :
       {synth::CameraPlacement::HeadMounted, synth::CameraPlacement::DeskFacing}) {
    synth::SynthOptions options;
    options.clip = "wave";
    options.profile = "tof";
    options.frameCount = 30;
    options.scene.placement = placement;
    // The image's top edge between the knuckles and the fingertips (the desk's hand is upright).
    options.scene.viewShift =
        Vec2(0.0f, placement == synth::CameraPlacement::HeadMounted ? -115.0f : -75.0f);
    Result<synth::SyntheticSequence> seq = synth::SyntheticSequence::create(options);
    ASSERT_TRUE(seq.ok()) << seq.error().message;
    const Intrinsics& k = seq->intrinsics();
    CloudPipeline pipeline(k);
    CloudFrame out;
    int frames = 0, kept = 0;
    for (int f = 0; f < options.frameCount; f += 3, ++frames) {
      const synth::SyntheticFrame& frame = seq->frame(f);
      ASSERT_TRUE(pipeline.process(frame.depth, out).ok());
      // The knuckles in view must each have segmented points within 2 cm.
      bool all = true;
      int inView = 0;
      for (int j : {5, 9, 13, 17}) {
        const Vec3& knuckle = frame.hands[0].keypoints[static_cast<std::size_t>(j)];
        const Vec2 uv = k.project(knuckle);
        if (uv.x() < 0.0f || uv.y() < 0.0f || uv.x() > static_cast<float>(k.width - 1) ||
            uv.y() > static_cast<float>(k.height - 1))
          continue;
        ++inView;
        bool near = false;
        for (const Vec3& p : out.points) near = near || (p - knuckle).norm() < 0.02f;
        all = all && near;
      }
      EXPECT_GE(inView, 2) << "frame " << f << ": the knuckles go out of view as well";
      kept += all;
    }
    const char* name = placement == synth::CameraPlacement::HeadMounted ? "head" : "desk";
    std::printf("%s: the knuckles in view segmented on %d of %d frames\n", name, kept, frames);
    EXPECT_EQ(kept, frames) << name;
  }
}

// The mean of hand 0's 21 keypoints in `frame`.
Vec3 handCentre(const synth::SyntheticFrame& frame) {
  Vec3 centre = Vec3::Zero();
  for (const Vec3& p : frame.hands[0].keypoints) centre += p;
  return centre / 21.0f;
}

// Share of the segmented points within radiusM (m) of centre; 0 when there are none.
float shareOfPointsWithin(const CloudFrame& out, const Vec3& centre, float radiusM) {
  if (out.points.empty()) return 0.0f;
  int near = 0;
  for (const Vec3& p : out.points) near += (p - centre).norm() <= radiusM;
  return static_cast<float>(near) / static_cast<float>(out.points.size());
}

// animbank.pose around frame 1390 from the desk on active-stereo: the arm bent at the elbow, a
// fist at the forearm's end, and the elbow nearer to the camera than the fist. The nearest
// volume is the elbow, and the limb search's ball around it ends in the upper arm on one side
// and the forearm on the other. The limb is attached at the lower of the two in the image (the
// body is below the view), and its free end is the fist, which the segment holds. Told where the
// tracker had the hand (HandHint), the pipeline keeps to it as well.
TEST(CloudSynthClips, AnElbowNearerThanTheTrackedFistIsNotTakenForTheHand) {
  DYNAHAND_REQUIRE_SHARED_DATA(data);
  synth::SynthOptions options = test::animbankOptions(data, 1386, 12, "active-stereo");
  options.proportions = synth::randomProportions(1, 0.15f);
  Result<synth::SyntheticSequence> seq = synth::SyntheticSequence::create(options);
  ASSERT_TRUE(seq.ok()) << seq.error().message;
  CloudPipeline pipeline(seq->intrinsics());
  CloudFrame out;
  int elbowTaken = 0;
  for (int f = 0; f < options.frameCount; ++f) {
    const synth::SyntheticFrame& frame = seq->frame(f);
    const Vec3 centre = handCentre(frame);
    ASSERT_TRUE(pipeline.process(frame.depth, out).ok());
    const float nearest = shareOfPointsWithin(out, centre, 0.12f);
    // The hint a tracker would give: last frame's hand, here its truth 1 cm off.
    const HandHint hint{centre + Vec3(0.01f, 0.0f, 0.0f)};
    ASSERT_TRUE(pipeline.process(frame.depth, out, &hint).ok());
    const float hinted = shareOfPointsWithin(out, centre, 0.12f);
    std::printf("frame %d: %.0f%% of the points on the hand nearest-first, %.0f%% hinted\n",
                1386 + f, 100.0 * static_cast<double>(nearest),
                100.0 * static_cast<double>(hinted));
    // The rest of a segment is forearm (about a third here when the fist is taken).
    EXPECT_GE(hinted, 0.4f) << "frame " << 1386 + f;
    if (nearest >= 0.4f) {
      EXPECT_EQ(hinted, nearest) << "frame " << 1386 + f;  // no change where it is right
    }
    elbowTaken += nearest < 0.1f;
  }
  // Nearest-first the limb is explored from the elbow too; it is attached at its lowest
  // border contact (the upper arm), so its free end is the fist: the elbow is not taken.
  EXPECT_EQ(elbowTaken, 0);
}

// animbank.pose (played whole: the head-mounted camera is placed for the motion played) from a
// head-mounted camera, on a hand shaped unlike the model; frames first..last every step through
// the pipeline, hinted with the true palm centre (where a tracker has it), each handed to visit.
void forEachHeadMountedAnimbankFrame(
    const std::filesystem::path& data, int first, int last, int step,
    const std::function<void(int, const synth::SyntheticFrame&, const CloudFrame&,
                             const Intrinsics&)>& visit) {
  synth::SynthOptions options = test::animbankOptions(data, 0, 2336, "tof");
  options.scene.placement = synth::CameraPlacement::HeadMounted;
  options.proportions = synth::randomProportions(3, 0.15f);
  Result<synth::SyntheticSequence> seq = synth::SyntheticSequence::create(options);
  ASSERT_TRUE(seq.ok()) << seq.error().message;
  CloudPipeline pipeline(seq->intrinsics());
  CloudFrame out;
  for (int f = first; f <= last; f += step) {
    const synth::SyntheticFrame& frame = seq->frame(f);
    Vec3 palm = Vec3::Zero();
    for (const int j : {0, 5, 9, 13, 17})
      palm += frame.hands[0].keypoints[static_cast<std::size_t>(j)];
    const HandHint hint{palm / 5.0f};
    ASSERT_TRUE(pipeline.process(frame.depth, out, &hint).ok());
    visit(f, frame, out, seq->intrinsics());
  }
}

enum class JointView { OffImage, Hidden, Segmented, LeftOut };

// Whether joint p projects into the image (with a pixel to spare), whether the camera sees it
// (the depth at its pixel is the joint's, not a surface in front of it) and, if so, whether the
// segment holds its pixel or a neighbour.
JointView jointView(const CloudFrame& out, const Intrinsics& k, const Vec3& p) {
  const Vec2 uv = k.project(p);
  const int u = static_cast<int>(std::lround(uv.x()));
  const int v = static_cast<int>(std::lround(uv.y()));
  if (!(u >= 1 && v >= 1 && u + 1 < k.width && v + 1 < k.height)) return JointView::OffImage;
  if (!(std::fabs(out.depthAt(u, v) - p.z()) < 0.02f)) return JointView::Hidden;
  for (int dv = -1; dv <= 1; ++dv)
    for (int du = -1; du <= 1; ++du)
      if (out.mask[static_cast<std::size_t>((v + dv) * k.width + u + du)] != 0)
        return JointView::Segmented;
  return JointView::LeftOut;
}

// animbank.pose frames 840-881 seen from a head-mounted camera, on a hand shaped unlike the
// model: the thumb points away from the camera, the hand in front of it hides most of it, and
// its tip shows past the hand, more than 6 cm deeper than the hand's surface beside it. The
// segment takes the tip as part of the hand (a surface up to kMaxHiddenFingerStepM behind the
// region, src/cloud/region_grow.cpp): left out, neither the detector's crop nor the surface
// constraints would see it.
TEST(CloudSynthClips, AThumbPointingAwayIsSegmentedPastTheHandThatHidesIt) {
  DYNAHAND_REQUIRE_SHARED_DATA(data);
  int visible = 0;
  int segmented = 0;
  constexpr int kFirst = 840, kCount = 42;
  forEachHeadMountedAnimbankFrame(
      data, kFirst, kFirst + kCount - 1, 3,
      [&](int, const synth::SyntheticFrame& frame, const CloudFrame& out, const Intrinsics& k) {
        const JointView tip = jointView(out, k, frame.hands[0].keypoints[4]);  // the thumb's
        EXPECT_NE(tip, JointView::OffImage);
        visible += tip == JointView::Segmented || tip == JointView::LeftOut;
        segmented += tip == JointView::Segmented;
      });
  if (HasFatalFailure()) return;
  std::printf("thumb tip seen on %d of %d frames, segmented on %d of those\n", visible,
              (kCount + 2) / 3, segmented);
  ASSERT_GE(visible, 10);
  EXPECT_GE(segmented, visible * 8 / 10);
}

// animbank.pose frames 2224-2260 seen from a head-mounted camera, on a hand shaped unlike the
// model: the forearm points at the camera and the limb's free end lies 16-18 cm from the
// nearest sample, just inside the hand-sized ball around it, while the thumb and the index
// finger reach 19-21 cm. The ball moves toward the free end whenever it holds the end with less
// than a quarter radius to spare (kEndInsideBall, src/cloud/cloud_pipeline.cpp), so every joint
// the camera sees is in the segment.
TEST(CloudSynthClips, FingersReachingPastTheLimbsFreeEndAreSegmented) {
  DYNAHAND_REQUIRE_SHARED_DATA(data);
  int visible = 0;
  int leftOut = 0;
  forEachHeadMountedAnimbankFrame(
      data, 2224, 2260, 4,
      [&](int f, const synth::SyntheticFrame& frame, const CloudFrame& out, const Intrinsics& k) {
        for (std::size_t j = 0; j < frame.hands[0].keypoints.size(); ++j) {
          const JointView view = jointView(out, k, frame.hands[0].keypoints[j]);
          visible += view == JointView::Segmented || view == JointView::LeftOut;
          if (view == JointView::LeftOut) {
            ++leftOut;
            std::printf("frame %d: joint %zu seen but not segmented\n", f, j);
          }
        }
      });
  if (HasFatalFailure()) return;
  std::printf("%d joints seen over 10 frames, %d of them not segmented\n", visible, leftOut);
  ASSERT_GE(visible, 50);
  EXPECT_EQ(leftOut, 0);
}

// animbank.pose frames 1380-1390 seen from a head-mounted camera, on a hand shaped unlike the
// model: the forearm rises from the sensor's near range at the image bottom to a fist 50-55 cm
// away, the back of the hand turned steeply from the camera. On 1384-1385 the surface breaks at
// the wrist (neighbouring samples more than the step rule apart), so the limb search ends at
// the break, 13-15 cm in front of the hand and within a hand radius of its centre, and the
// segment is forearm only (0-3 % of its points within 12 cm of the hand's centre). Told where
// the tracker has the hand (HandHint), the pipeline keeps to it: the end lies that far in front
// of the hint while the hand's surface is still there, apart from the limb (kHintEndInFrontM,
// src/cloud/cloud_pipeline.cpp). Elsewhere a third or more of the points are the hand's, the
// rest the forearm seen along its length.
TEST(CloudSynthClips, AFistBehindASteepWristIsKeptWhenTheLimbEndsInFrontOfIt) {
  DYNAHAND_REQUIRE_SHARED_DATA(data);
  int frames = 0;
  int onForearm = 0;
  forEachHeadMountedAnimbankFrame(
      data, 1380, 1390, 1,
      [&](int f, const synth::SyntheticFrame& frame, const CloudFrame& out, const Intrinsics&) {
        const float share = shareOfPointsWithin(out, handCentre(frame), 0.12f);
        ++frames;
        if (share < 0.25f) {
          ++onForearm;
          std::printf("frame %d: %.0f%% of the points within 12 cm of the hand\n", f,
                      100.0 * static_cast<double>(share));
        }
      });
  if (HasFatalFailure()) return;
  std::printf("%d of %d frames segmented mostly off the hand\n", onForearm, frames);
  EXPECT_EQ(onForearm, 0);
}

}  // namespace
}  // namespace dynahand
