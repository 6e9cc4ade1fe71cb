// Models as physics: the non-hand arm simulates under gravity; the hand rests; angle
// conventions agree with the physics joints.
#include <gtest/gtest.h>

#include <random>

#include "dynahand/model.h"
#include "dynahand/model_pose.h"
#include "dynahand/model_world.h"
#include "dynahand/physics_angles.h"
#include "model/model_test_util.h"

namespace dynahand::model {
namespace {

std::filesystem::path armPath() {
  return std::filesystem::path(DYNAHAND_SOURCE_DIR) / "tests/model/data/three_link_arm.json";
}

TEST(ModelWorld, JointRotationIsThePhysicsConventionInModelAxes) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> angle(-1.4f, 1.4f);
  const Quat c = modelToPhysicsFrame();
  for (int trial = 0; trial < 200; ++trial) {
    const Vec3 a(angle(rng), angle(rng), angle(rng));
    const Quat physics = c * physics::composeJointRotation(toPhysicsAngles(a)) * c.conjugate();
    EXPECT_LT(jointRotation(a).angularDistance(physics), 1e-5f);
    EXPECT_LT(
        (fromPhysicsAngles(physics::decomposeJointRotation(c.conjugate() * jointRotation(a) * c)) -
         a)
            .norm(),
        1e-4f);
  }
}

TEST(ModelWorld, ArmModelFromAFileSimulatesUnderGravity) {
  const Result<ArticulatedModel> arm = loadModel(armPath());
  ASSERT_TRUE(arm.ok()) << arm.message();
  physics::WorldSettings settings;
  settings.gravity = Vec3(0, -9.81f, 0);
  physics::World world(settings);
  const ModelPose start = forwardKinematics(*arm, zeroAngles(*arm));  // standing straight up (+z)
  WorldBuildOptions options;
  options.staticRoot = true;
  const ModelInWorld ids = addToWorld(world, *arm, start, options);
  ASSERT_EQ(ids.bodies.size(), 4u);
  ASSERT_EQ(ids.joints.size(), 3u);
  // Nudge it so it falls toward -y (positive flexion).
  world.setVelocity(ids.bodies[1], Vec3(0, -0.05f, 0), Vec3::Zero());
  ModelPose pose;
  JointAngles angles;
  const float dt = 1.0f / 120.0f;
  for (int step = 0; step < 240; ++step) {
    world.step(dt);
    readPose(world, ids, pose);
    jointAnglesInto(*arm, pose, angles);
    for (size_t j = 0; j < ids.joints.size(); ++j) {
      ASSERT_LT(world.jointSeparation(ids.joints[j]), 0.005f) << "step " << step;
      // The world's angles and the model's angles of the same poses agree.
      EXPECT_LT((fromPhysicsAngles(world.jointAngles(ids.joints[j])) - angles.angles[j]).norm(),
                1e-3f);
    }
    ASSERT_TRUE(withinLimits(*arm, angles, 0.05f)) << "step " << step;
  }
  EXPECT_EQ(pose.bodies[0].p, start.bodies[0].p);  // static base
  // The arm fell toward -y: the shoulder flexed well past 45 degrees (it is limited to 90).
  EXPECT_GT(angles.angles[0].x(), 0.8f);
  const Vec3 tip = pose.bodies[3].transform(Vec3(0, 0, 0.15f));
  EXPECT_LT(tip.y(), -0.3f);
}

TEST(ModelWorld, DefaultHandRestsWithoutContactsPushingItApart) {
  const ArticulatedModel hand = makeDefaultHand();
  physics::World world;  // no gravity
  std::mt19937 rng(2);
  const ModelPose start = forwardKinematics(hand, fixtures::randomValidAngles(hand, rng));
  const ModelInWorld ids = addToWorld(world, hand, start);
  ModelPose pose;
  for (int step = 0; step < 30; ++step) world.step(1.0f / 60.0f);
  readPose(world, ids, pose);
  // Random valid poses can press fingers together, so allow small settling; nothing flies.
  for (size_t b = 0; b < pose.bodies.size(); ++b)
    EXPECT_LT((pose.bodies[b].p - start.bodies[b].p).norm(), 0.01f);
  // At rest, nothing collides: the flat hand does not move at all.
  physics::World flat;
  const ModelPose rest = forwardKinematics(hand, zeroAngles(hand));
  const ModelInWorld flatIds = addToWorld(flat, hand, rest);
  for (int step = 0; step < 30; ++step) flat.step(1.0f / 60.0f);
  readPose(flat, flatIds, pose);
  for (size_t b = 0; b < pose.bodies.size(); ++b)
    EXPECT_LT((pose.bodies[b].p - rest.bodies[b].p).norm(), 1e-4f);
}

}  // namespace
}  // namespace dynahand::model
