// Internal: the clip library's keyframe representation and per-frame sampling without
// name lookups or allocation (after the first call per output buffer).
#pragma once

#include <array>
#include <string>
#include <vector>

#include "dynahand/synth.h"

namespace dynahand::synth::detail {

inline constexpr int kJointCount = 16;  // joints of makeDefaultHand

// A hand shape: per joint (flexion, abduction, twist), degrees.
struct Shape {
  Shape() { joints.fill(Vec3::Zero()); }  // Eigen vectors are not zeroed by {}
  std::array<Vec3, kJointCount> joints;
};

struct Key {
  float time = 0.0f;  // s
  Shape shape;
  Vec3 offset = Vec3::Zero();    // m, along the forearm frame's axes (x radial, y dorsal, z distal)
  Vec3 rotation = Vec3::Zero();  // deg about the forearm frame's x, y, z
};

struct ClipDefinition {
  ClipInfo info;
  std::vector<std::vector<Key>> tracks;  // one per hand; the second is mirrored to a left hand
};

const std::vector<ClipDefinition>& clipDefinitions();
const ClipDefinition* findClip(const std::string& name);  // nullptr when unknown
// One sample per track; root relative to the hand's rest placement, right-hand angles.
void sampleClipInto(const ClipDefinition& clip, float time, std::vector<HandMotionSample>& out);

}  // namespace dynahand::synth::detail
