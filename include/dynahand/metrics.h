/// @file
/// Accuracy metrics for 21-keypoint hand tracking against ground truth.
/// Inputs in metres; reported errors in millimetres (the unit papers and users quote).
#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "dynahand/core.h"

namespace dynahand::eval {

using Keypoints21 = std::array<Vec3, 21>;  ///< metres, camera frame, MediaPipe order

/// MediaPipe / MANO keypoint names, index = keypoint id.
extern const std::array<const char*, 21> kKeypointNames;

/// One sequence: per frame the ground truth (nullopt: no visible hand) and the
/// prediction (nullopt: the tracker reported the hand lost / not tracked).
struct SequenceKeypoints {
  std::vector<std::optional<Keypoints21>> groundTruth;  ///< per frame; nullopt: no visible hand
  std::vector<std::optional<Keypoints21>> predicted;    ///< per frame; nullopt: not tracked
  double fps = 30.0;                                    ///< frames per second, for times in seconds
  /// Optional, per frame: which joints are scored (e.g. those not hidden behind a held
  /// object); empty = every joint of every frame. Errors, per-frame means and maxima and the
  /// per-joint means count scored joints only; jitter counts every joint.
  std::vector<std::array<bool, 21>> scored;
};

/// Thresholds of computeKeypointMetrics.
struct MetricsOptions {
  /// A frame counts as lost when the hand is visible and the prediction is missing
  /// or its maximum joint error exceeds this (mm).
  double lostThresholdMm = 50.0;
  std::vector<double> successThresholdsMm = {10, 20, 30, 40, 50};  ///< success curve points, mm
};

/// Accuracy of one sequence (computeKeypointMetrics).
struct KeypointMetrics {
  int frames = 0;                           ///< frames in the sequence
  int evaluatedFrames = 0;                  ///< frames with ground truth and a prediction
  int visibleFrames = 0;                    ///< frames with ground truth
  double meanMm = 0,                        ///< mean error over all joints of evaluated frames
      medianMm = 0,                         ///< median of the same errors
      p95Mm = 0,                            ///< 95th percentile of the same errors
      maxMm = 0;                            ///< largest of the same errors
  std::array<double, 21> perJointMeanMm{};  ///< mean error of each keypoint
  std::vector<double> perFrameMeanMm;       ///< (frames), NaN where not evaluated
  std::vector<double> perFrameMaxMm;        ///< (frames), NaN where not evaluated
  std::vector<double> successThresholdsMm;  ///< MetricsOptions::successThresholdsMm
  /// Fraction of visible frames whose maximum joint error is under each threshold (a
  /// missing prediction counts as a failure): the standard hand-pose success curve.
  std::vector<double> successFraction;
  /// Extra frame-to-frame keypoint motion beyond the true motion, mean over joints and
  /// consecutive evaluated frame pairs (mm): |Δpredicted - Δtruth|. On a static clip
  /// this is plain jitter.
  double jitterMm = 0;
  int lostFrames = 0;              ///< visible frames counted as lost
  int lostEpisodes = 0;            ///< maximal runs of lost frames
  double meanRecoverySeconds = 0;  ///< mean length of lost episodes that ended in tracking
  double maxRecoverySeconds = 0;   ///< longest of those episodes, s
  int unrecoveredEpisodes = 0;     ///< lost at the end of the sequence
};

/// The q-quantile (q in [0, 1]) of values, interpolated linearly; 0 for no values.
double percentile(std::vector<double> values, double q);

/// Computes every metric. groundTruth and predicted must have the same length.
Result<KeypointMetrics> computeKeypointMetrics(const SequenceKeypoints& sequence,
                                               const MetricsOptions& options = {});

/// The summary `dynahand eval` prints: frames, error statistics, success fractions, jitter,
/// losses and recovery, one item group per line (each line ends with a newline).
std::string summaryText(const KeypointMetrics& metrics);

/// A Markdown report: summary table, success curve table, per-joint table.
std::string markdownReport(const KeypointMetrics& metrics, const std::string& title);

/// Self-contained SVG plots (no fonts or scripts fetched): mean and max joint error per frame.
std::string svgErrorOverTime(const KeypointMetrics& metrics, const std::string& title);
/// The success curve (successFraction over successThresholdsMm) as a self-contained SVG.
std::string svgSuccessCurve(const KeypointMetrics& metrics, const std::string& title);

}  // namespace dynahand::eval
