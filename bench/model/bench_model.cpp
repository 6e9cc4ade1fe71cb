// Model hot paths the tracker calls per step (FK, angles, keypoints) and the fit used to
// initialise tracking. Fixed random valid poses (seeded), prepared outside the timed loops.
#include <benchmark/benchmark.h>

#include <random>

#include "dynahand/model.h"
#include "dynahand/model_fit.h"
#include "dynahand/model_pose.h"

namespace dynahand::model {
namespace {

const ArticulatedModel& hand() {
  static const ArticulatedModel model = makeDefaultHand();
  return model;
}

std::vector<JointAngles> randomPoses(int count) {
  std::mt19937 rng(1234);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  std::vector<JointAngles> out;
  for (int i = 0; i < count; ++i) {
    JointAngles a = zeroAngles(hand());
    for (size_t j = 0; j < a.angles.size(); ++j) {
      const Joint& joint = hand().joints()[j];
      for (int axis = 0; axis < 3; ++axis) {
        a.angles[j][axis] =
            joint.minAngle[axis] + unit(rng) * (joint.maxAngle[axis] - joint.minAngle[axis]);
      }
    }
    a.root.p = Vec3(0.0f, 0.0f, 0.4f);
    a.root.q = Quat(
        Eigen::AngleAxisf(6.0f * unit(rng), Vec3(unit(rng), unit(rng), unit(rng)).normalized()));
    out.push_back(a);
  }
  return out;
}

void BM_ForwardKinematics(benchmark::State& state) {
  const auto poses = randomPoses(64);
  ModelPose out;
  size_t i = 0;
  for (auto _ : state) {
    forwardKinematicsInto(hand(), poses[i++ % poses.size()], out);
    benchmark::DoNotOptimize(out.bodies.data());
  }
}
BENCHMARK(BM_ForwardKinematics);

void BM_JointAngles(benchmark::State& state) {
  std::vector<ModelPose> poses;
  for (const auto& a : randomPoses(64)) poses.push_back(forwardKinematics(hand(), a));
  JointAngles out;
  size_t i = 0;
  for (auto _ : state) {
    jointAnglesInto(hand(), poses[i++ % poses.size()], out);
    benchmark::DoNotOptimize(out.angles.data());
  }
}
BENCHMARK(BM_JointAngles);

void BM_Keypoints21(benchmark::State& state) {
  std::vector<ModelPose> poses;
  for (const auto& a : randomPoses(64)) poses.push_back(forwardKinematics(hand(), a));
  size_t i = 0;
  for (auto _ : state) {
    auto k = keypoints21(hand(), poses[i++ % poses.size()]);
    benchmark::DoNotOptimize(k.data());
  }
}
BENCHMARK(BM_Keypoints21);

void BM_OpenXr26(benchmark::State& state) {
  std::vector<ModelPose> poses;
  for (const auto& a : randomPoses(64)) poses.push_back(forwardKinematics(hand(), a));
  size_t i = 0;
  for (auto _ : state) {
    auto x = openxr26(hand(), poses[i++ % poses.size()]);
    benchmark::DoNotOptimize(x.data());
  }
}
BENCHMARK(BM_OpenXr26);

// One complete fit from 21 keypoints (rigid start + Levenberg-Marquardt), per random pose.
void BM_FitToKeypoints(benchmark::State& state) {
  std::vector<std::array<Vec3, 21>> targets;
  for (const auto& a : randomPoses(32))
    targets.push_back(keypoints21(hand(), forwardKinematics(hand(), a)));
  KeypointFitter fitter(hand());
  size_t i = 0;
  float worst = 0.0f;
  for (auto _ : state) {
    const Result<FitResult> fit = fitter.fit21(targets[i++ % targets.size()]);
    worst = std::max(worst, fit->meanError);
    benchmark::DoNotOptimize(fit->angles.angles.data());
  }
  state.counters["worstMeanErrorUm"] = static_cast<double>(worst) * 1e6;
}
BENCHMARK(BM_FitToKeypoints)->Unit(benchmark::kMillisecond);

void BM_MakeDefaultHand(benchmark::State& state) {
  for (auto _ : state) {
    ArticulatedModel m = makeDefaultHand();
    benchmark::DoNotOptimize(m.bodyCount());
  }
}
BENCHMARK(BM_MakeDefaultHand)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace dynahand::model
