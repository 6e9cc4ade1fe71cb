/// @file
/// The tracker (paper sections 3-4): per depth frame, the cloud pipeline turns the
/// frame into sample points and boundary planes; several simulations (strategies)
/// start from the previous best state and fit the articulated hand to the points
/// with the physics solver; the paper's 3D error metric picks the winner, whose state
/// seeds the next frame. Lost hands are re-acquired without user action.
///
/// Units: metres, seconds, radians; camera frame x right, y down, z forward.
#pragma once

#include <array>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "dynahand/cloud.h"
#include "dynahand/depth_frame.h"
#include "dynahand/detector.h"
#include "dynahand/hand_split.h"
#include "dynahand/model.h"
#include "dynahand/model_pose.h"

namespace dynahand::track {

/// 21 hand keypoints (MediaPipe order: 0 wrist, 1-4 thumb, ... 17-20 pinky), m.
using Keypoints21 = std::array<Vec3, 21>;

/// The simulations run every frame (paper: "Multiple Simulations and Error"). DetectorFit
/// starts from the model fitted to the learned detector's keypoints (beyond the paper).
enum class StrategyKind : int {
  Normal = 0,
  GrossMotion,
  GraspBias,
  FingerFlip,
  FeatureDetection,
  DetectorFit
};
inline constexpr int kStrategyCount = 6;  ///< the number of StrategyKind values
/// m: with two hands, the second is looked for up to this far behind the first (unless
/// CloudConfig's segmentation.secondRegionDepthBandM says otherwise): hands held out side by
/// side, one somewhat nearer.
inline constexpr float kTwoHandDepthBandM = 0.2f;
const char* strategyName(StrategyKind kind);  ///< "normal", "gross_motion", ...

/// The learned keypoint detector (dynahand/detector.h) and how the tracker uses it.
struct DetectorSettings {
  bool enabled = true;  ///< run it every frame (when weights are found)
  /// ONNX weights; empty: detect::defaultDetectorFile() (the shipped ones), and without any
  /// the tracker runs without a detector. A file given here that does not load is an error.
  std::string weights;
  /// Keypoints below this confidence ([0, 1]) are not used by the strategies. Kept low: a
  /// finger left without targets is fitted from nothing, farther off than the detector's
  /// unsure guess (docs/tracker.md, "Learned detector").
  float minConfidence = 0.1f;
  /// The detector-fit and feature simulations and acquisition use the detection when its mean
  /// confidence reaches this (the error metric still decides between the simulations).
  float minMeanConfidence = 0.25f;
  /// The model fitted to the detection (the detector-fit simulation's start) weighs each
  /// keypoint's squared distance by its confidence to this power (dimensionless; 0: all
  /// alike). The confidence is calibrated: the shipped weights' keypoints at 0.6-0.7 are off
  /// by about 8 mm on average, those at 0.2-0.3 by about 35 mm (docs/tracker.md).
  float fitConfidenceExponent = 3.0f;
  /// When the detector fit starts from the frame-start pose (the detection within 3 cm of it:
  /// the hand is in the right basin), each of the pose's 21 keypoints is also a target where
  /// that pose has it, with this weight (dimensionless; a detected keypoint weighs its
  /// confidence to fitConfidenceExponent, 1 when sure). The keypoints the detector is unsure
  /// of (below 0.33 in confidence, 0.33^3 = 0.035: mostly joints hidden from the camera)
  /// then move the fitted start less than the motion so far holds it; the sure ones still
  /// move it. It smooths the unsure keypoints' jumps from frame to frame; a guess repeated
  /// frame after frame is still followed, more slowly. 0: the detection alone
  /// (docs/tracker.md, "Learned detector").
  float fitStartPoseWeight = 0.035f;
  /// ... and when the frame-start pose's keypoints are farther than this (m, mean over the
  /// confident keypoints) from the detector's: closer, its noise has nothing to add. Lower
  /// engages the detector-fit simulation on more frames (more accurate, about 0.3-0.45 ms a
  /// frame more at 1 cm than at 2 cm on the Xeon of docs/performance.md).
  float engageDistanceM = 0.01f;
  /// A detection whose confident keypoints lie farther than this (m, median) from the surface
  /// this hand's sample points show is not used. Seen from the camera, a keypoint is as far
  /// from it as it lies across the nearest point's line of sight, plus how far it lies in
  /// front of that point or more than a fist's depth (7 cm) behind it: joints hidden behind
  /// the visible skin (the fingers of a fist seen from behind) are on the data, and a
  /// detection beside the hand or in the space the camera sees through (a crop around the
  /// wrong surface) would pull the hand away from its data.
  float maxOffCloudM = 0.04f;
  /// Loss test: when the tracked keypoints stay farther than disagreeDistanceM (m, mean over
  /// the confident keypoints of a detection used as above, weighted by their confidence; as
  /// are engageDistanceM and selectionWeight's distances) from the detector's for
  /// disagreeFrames frames in a row, the detector-fit simulation's hand replaces the winner.
  float disagreeDistanceM = 0.035f;
  int disagreeFrames = 4;  ///< frames in a row beyond disagreeDistanceM (see above)
  /// ... unless its error is more than this times the winner's (dimensionless; 0: always
  /// replaced): a hand that fits the data that much worse says the detection is what is wrong.
  float replaceMaxErrorRatio = 2.0f;
  /// The winner of a frame's simulations is the one with the least error plus this times the
  /// mean distance (m) of its keypoints from the detector's confident ones (dimensionless;
  /// 0: the paper's error metric alone). Joints hidden from the camera (fingers curled behind
  /// the back of the hand) cost the metric nothing wherever they are; the detector's view of
  /// them breaks the tie.
  float selectionWeight = 1.0f;
  /// Sample points farther than this (m) from the detected skeleton (its bones as segments,
  /// and the forearm beyond the wrist) pull no bone and are not scored by the error metric:
  /// an object held in the hand. 0: every point is the hand's.
  float objectDistanceM = 0.03f;
  /// The reported keypoints (HandResult::keypoints21) are the tracked skeleton's moved toward
  /// the detector's confident ones by this times each one's confidence (dimensionless, [0, 1];
  /// 0: the skeleton's own). The two estimates' errors are partly independent, and the
  /// detector places the wrist and knuckles better than the rigid model palm of a hand shaped
  /// otherwise. Only the report: the pose, the OpenXR joints and the next frame's start stay
  /// the skeleton's.
  float reportBlend = 0.8f;
  /// ... scaled down linearly with the keypoint's distance from the skeleton's, to nothing at
  /// this distance (m): two estimates that far apart are not noise about one joint, and the
  /// skeleton, which won on the data, is kept (a wrong detection moves no joint).
  float reportBlendReachM = 0.10f;
  /// One hand whose segment is a limb attached to the body (CloudFrame::segment.limbEndFound):
  /// the crop of a hand not found last frame is centred on the mean of the hand's points
  /// within limbEndRadius x the model hand's length of the limb's free end, not on the
  /// segment's centroid (which lies on the forearm). 0 = off.
  float limbEndRadius = 0.6f;
  /// ... and last frame's detection is the crop's centre only while its box centre lies
  /// within this distance (m) of that mean: farther, it was read from the forearm.
  float limbEndCropDistanceM = 0.10f;
  /// The detection is the mean of the network's keypoints and confidences over its crop and
  /// this many more (0..4), centred shiftedCropM away along the image's diagonals (x and y
  /// both, in the camera frame at the crop centre's depth). The network's keypoints move by
  /// millimetres when its crop moves by a pixel; the mean is nearer the truth than one crop
  /// (docs/tracker.md, "Learned detector"). Each crop costs one network run (about 1 ms).
  int shiftedCrops = 2;
  float shiftedCropM = 0.008f;  ///< m, the shifted crops' offset along x and along y
};

/// Everything the tracker is set up with; the defaults are the shipped configuration.
struct TrackerSettings {
  CloudConfig cloud;          ///< filtering, segmentation, voxel size, planes
  DetectorSettings detector;  ///< the learned keypoint detector and how it is used
  /// The segmentation ball (cloud.segmentation.handRadiusM) is set for the reference hand
  /// (model::HandDimensions{}, 0.19 m long); a longer model hand scales it up in proportion,
  /// or a hand whose nearest point is a fingertip loses its far fingertips to the ball.
  bool scaleSegmentationToHand = true;
  int hands = 1;  ///< 1, or 2 (k-means split, paper "Tracking of Multiple Hands")
  /// Two hands: how the points are split between them, and which side of the image the user's
  /// left hand is on (split.placement: kFacingUser for a camera looking at the user,
  /// kBehindUser for one worn on the head or looking along the user's view). With two hands and
  /// cloud.segmentation.secondRegionDepthBandM 0, the second hand is looked for up to
  /// kTwoHandDepthBandM behind the first.
  HandSplitConfig split;
  /// Threads the simulations of a frame run on (1: the caller's only). Results are the same
  /// bits for any count: each simulation has its own copy of the hand.
  int threads = 1;
  /// Strategies to run, by StrategyKind (ablations switch some off).
  std::array<bool, kStrategyCount> strategies = {true, true, true, true, true, true};
  /// Physics steps per frame per simulation (gross motion, finger flip and the detector fit
  /// run twice this, feature detection this plus one). 2 with pullForce 7000 N tracks as well as 3
  /// with 4000 N in less time; 2 with a weaker pull loses fast motion and finger flips
  /// (docs/tracker.md, "Settings").
  int substeps = 2;
  /// Each physics step pulls on one of this many interleaved subsets of the sample points,
  /// in turn (1 = all points every step): 2 costs 20 % less and tracks as well (3: another
  /// 10-15 % less, as accurate on the synthetic clips, but at 8000 N the grasp bias's hidden
  /// fingers stayed 22 mm off, and at 4000 N the playground's dial slipped).
  int pointSubsets = 2;
  /// The simulations pull on at most this many of the sample points on the palm, and as many
  /// on the forearm (by the frame-start mapping; 0: all), taken evenly in scan order, each
  /// standing for the ones left out (its cap scaled up, so each body's total pull is kept).
  /// Those two bodies hold half the samples (about 345 and 180 of 1140 on the wave clip) for
  /// 6 degrees of freedom each; the fingers keep all of theirs. The error metric still
  /// measures every point. With the 12 + 3 sweeps below, 15 % less time and as accurate
  /// (docs/tracker.md, "Settings").
  int palmPointCap = 80;
  float stepDt = 1.0f / 60.0f;  ///< s per physics step
  int iterations = 12;          ///< Gauss-Seidel sweeps per step of the simulations
  int relaxIterations = 3;      ///< bias-removal sweeps per step of the simulations
  /// Sweeps while acquiring from a canonical pose, far from the data (16 + 4: 12 + 3 left a
  /// fingertip over background on a real open palm, RealData test, SR305 frame 6).
  int acquisitionIterations = 16;
  int acquisitionRelaxIterations = 4;  ///< bias-removal sweeps per step while acquiring
  float pullForce = 7000.0f;           ///< total surface-row force (N), split over the points
  /// The pull while acquiring from a canonical pose (acquisitionSubsteps steps, every point
  /// in every step): the per-frame pull above is too strong for that long a fit, and leaves
  /// a fingertip over background on a real open palm (RealData test, SR305 frame 6).
  float acquisitionPullForce = 4000.0f;  ///< N
  float boundaryForce = 200.0f;          ///< per boundary row (N)
  /// Boundary rows go to a body's hull vertices within this band (m) of its deepest vertex
  /// (and within 2 cm of the plane): the far side of a finger lying along a plane gets none.
  float boundaryBand = 0.005f;
  float surfaceErp = 0.9f;         ///< fraction of a surface row's gap closed per step, [0, 1]
  float velocityRetention = 0.8f;  ///< per physics step: the prior motion kept (momentum)
  /// The forearm is held at its frame-start position along its own axis (only): samples on
  /// the arm's sides cannot say where along the arm it is, so without this the hand slides
  /// along the arm when the fingers curl over the palm. Capped, so the hand's data wins.
  float forearmHoldForce = 1000.0f;  ///< N
  /// A model fingertip over pixels the camera sees as empty (background farther than it, or
  /// no data) is pushed towards the nearest segmented pixel with at most this force (N);
  /// 0 = off. Beyond the paper, whose metric only scores such a tip.
  float silhouetteForce = 100.0f;
  /// Lost when the winner's error per body stays above this (m) for lostAfterFrames
  /// frames, or when the hand leaves the view.
  float lostErrorPerBodyM = 0.02f;
  int lostAfterFrames = 3;  ///< frames above lostErrorPerBodyM before the hand is lost
  /// Treat every frame as a fresh acquisition (no temporal prior), e.g. for frames far
  /// apart in time.
  bool perFrame = false;
  int acquisitionSubsteps = 24;  ///< physics steps when fitting from a canonical pose
  float flipPeriodS = 0.5f;      ///< finger-flip choice cycles this often (sequence time)
  /// Report every simulation's pose and full error (for pictures of the losing candidates).
  /// Off, a losing simulation's error metric stops as soon as it is sure to lose, so its
  /// Candidate::error is only a lower bound and its pose is not kept; the winner, its error
  /// and the tracking results are the same bits either way.
  bool keepCandidates = false;
};

/// One TrackerSettings field settable by name (setTrackerSetting).
struct NamedSetting {
  std::string name;         ///< dotted as the docs write it: "detector.selectionWeight"
  std::string value;        ///< its value in the settings listed, as text
  std::string description;  ///< what it is, with its unit
};
/// Sets the TrackerSettings field `name` (dotted as the docs write it: "substeps",
/// "detector.selectionWeight", "cloud.segmentation.handRadiusM"; namedSettings() lists them)
/// from text: a number, or true / false (1 / 0). An unknown name or a value of the wrong kind
/// is an error naming both; ranges are checked where the settings are used (Tracker::create).
Status setTrackerSetting(TrackerSettings& settings, std::string_view name, std::string_view value);
/// The same from "NAME=VALUE" (`dynahand track --set`, `dynahand bench --set`).
Status setTrackerSetting(TrackerSettings& settings, std::string_view assignment);
/// Every setting setTrackerSetting takes, in the docs' order, with its value in `settings`.
std::vector<NamedSetting> namedSettings(const TrackerSettings& settings = {});

/// How well the fitted hand explains the data (beyond the paper's metric):
struct FitQuality {
  float dataNearModel = 0.0f;  ///< share of the hand's sample points within 10 mm of the model
                               ///< (those beyond its wrist left out)
  float modelOnHand = 0.0f;    ///< share of the camera-facing model surface (by area as seen
                               ///< from the camera, forearm excluded) that projects onto
                               ///< segmented pixels
  int fingertipsOffHand = 0;   ///< fingertip keypoints projecting more than 3 pixels outside
                               ///< the segmentation (onto background)
};

/// One simulation's outcome this frame.
struct Candidate {
  StrategyKind kind = StrategyKind::Normal;  ///< which simulation
  bool ran = false;                          ///< e.g. the detector did not fire
  float error = 0.0f;  ///< m, the paper's errTotal (a lower bound for a loser, see keepCandidates)
  model::ModelPose pose;  ///< its 17 body poses at the end of the frame
};

/// One hand's result for a frame.
struct HandResult {
  model::Side side = model::Side::Right;  ///< which hand
  bool tracked = false;                   ///< a pose is reported (the hand is not lost)
  model::ModelPose pose;                  ///< 17 body poses (valid when tracked)
  /// MediaPipe order, m: the pose's keypoints blended with the detector's
  /// (DetectorSettings::reportBlend); skeletonKeypoints21 are the pose's own.
  Keypoints21 keypoints21{};
  Keypoints21 skeletonKeypoints21{};               ///< the pose's keypoints, MediaPipe order, m
  std::array<model::XrJoint, 26> openxr26{};       ///< OpenXR's 26 hand joints (valid when tracked)
  float error = 0.0f;                              ///< errTotal of the winner, m
  float fitError = 0.0f;                           ///< sum errFit, m
  float occlusionError = 0.0f;                     ///< sum errOcc, m
  std::vector<float> bodyError;                    ///< (17) errFit_i + errOcc_i, m
  FitQuality quality;                              ///< of the reported pose (valid when tracked)
  StrategyKind simulation = StrategyKind::Normal;  ///< the simulation whose pose won
  bool acquired = false;  ///< this frame (re)acquired the hand from scratch
  /// The learned detector's keypoints this frame (MediaPipe order, m) and confidences; all
  /// zero when it did not run.
  bool detected = false;
  Keypoints21 detectorKeypoints21{};           ///< the detector's keypoints, m
  std::array<float, 21> detectorConfidence{};  ///< their confidences, [0, 1]
  /// Mean distance of the reported keypoints from the detector's confident ones (m), and the
  /// frames in a row it has exceeded DetectorSettings::disagreeDistanceM.
  float detectorDisagreement = 0.0f;
  int disagreeingFrames = 0;          ///< frames in a row beyond disagreeDistanceM
  int pointCount = 0;                 ///< sample points used
  std::vector<Candidate> candidates;  ///< every simulation's outcome, by StrategyKind
};

/// A frame's result: one HandResult per tracked hand.
struct TrackResult {
  int frame = 0;        ///< index of this frame, counted from 0 since the tracker was created
  double timeMs = 0.0;  ///< wall time spent in track(), ms
  std::vector<HandResult> hands;  ///< TrackerSettings::hands entries: [0] right, [1] left
};

/// The tracker: depth frames in, hand poses out (docs/tracker.md). One thread calls it; the
/// simulations may run on TrackerSettings::threads threads.
class Tracker {
 public:
  /// rightHand: the model for the right hand (the left is its mirror image).
  static Result<std::unique_ptr<Tracker>> create(const model::ArticulatedModel& rightHand,
                                                 const Intrinsics& intrinsics,
                                                 const TrackerSettings& settings = {});
  ~Tracker();

  /// Starts tracking from a known pose (e.g. ground truth) of the hand on `side`.
  void initialize(const model::ModelPose& pose, model::Side side = model::Side::Right);
  /// Starts from 21 labelled keypoints of the first frame (fit under the joint limits).
  Status initializeFromKeypoints(const Keypoints21& keypoints,
                                 model::Side side = model::Side::Right);
  /// Forgets all state: the next frame acquires from scratch.
  void reset();

  /// Tracks one frame. The reference stays valid until the next call.
  const TrackResult& track(const DepthFrame& frame);
  /// Keypoints of the hand on `side` from another source (camera frame, m, with a confidence
  /// each in [0, 1]), used by the next track() call instead of the learned detector's: e.g. a
  /// colour-image detector registered to the depth camera, or ground truth to measure what a
  /// perfect detector would give (`dynahand bench --keypoints-from-truth`). They go through
  /// the same tests as the detector's (DetectorSettings: confidences, distance from the
  /// cloud) and drive the same simulations; meanConfidence is recomputed. Works with the
  /// learned detector off or absent. Ignored for a side not tracked (TrackerSettings::hands 1:
  /// the right hand only).
  void setKeypoints(const detect::DetectedKeypoints& keypoints,
                    model::Side side = model::Side::Right);

  /// The cloud of the last frame (points, mask, planes), e.g. for pictures.
  const CloudFrame& lastCloud() const;
  /// The model tracked for `side` (the left one is the right one's mirror image).
  const model::ArticulatedModel& model(model::Side side) const;
  /// The settings in use: as given, except the segmentation radius scaled to the model's hand
  /// length (see scaleSegmentationToHand).
  const TrackerSettings& settings() const;

 private:
  struct Impl;
  explicit Tracker(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace dynahand::track
