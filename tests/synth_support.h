// Test support for synthetic sequences: options for a built-in clip (the designated-
// initialiser form warns about every member left out), and how many of a frame's ground-truth
// keypoints land on the hand's own rendered pixels.
#pragma once

#include <cmath>
#include <filesystem>
#include <string>

#include "dynahand/synth.h"

namespace dynahand::test {

inline synth::SynthOptions clipOptions(const std::string& clip, const std::string& profile,
                                       int frames) {
  synth::SynthOptions o;
  o.clip = clip;
  o.profile = profile;
  o.frameCount = frames;
  return o;
}

// Frames [start, start + frames) of animbank.pose (in `data`, ../shared/data) on `profile`.
inline synth::SynthOptions animbankOptions(const std::filesystem::path& data, int start, int frames,
                                           const std::string& profile) {
  synth::SynthOptions o;
  o.poseFile = data / "intel" / "animbank.pose";
  o.poseStart = start;
  o.frameCount = frames;
  o.profile = profile;
  return o;
}

// Of hand 0's 21 keypoints in `frame` (the sequence's last rendered frame), those whose pixel
// is labelled Hand0.
inline int keypointsOnHandPixels(const synth::SyntheticSequence& seq,
                                 const synth::SyntheticFrame& frame) {
  const Intrinsics& k = seq.intrinsics();
  int inside = 0;
  for (const Vec3& p : frame.hands[0].keypoints) {
    const Vec2 uv = k.project(p);
    if (!k.contains(uv.x(), uv.y())) continue;
    const std::size_t i = static_cast<std::size_t>(std::lround(uv.y())) * k.width +
                          static_cast<std::size_t>(std::lround(uv.x()));
    inside += seq.labels()[i] == synth::PixelLabel::Hand0;
  }
  return inside;
}

}  // namespace dynahand::test
