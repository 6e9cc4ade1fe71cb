// The simulator's point handling: weighted pulls (a point standing for thinned ones) and
// simulations running on a kept part of the frame-start mapping's points
// (TrackerSettings::palmPointCap).
#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "dynahand/model.h"
#include "track/hand_rig.h"
#include "track/simulation.h"

namespace dynahand::track {
namespace {

struct HandAtRest {
  model::ArticulatedModel hand = model::makeDefaultHand();
  HandRig rig;
  std::vector<Vec3> points;
};

// The open hand 40 cm away and sample points on and around its bodies (the rig's keypoints
// and points a little off them).
HandAtRest makeHandAtRest() {
  const model::ArticulatedModel hand = model::makeDefaultHand();
  auto rig = HandRig::create(hand, physics::WorldSettings{}, RigSettings{}, 1.0f / 60);
  EXPECT_TRUE(rig.ok()) << rig.message();
  model::JointAngles a = model::zeroAngles(hand);
  model::clampToLimits(hand, a);
  a.root.p = Vec3(0.0f, 0.0f, 0.4f);
  const model::ModelPose pose = model::forwardKinematics(hand, a);
  rig->setPose(pose);
  HandAtRest s{hand, std::move(*rig), {}};
  for (const Vec3& k : model::keypoints21(hand, pose)) {
    s.points.push_back(k);
    s.points.push_back(k + Vec3(0.004f, -0.003f, -0.006f));
    s.points.push_back(k + Vec3(-0.005f, 0.002f, -0.008f));
  }
  return s;
}

SimulationSettings everyPoint() {
  SimulationSettings settings;
  settings.pointSubsets = 1;
  settings.silhouetteForce = 0.0f;
  return settings;
}

TEST(Simulator, WeightedPointsShareThePullInProportion) {
  HandAtRest s = makeHandAtRest();
  const SimulationSettings settings = everyPoint();
  std::vector<float> weights;
  for (std::size_t i = 0; i < s.points.size(); ++i)
    weights.push_back(1.0f + static_cast<float>(i % 4));
  Simulator simulator(settings);
  simulator.beginFrame();
  FrameInput input{s.points, {}, {}, nullptr, nullptr, weights};
  simulator.prepareStep(s.rig, input);
  const physics::SurfaceRows& rows = s.rig.world().rows();
  ASSERT_EQ(rows.upper.size(), s.points.size()) << "every point near the hand makes one row";
  float weightSum = 0.0f, capSum = 0.0f;
  for (const float w : weights) weightSum += w;
  for (std::size_t i = 0; i < rows.upper.size(); ++i) {
    capSum += rows.upper[i];
    EXPECT_FLOAT_EQ(rows.upper[i] / weights[i], rows.upper[0] / weights[0]) << "row " << i;
  }
  // The total stays pullForce (N s per step), whatever the weights.
  EXPECT_NEAR(capSum, settings.pullForce * settings.stepDt, 1e-3f * capSum);
  EXPECT_FLOAT_EQ(rows.upper[0], settings.pullForce * settings.stepDt * weights[0] / weightSum);
}

// The world's rows as numbers (bodies, anchors, normals, targets, bounds), appended to out.
void appendRows(const physics::SurfaceRows& rows, std::vector<float>& out) {
  for (std::size_t i = 0; i < rows.body.size(); ++i) {
    out.push_back(static_cast<float>(rows.body[i]));
    for (int k = 0; k < 3; ++k) {
      out.push_back(rows.anchor[i][k]);
      out.push_back(rows.normal[i][k]);
      out.push_back(rows.target[i][k]);
    }
    out.push_back(rows.lower[i]);
    out.push_back(rows.upper[i]);
  }
}

// Rows of `steps` physics steps of a simulation sharing `shared`'s frame-start mapping.
std::vector<float> rowsOfSteps(HandAtRest& s, const Simulator& shared, const FrameInput& input,
                               int steps) {
  Simulator lane(SimulationSettings{});
  lane.beginFrame(&shared);
  std::vector<float> out;
  for (int step = 0; step < steps; ++step) {
    lane.prepareStep(s.rig, input);
    appendRows(s.rig.world().rows(), out);
    if (step + 1 < steps) s.rig.world().step(1.0f / 60);
  }
  return out;
}

TEST(Simulator, KeptPointsMapAsIfTheyWereTheFramesOnly) {
  // Every third point kept: the simulations then pull exactly as if the frame had held only
  // those points (a point's mapping does not depend on the others).
  HandAtRest a = makeHandAtRest();
  HandAtRest b = makeHandAtRest();
  std::vector<int> kept;
  std::vector<Vec3> keptPoints;
  for (std::size_t i = 0; i < a.points.size(); i += 3) {
    kept.push_back(static_cast<int>(i));
    keptPoints.push_back(a.points[i]);
  }
  Simulator all(SimulationSettings{});
  all.mapFrameStart(a.rig, FrameInput{a.points, {}, {}, nullptr, nullptr, {}});
  all.keepPoints(kept, keptPoints);
  const FrameInput keptInput{keptPoints, {}, {}, nullptr, nullptr, {}};
  const std::vector<float> thinned = rowsOfSteps(a, all, keptInput, 2);

  Simulator only(SimulationSettings{});
  only.mapFrameStart(b.rig, keptInput);
  const std::vector<float> direct = rowsOfSteps(b, only, keptInput, 2);
  ASSERT_FALSE(direct.empty());
  EXPECT_EQ(thinned, direct);
}

// Rows of one first step of a simulation sharing `shared`'s mapping, as numbers.
std::vector<float> firstStepRows(HandAtRest& s, const Simulator& shared, const FrameInput& input) {
  return rowsOfSteps(s, shared, input, 1);
}

TEST(Simulator, FirstStepRowsSharedOnlyFromTheSameState) {
  HandAtRest a = makeHandAtRest();
  const FrameInput input{a.points, {}, {}, nullptr, nullptr, {}};
  Simulator built(SimulationSettings{}), prepared(SimulationSettings{});
  built.mapFrameStart(a.rig, input);
  prepared.mapFrameStart(a.rig, input);
  prepared.prepareFrameStartRows(a.rig, input);
  const std::vector<float> own = firstStepRows(a, built, input);
  ASSERT_FALSE(own.empty());
  EXPECT_EQ(firstStepRows(a, prepared, input), own);
  // Another input object, or the bodies moved: the simulation builds its own rows.
  const FrameInput fewer{
      std::span(a.points).first(a.points.size() / 2), {}, {}, nullptr, nullptr, {}};
  EXPECT_EQ(firstStepRows(a, prepared, fewer), firstStepRows(a, built, fewer));
  EXPECT_NE(firstStepRows(a, prepared, fewer), own);
  model::ModelPose moved;
  a.rig.readPose(moved);
  for (Pose& body : moved.bodies) body.p.x() += 0.003f;
  a.rig.setPose(moved);
  const std::vector<float> movedRows = firstStepRows(a, built, input);
  EXPECT_NE(movedRows, own);
  EXPECT_EQ(firstStepRows(a, prepared, input), movedRows);
}

}  // namespace
}  // namespace dynahand::track
