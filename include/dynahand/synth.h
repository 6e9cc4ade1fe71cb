/// @file
/// Synthetic depth sequences of moving hands with exact ground truth: a library of named
/// procedural motion clips on the default hand model (or a pose file), a scene (camera
/// placement, background, table), the smooth render surface (synth_render.h) and a sensor
/// profile (synth_sensor.h). Frames are made on demand, in any order, deterministically
/// from the options (seed included), in memory or written to disk in the canonical
/// sequence layout (sequence.h) plus per-body poses (docs/synth.md, docs/formats/synth.md).
///
///   auto seq = synth::SyntheticSequence::create({.clip = "wave", .profile = "tof"});
///   const synth::SyntheticFrame& f = seq->frame(10);   // f.depth, f.hands[0].keypoints, .pose
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "dynahand/core.h"
#include "dynahand/depth_frame.h"
#include "dynahand/model.h"
#include "dynahand/model_pose.h"
#include "dynahand/sequence.h"
#include "dynahand/synth_render.h"
#include "dynahand/synth_sensor.h"

namespace dynahand::synth {

// ---- Motion ----

/// Where a clip's hand is at one instant: the model's joint angles (root = forearm body
/// pose in the clip's workspace frame, see docs/synth.md) for a right hand; left hands are
/// the mirror image (model::mirrorAngles).
struct HandMotionSample {
  model::Side side = model::Side::Right;  ///< which hand
  model::JointAngles angles;              ///< right-hand joint angles (see above)
};

/// A named procedural clip: joint-angle keyframes on the default hand, within its joint
/// limits, smoothly interpolated and looped.
struct ClipInfo {
  std::string name;         ///< e.g. "wave"
  std::string description;  ///< one line
  float duration = 0.0f;    ///< s, one loop at speed 1
  int handCount = 1;        ///< 2 for "two-hands"
};

/// The built-in clips, in a stable order.
const std::vector<ClipInfo>& clips();
/// The clips README's demo and the default `dynahand synth` use.
const std::vector<std::string>& defaultClipSet();

/// Samples a clip at time t (s; wraps around) for a model made by makeDefaultHand (any size):
/// one sample per hand. Errors for an unknown name (listing the known ones).
Result<std::vector<HandMotionSample>> sampleClip(const std::string& name,
                                                 const model::ArticulatedModel& rightHand,
                                                 float time);

// ---- Scene ----

/// Where the synthetic camera is relative to the user.
enum class CameraPlacement {
  DeskFacing,   ///< camera in front of the user, sees the palm; forearm enters from the bottom
  HeadMounted,  ///< camera at the eyes looking ~35 deg down, sees the back of the hand
};
/// What is behind the hand: nothing, a wall plane facing the camera, or a standing torso.
enum class Background { None, Wall, Torso };
/// An object held against the first hand's palm, moving with it (Scene::heldObjectSize sets
/// its size): a ball; a cylinder with rounded ends lying across the palm (index to little
/// finger side), 12 cm between the centres of its ends; a box lying the same way, 12 cm long.
enum class HeldObject { None, Ball, Cylinder, Box };
/// "none", "ball", "cylinder", "box".
const char* heldObjectName(HeldObject object);

/// m: how far above a Scene::tableBelowHand table the lowest joint stays (about the flesh of
/// a palm or finger below its joint centre).
inline constexpr float kTableClearance = 0.015f;

/// The synthetic scene around the hand.
struct Scene {
  CameraPlacement placement = CameraPlacement::DeskFacing;  ///< where the camera is
  Background background = Background::None;                 ///< what is behind the hand
  float backgroundDistance = 0.35f;  ///< m behind the hand (wall plane or torso front)
  bool table = false;                ///< a table plane below the hand
  float tableDrop = 0.20f;           ///< m from the wrist down to the table (world down)
  /// The table is lowered where the motion would take the hand into it: no joint of any frame
  /// comes nearer to it than kTableClearance (the finger's or palm's flesh below the joint).
  /// A hand then reaches down to the table at most, never through it.
  bool tableBelowHand = false;
  float handDistance = 0.0f;  ///< m, camera to hand; 0 = auto: max(0.40, minRange + 0.2)
  HeldObject heldObject = HeldObject::None;  ///< an object in the first hand, labelled HeldObject
  /// m: the ball's and the cylinder's radius, half the box's thickness (its cross-section is
  /// square), in [0.01, 0.06]. The object touches the palm's skin on its palmar side.
  float heldObjectSize = 0.025f;
  /// Pixels (x right, y down): the camera's principal point moved by this, so the whole scene
  /// lands this far from where it would (a hand at the view's centre moved toward a border,
  /// part of it out of view). Each component within the image's width / height.
  Vec2 viewShift = Vec2::Zero();
};

// ---- Sequences ----

/// Everything a SyntheticSequence is made from (deterministic given these).
struct SynthOptions {
  std::string clip = "wave";  ///< a clips() name; ignored when poseFile is set
  /// Optional: play poses instead of a clip, retargeted to the default hand at `hand` size:
  /// a pose JSONL of the default hand (docs/formats/pose.md; joint angles carried over) or
  /// the original authors' .pose (their model's 21 keypoints fitted by model::KeypointFitter).
  /// Frames past the file's end wrap around. Placement: `desk` keeps the file's camera
  /// placement; `head` re-places the whole sequence rigidly (one transform for every frame)
  /// so that the mean forearm placement of the poses played (mean position, normalised mean
  /// quaternion) lies at the head-mounted rest placement: the same motion, seen from the
  /// head-mounted camera; a frame whose forearm lies more than 30 degrees from the rest
  /// direction is turned about the wrist to 30 degrees (an arm comes from the body).
  std::filesystem::path poseFile;
  std::filesystem::path intelModelFile;  ///< for .pose; empty = model_hand.json beside it
  /// Optional: the poses already loaded (loadPoseAngles for the same file and hand size), so
  /// that many sequences share one load; played instead of poseFile when set.
  std::shared_ptr<const std::vector<model::JointAngles>> poseAngles;
  int poseStart = 0;  ///< pose file / poseAngles: frame i plays pose poseStart + i (wrapping)
  std::string profile = "tof";    ///< a sensorProfiles() name
  int frameCount = 300;           ///< frames in the sequence, >= 1
  float framesPerSecond = 30.0f;  ///< frame rate: frame i is at time i / framesPerSecond, s
  float speed = 1.0f;             ///< clip time multiplier
  std::uint64_t seed = 1;         ///< sensor noise seed
  Scene scene;                    ///< camera placement, background, table
  model::HandDimensions hand;     ///< hand size (render surface and model scale together)
  SurfaceRadii surface;           ///< render-surface radii for the reference hand size
  /// Shape of the rendered hand relative to the tracker's model (bone lengths, finger and
  /// palm thickness; all ones = the model's shape): rendered depth and HandTruth::keypoints
  /// follow it, HandTruth::pose stays the model's. Each factor in [0.5, 1.5].
  HandProportions proportions;
};

/// The joint angles SynthOptions::poseFile plays: retargeted to the default hand at
/// options.hand size (see SynthOptions::poseFile), root in the file's camera frame, at most
/// `maxPoses` of them (0: all). For SynthOptions::poseAngles.
Result<std::vector<model::JointAngles>> loadPoseAngles(const SynthOptions& options,
                                                       int maxPoses = 0);

/// Ground truth of one hand in one frame.
struct HandTruth {
  model::Side side = model::Side::Right;  ///< which hand
  /// m, camera frame, MediaPipe order: the rendered hand's joints (options.proportions applied)
  Keypoints21 keypoints = zeroKeypoints();
  /// per-body world (camera-frame) poses of the hand's model (without proportions)
  model::ModelPose pose;
};

/// One rendered frame with its ground truth.
struct SyntheticFrame {
  int index = 0;                 ///< frame index in the sequence
  DepthFrame depth;              ///< as the sensor profile reports it
  std::vector<HandTruth> hands;  ///< hand 0 is the right hand when there are two
};

/// A synthetic depth sequence, rendered frame by frame on demand (see the file comment).
class SyntheticSequence {
 public:
  /// Validates the options (clip, profile, pose file, ranges); errors say which is wrong.
  static Result<SyntheticSequence> create(const SynthOptions& options);
  SyntheticSequence(SyntheticSequence&&) noexcept;             ///< Moves the sequence.
  SyntheticSequence& operator=(SyntheticSequence&&) noexcept;  ///< Moves the sequence.
  ~SyntheticSequence();

  const SynthOptions& options() const;   ///< the options it was created with
  const SensorProfile& profile() const;  ///< the sensor profile named by the options
  const Intrinsics& intrinsics() const;  ///< the profile's camera
  int frameCount() const;                ///< SynthOptions::frameCount
  int handCount() const;                 ///< 1, or 2 for a two-hand clip
  /// The tracker's model of hand i (default hand at the options' size, its side).
  const model::ArticulatedModel& model(int hand) const;

  /// Renders frame `index` in [0, frameCount()). The reference stays valid until the next
  /// call; the same index always gives the same bytes.
  const SyntheticFrame& frame(int index);
  /// Ground truth only (no rendering), for hand i.
  HandTruth truth(int index, int hand) const;
  /// The exact (noise-free) depth of the last rendered frame, m, and its pixel labels.
  std::span<const float> exactDepth() const;
  std::span<const PixelLabel> labels() const;  ///< (height x width) labels of that frame

 private:
  struct State;
  explicit SyntheticSequence(std::unique_ptr<State> state);
  std::unique_ptr<State> state_;
};

/// Writes the whole sequence to `dir` (must not hold a sequence): camera.json, depth/,
/// groundtruth.jsonl (hand 0), poses.jsonl (hand 0's model poses, model pose format),
/// for two hands groundtruth_hand1.jsonl and poses_hand1.jsonl, and synth.json (the
/// options, so the sequence can be regenerated). `progress(done, total)` is called after
/// each frame when given; returning false stops early, leaving a valid shorter sequence.
Status writeSequence(SyntheticSequence& sequence, const std::filesystem::path& dir,
                     const std::function<bool(int, int)>& progress = {});

/// A contact sheet PNG: one row per sensor profile, one column per clip (a frame 45% into
/// it), depth shaded (near red, far blue, no data black) with the ground-truth skeleton drawn
/// on top and labelled. Tiles are 320x240 (640x480 profiles are halved).
Status writeContactSheet(const std::filesystem::path& pngPath,
                         const std::vector<std::string>& clipNames, const Scene& scene,
                         std::uint64_t seed = 1);

}  // namespace dynahand::synth
