// Scenario runner for the playground tests: a synthetic clip seen by the desk-facing (or the
// head-mounted) synthetic tof sensor, tracked by the tracker (initialised from the first frame's
// ground truth), drives the playground; `onFrame` sees the playground after every input frame.
// Set DYNAHAND_PLAYGROUND_TRUTH=1 to drive it by the ground truth instead (tuning only), and
// DYNAHAND_SCENARIO_SEED=N to render the clip with sensor noise seed N instead of 1 (a scenario
// run over several seeds gives its own).
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <cstdlib>
#include <functional>
#include <optional>
#include <string>

#include "dynahand/playground.h"
#include "dynahand/synth.h"
#include "dynahand/tracker.h"
#include "scene_files.h"

namespace dynahand::playground::test {

struct ScenarioStats {
  int frames = 0;
  int trackedFrames = 0;
  float meanKeypointErrorM = 0.0f;  // tracker vs ground truth, mean over frames and keypoints
};

// The scene camera that maps the clip seen by the head-mounted camera onto the same scene poses
// as `deskCamera` maps it seen by the desk camera: the synthesiser places the same motion at
// each placement's rest pose, so the two views differ by one rigid transform (the root body's
// pose at frame 0 in each).
inline Pose headMountedCamera(const Pose& deskCamera, const std::string& clip) {
  synth::SynthOptions o;
  o.clip = clip;
  o.frameCount = 1;
  auto desk = synth::SyntheticSequence::create(o);
  o.scene.placement = synth::CameraPlacement::HeadMounted;
  auto head = synth::SyntheticSequence::create(o);
  EXPECT_TRUE(desk.ok() && head.ok());
  if (!desk || !head) return deskCamera;
  const Pose rootDesk = desk->truth(0, 0).pose.bodies.front();
  const Pose rootHead = head->truth(0, 0).pose.bodies.front();
  return deskCamera * rootDesk * rootHead.inverse();
}

inline ScenarioStats runScenario(
    Playground& pg, const std::string& clip, int frames,
    const std::function<void(int, const Playground&)>& onFrame,
    synth::CameraPlacement placement = synth::CameraPlacement::DeskFacing,
    std::optional<std::uint64_t> seed = std::nullopt) {
  synth::SynthOptions o;
  o.clip = clip;
  o.profile = "tof";
  o.frameCount = frames;
  o.scene.placement = placement;
  // The synthetic sensor's noise seed (default 1): DYNAHAND_SCENARIO_SEED=N reruns a scenario on
  // other noise, to see how far its outcome rests on one draw.
  if (const char* env = std::getenv("DYNAHAND_SCENARIO_SEED"))
    o.seed = std::strtoull(env, nullptr, 10);
  if (seed) o.seed = *seed;
  auto seq = synth::SyntheticSequence::create(o);
  EXPECT_TRUE(seq.ok()) << (seq.ok() ? "" : seq.message());
  ScenarioStats stats;
  if (!seq) return stats;
  const bool truthOnly = std::getenv("DYNAHAND_PLAYGROUND_TRUTH") != nullptr;
  auto tracker = track::Tracker::create(seq->model(0), seq->intrinsics());
  EXPECT_TRUE(tracker.ok());
  if (!tracker) return stats;
  (*tracker)->initialize(seq->truth(0, 0).pose);
  pg.setCameraIntrinsics(seq->intrinsics());
  const float dt = 1.0f / o.framesPerSecond;
  double errorSum = 0.0;
  for (int i = 0; i < frames; ++i) {
    const synth::SyntheticFrame& frame = seq->frame(i);
    std::optional<model::ModelPose> pose;
    if (truthOnly) {
      pose = frame.hands[0].pose;
    } else {
      const track::TrackResult& r = (*tracker)->track(frame.depth);
      if (!r.hands.empty() && r.hands[0].tracked) {
        pose = r.hands[0].pose;
        ++stats.trackedFrames;
        float e = 0.0f;
        for (std::size_t k = 0; k < 21; ++k)
          e += (r.hands[0].keypoints21[k] - frame.hands[0].keypoints[k]).norm();
        errorSum += static_cast<double>(e / 21.0f);
      }
    }
    if (i == 0 && pose) pg.placeHand(*pose);
    pg.step(pose, dt);
    onFrame(i, pg);
    ++stats.frames;
  }
  if (stats.trackedFrames > 0)
    stats.meanKeypointErrorM = static_cast<float>(errorSum / stats.trackedFrames);
  return stats;
}

}  // namespace dynahand::playground::test
