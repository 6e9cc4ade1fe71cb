// The pipeline on rendered clips (synth module) with sensor noise: on every frame the
// segmented cloud must be the hand (and forearm), hand-sized, never nothing or a fragment.
// Regression: wrist-flex-roll (tof) frame 18, fingers pointing at the camera split into
// fragments a few cm in front of each other, gave no points at all, and frames 19-23 only
// the forearm.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

#include "dynahand/cloud.h"
#include "dynahand/synth.h"
#include "dynahand/synth_render.h"
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

// The original authors' captured motion seen from a head-mounted camera: the forearm comes from
// the image's bottom toward the camera, is often nearer than the hand and is cut off by the
// sensor's near range inside the image. The segment must hold the hand (its palm), not only
// the forearm around the nearest point, and the limb's free end must lie on the hand (the
// tracker centres the detector's crop there).
TEST(CloudSynthClips, AnimbankSeenFromTheHeadSegmentsTheHand) {
  DYNAHAND_REQUIRE_SHARED_DATA(data);
  synth::SynthOptions options;
  options.poseFile = data / "intel" / "animbank.pose";
  options.profile = "tof";
  options.frameCount = 2336;
  options.scene.placement = synth::CameraPlacement::HeadMounted;
  Result<synth::SyntheticSequence> seq = synth::SyntheticSequence::create(options);
  ASSERT_TRUE(seq.ok()) << seq.error().message;
  CloudPipeline pipeline(seq->intrinsics());
  CloudFrame out;
  // The palm's centre this near (m) to a segmented point is on the segment (the skin is 1-2 cm
  // from it).
  constexpr float kReachM = 0.03f;
  // A limb end this near (m) to the centre of the keypoints' box is on the hand (a fingertip
  // lies 8-10 cm from it).
  constexpr float kEndOnHandM = 0.10f;
  int frames = 0, onHand = 0, endFound = 0, endOnHand = 0;
  for (int i = 0; i < seq->frameCount(); i += 8, ++frames) {
    const synth::SyntheticFrame& frame = seq->frame(i);
    ASSERT_TRUE(pipeline.process(frame.depth, out).ok());
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

  const double share = static_cast<double>(onHand) / frames;
  const double endShare = static_cast<double>(endFound) / frames;
  const double endOnHandShare = endFound > 0 ? static_cast<double>(endOnHand) / endFound : 0.0;
  std::printf(
      "animbank head tof: palm segmented on %.1f%% of %d frames; limb end found on %.1f%%, "
      "on the hand on %.1f%% of those\n",
      100.0 * share, frames, 100.0 * endShare, 100.0 * endOnHandShare);
  EXPECT_GE(share, 0.95);
  EXPECT_GE(endShare, 0.95);
  EXPECT_GE(endOnHandShare, 0.95);
}

}  // namespace
}  // namespace dynahand
