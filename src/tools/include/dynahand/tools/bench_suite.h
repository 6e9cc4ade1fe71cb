/// @file
/// The accuracy and speed suites behind `dynahand bench` (docs/benchmarks.md). The motion
/// suite (the headline numbers): every continuous segment of the original authors'
/// animbank.pose and the built-in clips at 2.5x speed, desk and head-mounted cameras, hands
/// shaped unlike the tracker's model, ground-truth and automatic starts, plus the whole
/// animbank played through its cuts (frames to re-acquire). The standard suite (regression
/// rows): the default clips x sensor profile x hand size, with ground-truth first-frame
/// initialisation and with automatic acquisition, plus ablations (each simulation strategy
/// off in turn, and "normal only"). Synthetic input with fixed seeds, so runs compare.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "dynahand/metrics.h"
#include "dynahand/model.h"
#include "dynahand/model_pose.h"
#include "dynahand/synth.h"
#include "dynahand/tracker.h"

namespace dynahand::eval {

/// A named hand size of the suites.
struct HandSize {
  std::string name;                  ///< "small", "medium", "large"
  model::HandDimensions dimensions;  ///< length and width, m
};
/// The three hand sizes: small, medium, large (about the 5th, 50th and 95th percentile adult
/// hand length).
const std::vector<HandSize>& benchHandSizes();
/// Clips outside the default set that the ablations also run, each for the strategies it
/// targets: fast-translation (gross motion; the detector re-acquires), finger-flips (finger
/// flip), grasp-cylinder (grasp bias).
const std::vector<std::string>& targetedAblationClips();

/// Which shape factors of the rendered hand a benchmark item gives the tracker's model.
enum class TrueShape {
  None,         ///< the default proportions (the hand's shape unknown, as for a user)
  All,          ///< every bone length and thickness factor
  Metacarpals,  ///< bone 0 of each digit alone: where the knuckles and the thumb base sit
  Phalanges,    ///< bones 1-3 of each digit alone
  Thickness,    ///< the finger and palm thickness factors alone
};

/// Whether the tracker's hand is estimated from the item's first frames, as `dynahand track
/// --hand-size auto` does it (track::estimateHandSize).
enum class HandEstimate {
  None,         ///< the default hand at the rendered hand's size, as `--hand-length` gives it
  Size,         ///< the size estimated (`--hand-size auto --hand-size-only`)
  Metacarpals,  ///< the size and each digit's metacarpal estimated (`--hand-size auto`)
};

/// One benchmark item: a clip synthesised on one sensor profile and hand, then tracked.
struct SuiteItem {
  std::string variant = "all";  ///< "all", "no <strategy>" or "normal only"
  bool ablation = false;        ///< part of the ablation block (tof, medium, gt init)
  /// An ablation item on a clip a strategy targets beyond the default set
  /// (targetedAblationClips(), not synth::defaultClipSet()):
  /// in the per-clip ablation table only, not in the summary rows.
  bool targeted = false;
  std::string clip,       ///< clip name (synth clips), or the label of `poses`
      profile;            ///< sensor profile name (synth::sensorProfiles)
  HandSize size;          ///< size of the synthesised hand
  bool autoInit = false;  ///< false: initialised from frame 0's ground truth
  /// The tracker's settings (ablations switch strategies off); keepCandidates is ignored.
  track::TrackerSettings tracker;
  int frames = 0;          ///< frames synthesised and tracked
  float speed = 1.0f;      ///< clip time multiplier (0.5: half speed)
  std::uint64_t seed = 1;  ///< sensor noise

  /// Motion suite items (motionSuite); the standard suite leaves these at their defaults.
  std::string group;  ///< row label; empty: the standard suite's "profile / size / init"
  synth::CameraPlacement placement = synth::CameraPlacement::DeskFacing;  ///< camera placement
  float proportionSpread = 0.0f;     ///< synth::randomProportions(proportionSeed, spread)
  std::uint64_t proportionSeed = 0;  ///< seed of synth::randomProportions
  /// Poses played instead of `clip` when set (synth::loadPoseAngles), from poseStart on;
  /// `clip` then names them (e.g. "animbank 428-965").
  std::shared_ptr<const std::vector<model::JointAngles>> poses;
  int poseStart = 0;      ///< index of the first pose played from `poses`
  std::vector<int> cuts;  ///< frames (of this item) where the motion jumps: re-acquisition
  /// An object held against the palm (synth::Scene::heldObject); joints it hides from the
  /// camera (their pixel shows the object) are not scored.
  synth::HeldObject heldObject = synth::HeldObject::None;
  /// A table this far (m) below the scene's rest wrist position (synth::Scene::tableDrop), or
  /// lower where the motion would take the hand into it (synth::Scene::tableBelowHand); 0: none.
  float tableDropM = 0.0f;
  /// Pixels: the scene moved in the image (synth::Scene::viewShift), so the hand reaches past
  /// an image border; joints outside the image are not scored.
  Vec2 viewShift = Vec2::Zero();
  /// >= 0: each frame the tracker is given the ground-truth keypoints, plus Gaussian noise of
  /// this standard deviation per axis (m), instead of the learned detector's
  /// (Tracker::setKeypoints, confidence 1): what a perfect or a given-noise detector would
  /// give. The error is then the tracked skeleton's (HandResult::skeletonKeypoints21), since
  /// the report's blend would move the keypoints onto the given ones. < 0: the learned
  /// detector, and the error is the report's (HandResult::keypoints21).
  float truthKeypointsNoiseM = -1.0f;
  /// Which of the rendered hand's shape factors (synth::HandProportions) the tracker's model
  /// is given (model::makeDefaultHand with a model::HandShape): what a model shaped like the
  /// hand would give. None: the default hand, as a user's tracker has.
  TrueShape trueShape = TrueShape::None;
  /// The tracker's hand estimated from the first kHandEstimateFrames frames (with the first
  /// frame's keypoints on a `gt` item, from the hand the learned detector finds on an `auto`
  /// one: HandSizeOptions::acquisitionFrames) instead of given; not with trueShape.
  HandEstimate handEstimate = HandEstimate::None;
};

/// Frames SuiteItem::handEstimate estimates from (`dynahand track --hand-size-frames` default).
inline constexpr int kHandEstimateFrames = 30;

/// The tracker's model shaped like the rendered hand, from these of its factors.
model::HandShape trackerShape(const synth::HandProportions& proportions, TrueShape part);

/// What standardSuite builds.
struct SuiteOptions {
  bool quick = false;  ///< a few short items, for CI
  int frames = 0;      ///< frames per item; 0: 60 (quick: 8)
};
/// The standard suite's items: default clips x sensor profile x hand size with gt and auto
/// starts, then the ablation items (see the file comment).
std::vector<SuiteItem> standardSuite(const SuiteOptions& options);

inline constexpr float kCutWristM = 0.04f,  ///< wrist move that marks a cut (findCuts), m
    kCutKeypointM = 0.055f;                 ///< move of any keypoint that marks a cut (findCuts), m
/// Where a pose sequence jumps (a cut between takes): frames i whose wrist keypoint moved more
/// than 4 cm, or any keypoint more than 5.5 cm, from frame i - 1 (in animbank the largest
/// move within a take is 4.3 cm). Keypoints of the default hand.
std::vector<int> findCuts(const std::vector<Keypoints21>& keypoints);

/// What motionSuite builds.
struct MotionSuiteOptions {
  bool quick = false;  ///< a few short items, for CI
  int frames = 0;      ///< frames per clip item; 0: 90 (3 s; quick: 8)
  /// Folder holding intel/animbank.pose and intel/model_hand.json (../shared/data); empty or
  /// without the file: the animbank rows are skipped (MotionSuite::skipped says why).
  std::filesystem::path data;
};
/// The motion suite's items, and what was found of the animbank.
struct MotionSuite {
  std::vector<SuiteItem> items;  ///< clip items, then animbank items
  std::string skipped;           ///< why the animbank rows are missing; empty when they are there
  int animbankPoses = 0,         ///< poses in animbank.pose; 0 when skipped
      animbankSegments = 0;      ///< continuous segments between its cuts
};
/// The clips (all built-in one-hand clips at speed 2.5) and the animbank segments (each from
/// its own first frame), each on the four sensor profiles, the desk and head-mounted cameras,
/// gt and auto starts (animbank on the desk camera, in the file's own placement, is too near
/// for structured light and is left out there), and one continuous animbank item per
/// placement (tof, gt start); hand proportions spread 0.15, one seed per clip or segment.
/// Quick: pinch and wave on tof, 8 frames; the first two segments (8 frames) and the
/// continuous item over its first cut.
Result<MotionSuite> motionSuite(const MotionSuiteOptions& options);

inline constexpr double kAcquiredMaxJointMm = 30.0;  ///< "tracking" for frames-to-acquire
/// An item acquired by this many frames from its start counts as acquired promptly (the
/// head-mounted acquisition target: within 5 frames on 95 % of segments).
inline constexpr int kPromptAcquireFrames = 5;

/// What runSuiteItem measured for one item.
struct SuiteItemResult {
  SuiteItem item;               ///< the item run
  SequenceKeypoints keypoints;  ///< ground truth and prediction per frame
  KeypointMetrics metrics;      ///< error statistics over `keypoints`
  /// The same ground truth against the learned detector's keypoints (or those given with
  /// truthKeypointsNoiseM) on their own, without the physics; nullopt where none were used.
  SequenceKeypoints detectorKeypoints;
  /// The model's misfit: the same ground truth against the tracker's model fitted to each
  /// frame's true keypoints under its joint limits (model::KeypointFitter, started from the
  /// rendered pose). The rendered hand is shaped unlike the model, so no pose of the model
  /// reaches its keypoints: the floor of the tracker's error with a perfect fit.
  SequenceKeypoints misfitKeypoints;
  /// Mean joint error (mm) of `detectorKeypoints` and of `misfitKeypoints` over the frames
  /// with a prediction; NaN: none.
  double detectorMeanMm = 0, misfitMm = 0;
  std::vector<double> frameMs;     ///< tracker wall time per frame (one thread), ms
  std::vector<double> frameCpuMs;  ///< CPU time of that thread in track(), ms: on a loaded
                                   ///< machine wall time grows, CPU time much less
  int framesToAcquire = -1;        ///< first frame with max joint error <= 30 mm; -1: never
  /// Per item cut: frames from the cut to the first frame with max joint error <= 30 mm,
  /// -1 when that does not happen before the next cut (or the end).
  std::vector<int> framesToReacquire;
};

/// Synthesises and tracks one item on the calling thread.
Result<SuiteItemResult> runSuiteItem(const SuiteItem& item);

/// Runs items on `threads` worker threads (each item on one thread, so per-frame times are
/// single-core times as long as threads <= idle cores). progress(done, total) is called
/// from the workers, serialised; `stop` (may be null) ends the run early: results then
/// hold the items finished. Results are in item order.
Result<std::vector<SuiteItemResult>> runSuite(const std::vector<SuiteItem>& items, int threads,
                                              const std::function<void(int, int)>& progress,
                                              const std::atomic<bool>* stop = nullptr);

/// One table row: items aggregated over clips.
struct SuiteRow {
  std::string label;     ///< e.g. "tof / medium / gt" or "ablation: no grasp_bias"
  int items = 0,         ///< items aggregated
      frames = 0;        ///< frames over those items
  double meanMm = 0,     ///< mean joint error, mm
      p95Mm = 0;         ///< 95th percentile joint error, mm
  double success30 = 0;  ///< fraction of frames with max joint error <= 30 mm
  /// The detector alone (SuiteItemResult::detectorKeypoints): mean joint error, mm, over the
  /// frames it ran on (NaN: it ran on none), and the fraction of frames it ran on.
  double detectorMeanMm = 0, detectorRan = 0;
  double misfitMm = 0;  ///< mean joint error of the model fitted to the truth (misfitKeypoints), mm
  double p50Ms = 0,     ///< median wall time per frame, ms
      p99Ms = 0,        ///< 99th percentile wall time per frame, ms
      framesPerSecond = 0;             ///< frames per second of total wall time
  double p50CpuMs = 0;                 ///< median thread CPU time per frame, ms
  int autoItems = 0;                   ///< items with automatic acquisition
  double meanFramesToAcquire = 0;      ///< over auto items that acquired
  int maxFramesToAcquire = -1;         ///< over auto items that acquired; -1: none did
  int neverAcquired = 0;               ///< auto items that never acquired
  int promptlyAcquired = 0;            ///< auto items acquired within kPromptAcquireFrames frames
  int cuts = 0;                        ///< cuts in the row's items
  double medianFramesToReacquire = 0;  ///< over all cuts, never = infinitely many
  int neverReacquired = 0;             ///< cuts never re-acquired
};
/// Groups results into table rows by label: motion-suite groups, standard rows, the ablation
/// baseline and the ablations (targeted items excluded), in that order.
std::vector<SuiteRow> summarizeSuite(const std::vector<SuiteItemResult>& results);
/// The row an item is summarised in: its group (motion suite), "ablation: VARIANT", or
/// "PROFILE / SIZE / gt|auto".
std::string rowLabel(const SuiteItem& item);

/// The table as fixed-width text (terminal) and as Markdown.
std::string suiteTableText(const std::vector<SuiteRow>& rows);
std::string suiteTableMarkdown(const std::vector<SuiteRow>& rows);  ///< as Markdown
/// The motion suite's table (rows with a group label): mean / p95 error, frames within
/// 30 mm, the detector alone's and the model misfit's mean error, frames to acquire (auto) and
/// to re-acquire after cuts, p50 ms.
std::string motionTableText(const std::vector<SuiteRow>& rows);
std::string motionTableMarkdown(const std::vector<SuiteRow>& rows);  ///< as Markdown
/// Mean error (mm) per clip for every ablation variant: what each strategy buys where.
std::string ablationByClipMarkdown(const std::vector<SuiteItemResult>& results);

}  // namespace dynahand::eval
