// Keypoint fitting: Umeyama alignment of the keypoints rigid with one body, then
// Levenberg-Marquardt on (root translation, root rotation, free joint angles, scale).
// Jacobian columns are analytic: a rotation about world axis a through centre c moves a
// downstream point p by a x (p - c); the scale moves p by (p - root) / s.
#include <algorithm>
#include <cmath>

#include <fmt/format.h>
#include <Eigen/Cholesky>
#include <Eigen/Geometry>

#include "dynahand/model_fit.h"

namespace dynahand::model {
namespace {

// Target i's weight in the cost (1 without weights).
float weightOf(std::span<const float> weights, std::size_t i) {
  return weights.empty() ? 1.0f : weights[i];
}

Mat3 skew(const Vec3& v) {
  Mat3 m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

Quat expMap(const Vec3& w) {
  const float angle = w.norm();
  if (angle < 1e-12f) return Quat::Identity();
  return Quat(Eigen::AngleAxisf(angle, w / angle));
}

}  // namespace

KeypointFitter::KeypointFitter(const ArticulatedModel& model) : model_(&model) {
  for (int j = 0; j < model.jointCount(); ++j) {
    const Joint& joint = model.joints()[static_cast<size_t>(j)];
    for (int axis = 0; axis < 3; ++axis) {
      if (joint.maxAngle[axis] > joint.minAngle[axis]) params_.push_back({j, axis});
    }
  }
  trial_ = zeroAngles(model);
}

float KeypointFitter::evaluate(std::span<const int> keypoints, std::span<const Vec3> targets,
                               const JointAngles& angles, float scale,
                               std::vector<Vec3>& positions) {
  forwardKinematicsInto(*model_, angles, pose_);
  positions.resize(keypoints.size());
  float cost = 0.0f;
  for (size_t i = 0; i < keypoints.size(); ++i) {
    const Keypoint& kp = model_->keypoints()[static_cast<size_t>(keypoints[i])];
    const Vec3 unscaled = pose_.bodies[static_cast<size_t>(kp.body)].transform(kp.point);
    positions[i] = angles.root.p + scale * (unscaled - angles.root.p);
    cost += weightOf(weights_, i) * (positions[i] - targets[i]).squaredNorm();
  }
  return cost;
}

bool KeypointFitter::rigidStart(std::span<const int> keypoints, std::span<const Vec3> targets,
                                bool fitScale, JointAngles& angles, float& scale) {
  const ArticulatedModel& model = *model_;
  // Keypoints rigid with body b: on b, or at the centre of the joint from b to a child.
  auto rigidWith = [&](const Keypoint& kp, int b) {
    if (kp.body == b) return true;
    const Body& body = model.bodies()[static_cast<size_t>(kp.body)];
    return body.parent == b &&
           (kp.point - model.joints()[static_cast<size_t>(body.joint)].anchorChild).norm() < 1e-7f;
  };
  int best = -1;
  int bestCount = 0;
  for (int b = 0; b < model.bodyCount(); ++b) {
    int count = 0;
    for (const int k : keypoints)
      count += rigidWith(model.keypoints()[static_cast<size_t>(k)], b) ? 1 : 0;
    if (count > bestCount) {
      best = b;
      bestCount = count;
    }
  }
  if (bestCount < 3) return false;
  angles.root = Pose::identity();
  evaluate(keypoints, targets, angles, 1.0f, positions_);
  // Double precision: also avoids a GCC 12 false -Warray-bounds inside Eigen's float path.
  Eigen::Matrix3Xd src(3, bestCount);
  Eigen::Matrix3Xd dst(3, bestCount);
  int column = 0;
  for (size_t i = 0; i < keypoints.size(); ++i) {
    if (!rigidWith(model.keypoints()[static_cast<size_t>(keypoints[i])], best)) continue;
    src.col(column) = positions_[i].cast<double>();
    dst.col(column) = targets[i].cast<double>();
    ++column;
  }
  const Eigen::Matrix4f t = Eigen::umeyama(src, dst, fitScale).cast<float>();
  Mat3 sr = t.block<3, 3>(0, 0);
  const float s = fitScale ? std::cbrt(sr.determinant()) : 1.0f;
  if (!(s > 0.0f) || !sr.allFinite()) return false;
  angles.root = Pose{t.block<3, 1>(0, 3), Quat(Mat3(sr / s)).normalized()};
  scale = s;
  return true;
}

float KeypointFitter::run(std::span<const int> keypoints, std::span<const Vec3> targets,
                          const FitOptions& options, JointAngles& angles, float& scale,
                          int& iterations) {
  const ArticulatedModel& model = *model_;
  const int rows = static_cast<int>(keypoints.size()) * 3;
  const int jointParams = static_cast<int>(params_.size());
  const int n = 6 + jointParams + (options.fitScale ? 1 : 0);
  Eigen::MatrixXd jac(rows, n);
  Eigen::VectorXd residual(rows);
  Eigen::MatrixXd normal(n, n);
  Eigen::VectorXd gradient(n);
  Eigen::VectorXd step(n);
  std::vector<Vec3> axes(static_cast<size_t>(jointParams));
  std::vector<Vec3> centres(static_cast<size_t>(jointParams));

  const float goal =
      options.meanErrorGoal * options.meanErrorGoal * static_cast<float>(keypoints.size());
  float cost = evaluate(keypoints, targets, angles, scale, positions_);
  double lambda = 1e-3;
  for (int it = 0; it < options.maxIterations && cost > goal; ++it) {
    ++iterations;
    // Jacobian at the current state (pose_ and positions_ are current). A joint angle turns
    // the child about a world axis through the joint centre; the angular rate per radian
    // comes from a central difference of the joint rotation (swing-twist is not a fixed-axis
    // product), so each column is exact to O(h^2).
    constexpr float h = 1e-3f;
    for (int k = 0; k < jointParams; ++k) {
      const Param& param = params_[static_cast<size_t>(k)];
      const Joint& joint = model.joints()[static_cast<size_t>(param.joint)];
      Vec3 plus = angles.angles[static_cast<size_t>(param.joint)];
      Vec3 minus = plus;
      plus[param.axis] += h;
      minus[param.axis] -= h;
      Quat delta = jointRotation(plus) * jointRotation(minus).conjugate();
      if (delta.w() < 0.0f) delta.coeffs() = -delta.coeffs();
      const Vec3 rateLocal = delta.vec() / h;  // rotation vector 2 * vec over the step 2h
      axes[static_cast<size_t>(k)] =
          pose_.bodies[static_cast<size_t>(joint.parent)].q * (joint.frame * rateLocal);
      const Vec3 centre =
          pose_.bodies[static_cast<size_t>(joint.child)].transform(joint.anchorChild);
      centres[static_cast<size_t>(k)] = angles.root.p + scale * (centre - angles.root.p);
    }
    jac.setZero();
    for (size_t i = 0; i < keypoints.size(); ++i) {
      const int row = static_cast<int>(i) * 3;
      const Vec3& p = positions_[i];
      const Vec3 fromRoot = p - angles.root.p;
      residual.segment<3>(row) = (p - targets[i]).cast<double>();
      jac.block<3, 3>(row, 0).setIdentity();
      jac.block<3, 3>(row, 3) = (-skew(fromRoot)).cast<double>();
      const int body = model.keypoints()[static_cast<size_t>(keypoints[i])].body;
      for (int k = 0; k < jointParams; ++k) {
        const Joint& joint =
            model.joints()[static_cast<size_t>(params_[static_cast<size_t>(k)].joint)];
        if (!model.isAncestorOrSelf(joint.child, body)) continue;
        jac.block<3, 1>(row, 6 + k) =
            axes[static_cast<size_t>(k)].cross(p - centres[static_cast<size_t>(k)]).cast<double>();
      }
      if (options.fitScale) jac.block<3, 1>(row, n - 1) = (fromRoot / scale).cast<double>();
      if (!weights_.empty()) {
        const double root = std::sqrt(static_cast<double>(weights_[i]));
        residual.segment<3>(row) *= root;
        jac.middleRows<3>(row) *= root;
      }
    }
    normal.noalias() = jac.transpose() * jac;
    gradient.noalias() = jac.transpose() * residual;

    bool improved = false;
    while (!improved && lambda < 1e8) {
      Eigen::MatrixXd damped = normal;
      for (int c = 0; c < n; ++c) damped(c, c) += lambda * normal(c, c) + 1e-9;
      step = damped.ldlt().solve(-gradient);
      trial_.root.p = angles.root.p + step.segment<3>(0).cast<float>();
      trial_.root.q = (expMap(step.segment<3>(3).cast<float>()) * angles.root.q).normalized();
      trial_.angles = angles.angles;
      for (int k = 0; k < jointParams; ++k) {
        const Param& param = params_[static_cast<size_t>(k)];
        trial_.angles[static_cast<size_t>(param.joint)][param.axis] +=
            static_cast<float>(step(6 + k));
      }
      clampToLimits(model, trial_);
      float trialScale = scale;
      if (options.fitScale) {
        trialScale =
            std::clamp(scale + static_cast<float>(step(n - 1)), options.minScale, options.maxScale);
      }
      const float trialCost = evaluate(keypoints, targets, trial_, trialScale, trialPositions_);
      if (trialCost < cost) {
        improved = true;
        const float decrease = cost - trialCost;
        std::swap(angles.angles, trial_.angles);
        angles.root = trial_.root;
        scale = trialScale;
        std::swap(positions_, trialPositions_);
        cost = trialCost;
        lambda = std::max(lambda * 0.3, 1e-7);
        // Converged: the step no longer changes the cost measurably.
        if (decrease < 1e-6f * cost + 1e-14f) it = options.maxIterations;
      } else {
        lambda *= 10.0;
      }
    }
    if (!improved) break;
    forwardKinematicsInto(model, angles,
                          pose_);  // positions_ already match; pose_ for the next Jacobian
  }
  return cost;
}

Result<FitResult> KeypointFitter::fit(std::span<const int> keypointIndices,
                                      std::span<const Vec3> targets, const FitOptions& options) {
  const ArticulatedModel& model = *model_;
  if (keypointIndices.size() != targets.size()) {
    return Error{fmt::format("fitToKeypoints: {} keypoint indices for {} targets",
                             keypointIndices.size(), targets.size())};
  }
  if (targets.size() < 3) return Error{"fitToKeypoints: at least 3 target keypoints are needed"};
  for (size_t i = 0; i < targets.size(); ++i) {
    if (!targets[i].allFinite())
      return Error{fmt::format("fitToKeypoints: target {} is not finite", i)};
    if (keypointIndices[i] < 0 ||
        keypointIndices[i] >= static_cast<int>(model.keypoints().size())) {
      return Error{
          fmt::format("fitToKeypoints: keypoint index {} out of range", keypointIndices[i])};
    }
  }
  if (!options.weights.empty()) {
    if (options.weights.size() != targets.size())
      return Error{fmt::format("fitToKeypoints: {} weights for {} targets", options.weights.size(),
                               targets.size())};
    for (size_t i = 0; i < options.weights.size(); ++i) {
      if (!(std::isfinite(options.weights[i]) && options.weights[i] >= 0.0f))
        return Error{fmt::format("fitToKeypoints: weight {} is negative or not finite", i)};
    }
  }
  weights_ = options.weights;

  // Starts: the given pose, or the rigid alignment with straight joints and, if that does
  // not converge, with joints half-way into flexion (curled hands).
  FitResult best;
  best.meanError = std::numeric_limits<float>::infinity();
  float bestScore = std::numeric_limits<float>::infinity();
  const int starts = options.initial ? 1 : 2;
  for (int start = 0; start < starts; ++start) {
    JointAngles angles = options.initial ? *options.initial : zeroAngles(model);
    float scale = 1.0f;
    if (!options.initial) {
      for (size_t j = 0; j < angles.angles.size(); ++j) {
        angles.angles[j].x() = start == 0 ? 0.0f : 0.5f * model.joints()[j].maxAngle.x();
      }
      clampToLimits(model, angles);
      if (!rigidStart(keypointIndices, targets, options.fitScale, angles, scale)) {
        return Error{"fitToKeypoints: fewer than 3 target keypoints are fixed to a single body"};
      }
    } else {
      if (angles.angles.size() != model.joints().size())
        return Error{"fitToKeypoints: initial angles do not match the model"};
      clampToLimits(model, angles);
    }
    int iterations = 0;
    const float cost = run(keypointIndices, targets, options, angles, scale, iterations);
    best.iterations += iterations;
    float sum = 0.0f;
    float worst = 0.0f;
    float weighted = 0.0f;
    float weightSum = 0.0f;
    evaluate(keypointIndices, targets, angles, scale, positions_);
    for (size_t i = 0; i < targets.size(); ++i) {
      const float d = (positions_[i] - targets[i]).norm();
      sum += d;
      worst = std::max(worst, d);
      weighted += weightOf(weights_, i) * d;
      weightSum += weightOf(weights_, i);
    }
    const float mean = sum / static_cast<float>(targets.size());
    (void)cost;
    // The starts compared by the weighted mean distance: what the fit minimises.
    const float score = weightSum > 0.0f ? weighted / weightSum : mean;
    if (score < bestScore) {
      bestScore = score;
      best.angles = std::move(angles);
      best.scale = scale;
      best.meanError = mean;
      best.maxError = worst;
    }
    if (bestScore < 1e-4f) break;  // 0.1 mm: a second start cannot do meaningfully better
  }
  weights_ = {};
  return best;
}

Result<FitResult> KeypointFitter::fit21(const std::array<Vec3, 21>& targets,
                                        const FitOptions& options) {
  if (!model_->hasKeypoints21())
    return Error{"fitToKeypoints: the model does not name the 21 hand keypoints"};
  return fit(model_->keypoints21Indices(), targets, options);
}

Result<FitResult> fitToKeypoints(const ArticulatedModel& model,
                                 const std::array<Vec3, 21>& keypoints, const FitOptions& options) {
  KeypointFitter fitter(model);
  return fitter.fit21(keypoints, options);
}

}  // namespace dynahand::model
