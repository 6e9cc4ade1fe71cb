/// @file
/// Fitting a model pose (and optionally a uniform scale) to target keypoints under the joint
/// limits: rigid alignment of the keypoints fixed to one body (Umeyama), then damped
/// Gauss-Newton (Levenberg-Marquardt) on the root pose, every free joint angle and the scale,
/// with angles projected onto their limits after each step. Used to initialise tracking from
/// labelled keypoints and to compare with datasets.
#pragma once

#include <array>
#include <span>
#include <vector>

#include "dynahand/model_pose.h"

namespace dynahand::model {

/// How KeypointFitter fits.
struct FitOptions {
  bool fitScale = false;                 ///< also estimate a uniform scale of the model
  float minScale = 0.5f;                 ///< scale bounds when fitScale
  float maxScale = 2.0f;                 ///< see minScale
  int maxIterations = 60;                ///< Levenberg-Marquardt iterations per start
  float meanErrorGoal = 1e-5f;           ///< m; stop once the mean keypoint error is below this
  const JointAngles* initial = nullptr;  ///< start here (and skip the rigid alignment); not owned
  /// Per target, its weight in the squared-distance cost (finite, >= 0; e.g. a detector's
  /// confidence); empty: 1 each. The rigid alignment that starts a fit is unweighted.
  std::span<const float> weights;
};

/// A fitted pose and how well it fits.
struct FitResult {
  JointAngles angles;      ///< for scaleModel(model, scale): same root, same angles
  float scale = 1.0f;      ///< uniform model scale (1 unless fitScale)
  float meanError = 0.0f;  ///< mean keypoint distance after the fit, m
  float maxError = 0.0f;   ///< largest keypoint distance, m
  int iterations = 0;      ///< total over all starts
};

/// Reusable fitter: buffers are sized once per model, so repeated fits do not reallocate.
class KeypointFitter {
 public:
  /// A fitter for `model` (kept by reference; it must outlive the fitter).
  explicit KeypointFitter(const ArticulatedModel& model);

  /// keypointIndices index model.keypoints(); targets are world positions (m), same length.
  /// Fails (with a reason) on mismatched lengths, non-finite targets or fewer than 3 targets,
  /// or weights (FitOptions::weights) that are not one finite, non-negative value per target.
  Result<FitResult> fit(std::span<const int> keypointIndices, std::span<const Vec3> targets,
                        const FitOptions& options = {});
  /// The 21 MediaPipe keypoints (the model must have them).
  Result<FitResult> fit21(const std::array<Vec3, 21>& targets, const FitOptions& options = {});

 private:
  struct Param {
    int joint;  ///< -1: root / scale
    int axis;
  };
  float run(std::span<const int> keypoints, std::span<const Vec3> targets,
            const FitOptions& options, JointAngles& angles, float& scale, int& iterations);
  float evaluate(std::span<const int> keypoints, std::span<const Vec3> targets,
                 const JointAngles& angles, float scale, std::vector<Vec3>& positions);
  bool rigidStart(std::span<const int> keypoints, std::span<const Vec3> targets, bool fitScale,
                  JointAngles& angles, float& scale);

  const ArticulatedModel* model_;
  std::vector<Param> params_;  ///< free joint axes (min < max)
  ModelPose pose_;
  std::vector<Vec3> positions_, trialPositions_;
  JointAngles trial_;
  std::span<const float> weights_;  ///< FitOptions::weights of the fit in progress
};

/// KeypointFitter(model).fit21(keypoints, options) in one call.
Result<FitResult> fitToKeypoints(const ArticulatedModel& model,
                                 const std::array<Vec3, 21>& keypoints,
                                 const FitOptions& options = {});

}  // namespace dynahand::model
