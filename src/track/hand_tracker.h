// Tracking of one hand: its rig (physics world), the strategies, the error metric,
// acquisition from scratch and the tracked/lost state.
#pragma once

#include <array>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "dynahand/detector.h"
#include "dynahand/model_fit.h"
#include "dynahand/tracker.h"
#include "track/error_metric.h"
#include "track/finger_detector.h"
#include "track/hand_rig.h"
#include "track/simulation.h"
#include "track/strategies/strategy.h"
#include "track/worker_pool.h"

namespace dynahand::track {

struct HandFrame {
  std::span<const Vec3> points;  // this hand's sample points, m
  std::span<const BoundaryPlane> planes;
  const CloudFrame* cloud = nullptr;
  const FingerDetection* detection = nullptr;  // nullptr or not fired: none
  // The learned detector's keypoints for this hand (camera frame); nullptr: none.
  const detect::DetectedKeypoints* keypoints = nullptr;
  double time = 0.0;  // sequence time, s
};

class HandTracker {
 public:
  static Result<std::unique_ptr<HandTracker>> create(const model::ArticulatedModel& model,
                                                     model::Side side,
                                                     const TrackerSettings& settings,
                                                     WorkerPool* pool = nullptr);
  void initialize(const model::ModelPose& pose);
  void reset();
  bool tracked() const { return tracked_; }
  const model::ArticulatedModel& model() const { return *model_; }
  void track(const HandFrame& frame, HandResult& out);

 private:
  HandTracker(const model::ArticulatedModel& model, model::Side side,
              const TrackerSettings& settings, HandRig rig, WorkerPool* pool);
  // The paper's error of the rig's current state (writes posed and error), given up once it
  // is sure to exceed abortAbove (see computeErrorBounded; false then). order: the points'
  // visiting order, optional.
  static bool evaluate(Simulator& simulator, const HandRig& rig, const HandFrame& frame,
                       std::span<const int> hints, PosedBodies& posed, ErrorBreakdown& error,
                       float abortAbove = std::numeric_limits<float>::infinity(),
                       std::span<const int> order = {});
  float evaluate(Simulator& simulator, const HandFrame& frame);  // of rig_, into error_
  // Each lane's candidate.error and lane.error, stopping a candidate's metric once it cannot
  // win (see computeErrorBounded): its error is then only a lower bound.
  void evaluateUntilBeaten(const HandFrame& frame);
  // The farthest 1/kMetricHeadFraction of the points go first in evaluateUntilBeaten.
  static constexpr std::size_t kMetricHeadFraction = 5;
  // A frame's simulations, in stages: the shared frame start, every lane run, the winner.
  void runStrategies(const HandFrame& frame, HandResult& out);
  struct Lane;
  // What every simulation of a frame starts from.
  struct FrameStart {
    FrameInput laneInput;     // the points the lanes pull on (thinned by palmPointCap)
    bool bindLabels = false;  // the detector's keypoints bound as labelled points
    const model::ModelPose* fittedStart = nullptr;  // the model fitted to them, if any
  };
  // Saves the start state, maps the points at it once for every lane, fits the detector's
  // keypoints when the frame starts away from them.
  // Into frameStart_.
  void prepareFrameStart(const HandFrame& frame);
  StrategyContext laneContext(Lane& lane, const HandFrame& frame, const FrameStart& start) const;
  void startLane(Lane& lane);
  // With keepCandidates: the lane's full error and pose.
  void finishLane(Lane& lane, const HandFrame& frame);
  // Every lane on the worker pool, or side by side on the caller.
  void runLanes(const HandFrame& frame, const FrameStart& start);
  // The lane with the least error (the loss test may replace it) into the rig and `out`;
  // counts bad frames toward a loss.
  void pickWinner(const HandFrame& frame, HandResult& out);
  void acquire(const HandFrame& frame, HandResult& out);
  // The open hand placed at the cloud: fingers along axisImage (wrist -> tips), thumb
  // toward thumbSideImage, palm centre at the cloud's centroid.
  model::ModelPose canonicalPose(const HandFrame& frame, const Vec2& axisImage,
                                 const Vec2& thumbSideImage) const;
  void fillResult(HandResult& out);
  // The learned detector's evidence of this frame (detectorLabels_, keypoints_): its
  // confident keypoints; none below the confidence settings.
  void prepareDetectorEvidence(const HandFrame& frame);
  // The model fitted to the detector's confident keypoints (detectorPose_), once per frame
  // and only when a strategy or acquisition asks; false without one. From warmStart when
  // given (a few iterations), else from scratch (a rigid start, then every joint; about 3 ms).
  bool fitDetectorPose(const model::JointAngles* warmStart = nullptr);
  // Mean distance (m) of `keypoints` from the detector's confident ones.
  float detectorDistance(const Keypoints21& keypoints) const;
  // The reported keypoints moved toward the detector's (DetectorSettings::reportBlend).
  void blendTowardDetector(Keypoints21& keypoints) const;

  const model::ArticulatedModel* model_;
  model::Side side_;
  TrackerSettings settings_;
  HandRig rig_;
  Simulator simulator_;  // the frame-start mapping the lanes share
  // Acquisition moves the hand from a canonical pose, far from the data: every point pulls
  // in every step (pointSubsets 1), as a frame's few steps from the last pose need not.
  Simulator acquisitionSimulator_;
  // One simulation strategy with everything it writes to while it runs.
  struct Lane {
    HandRig rig;
    Simulator simulator;
    std::unique_ptr<Strategy> strategy;
    PosedBodies posed;
    ErrorBreakdown error;
    Candidate candidate;
    std::vector<int> metricHints;  // scratch: its simulator's bodies over all points
    // What the winner is chosen by: candidate.error plus the detector-agreement term
    // (DetectorSettings::selectionWeight), m.
    float score = 0.0f;
  };
  // DetectorSettings::selectionWeight x the mean distance (m) of the lane's keypoints from the
  // detector's confident ones; 0 without a detection in use.
  float agreementTerm(const Lane& lane);
  // `points` without those farther than DetectorSettings::objectDistanceM from the detected
  // skeleton (a held object's); all of them without a detection in use, or when that would
  // leave fewer than half.
  std::span<const Vec3> pointsOnTheDetectedHand(std::span<const Vec3> points);
  std::vector<Vec3> handPoints_;  // pointsOnTheDetectedHand's result
  // Loss test after the winner is chosen: counts frames in a row the winner disagrees with
  // the detector; at DetectorSettings::disagreeFrames the detector-fit lane replaces it unless
  // it fits more than DetectorSettings::replaceMaxErrorRatio times worse. Returns the lane to
  // keep.
  const Lane* checkAgainstDetector(const HandFrame& frame, const Lane* best);
  // Median over `keypoints` of how far (m) each lies from the surface `points` sample, seen
  // from the camera: its distance from the nearest point's line of sight plus how far it lies
  // in front of that point or more than kHiddenDepthM behind it. Infinity without points.
  float medianDistanceFromSurface(std::span<const Vec3> keypoints, std::span<const Vec3> points);
  // A simulator's last nearest bodies over all of the frame's points, for the metric: the
  // simulations' own where they ran on thinned points (palmPointCap), else the frame start's.
  std::span<const int> metricHints(const Simulator& simulator, std::vector<int>& buffer) const;
  // Picks the points the simulations pull on (palmPointCap) and their weights from the
  // frame-start mapping, and hands them to the simulator sharing it.
  void thinPoints(std::span<const Vec3> points);
  std::vector<int> frameStartBodies_;  // (points) nearest body at the frame start
  std::vector<int> keptIndex_;         // the points kept by thinPoints, increasing
  std::vector<Vec3> keptPoints_;
  std::vector<float> keptWeights_;
  std::vector<std::unique_ptr<Lane>> lanes_;
  std::vector<int> runOrder_;  // lanes by decreasing run length (runStrategiesSideBySide)
  // runStrategies' scratch, in runOrder_ (no allocation per frame).
  std::array<std::optional<StrategyContext>, kStrategyCount> laneContexts_;
  std::array<Strategy*, kStrategyCount> laneStrategies_{};
  std::array<StrategyContext*, kStrategyCount> laneContextPointers_{};
  std::array<bool, kStrategyCount> laneRan_{};
  WorkerPool* pool_ = nullptr;  // runs the lanes; null: in order on the caller
  physics::WorldState start_, best_;
  AxisHold forearmHold_;   // this frame's hold of the forearm along its axis (FrameInput::hold)
  FrameStart frameStart_;  // this frame's (prepareFrameStart)
  model::ModelPose pose_;
  model::JointAngles startAngles_;
  model::JointAngles openAngles_;  // the acquisition pose's angles
  PosedBodies posed_;
  ErrorBreakdown error_;          // of the last evaluate()
  ErrorBreakdown bestBreakdown_;  // of the state the world holds after a frame
  std::vector<int> metricOrder_;  // point order for evaluateUntilBeaten
  // The lane that won the last frame (measured first in evaluateUntilBeaten: it usually wins
  // again, so the others give up early); -1 after acquisition or a reset.
  int lastWinner_ = -1;
  bool tracked_ = false;
  int badFrames_ = 0;
  // Learned detector evidence (prepareDetectorEvidence) and the loss test's state.
  model::KeypointFitter fitter_;
  std::vector<int> fitIndices_;
  std::vector<Vec3> fitTargets_;
  std::vector<float> fitWeights_;  // per target, the fit's weight (detector confidence)
  // The warm fit's targets: the detection's above, then the frame-start pose's keypoints
  // (DetectorSettings::fitStartPoseWeight).
  std::vector<int> warmFitIndices_;
  std::vector<Vec3> warmFitTargets_;
  std::vector<float> warmFitWeights_;
  Keypoints21 startKeypoints_{};  // the frame-start pose's (prepareFrameStart)
  std::vector<LabelledPoint> detectorLabels_;
  model::ModelPose detectorPose_;
  bool haveDetectorPose_ = false;
  bool detectorPoseTried_ = false;
  std::vector<int> confidentKeypoints_;  // of the 21, those used this frame
  std::vector<float> offCloud_;          // medianDistanceFromSurface' scratch (m^2)
  const detect::DetectedKeypoints* keypoints_ = nullptr;
  int disagreeFrames_ = 0;
  Keypoints21 scratchKeypoints_{};
};

}  // namespace dynahand::track
