#include <gtest/gtest.h>

#include <random>

#include "track/hand_rig.h"

namespace dynahand::track {
namespace {

// A pose inside the joint limits must be an equilibrium of the rig: with no data rows,
// stepping changes nothing (limits and joints agree with the model). Contacts are off:
// random angles can put a finger into its neighbour, which contacts rightly push apart.
TEST(HandRig, ValidPosesAreAtRest) {
  const auto hand = model::makeDefaultHand();
  physics::WorldSettings settings;
  settings.enableContacts = false;
  auto rig = HandRig::create(hand, settings, RigSettings{}, 1.0f / 60);
  ASSERT_TRUE(rig.ok()) << rig.message();
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(0.1f, 0.9f);
  for (int trial = 0; trial < 5; ++trial) {
    model::JointAngles a = model::zeroAngles(hand);
    for (int j = 0; j < hand.jointCount(); ++j) {
      const auto& joint = hand.joints()[static_cast<std::size_t>(j)];
      for (int k = 0; k < 3; ++k) {
        a.angles[static_cast<std::size_t>(j)][k] =
            joint.minAngle[k] + u(rng) * (joint.maxAngle[k] - joint.minAngle[k]);
      }
    }
    a.root.p = Vec3(0, 0, 0.4f);
    const auto pose = model::forwardKinematics(hand, a);
    rig->setPose(pose);
    for (int s = 0; s < 10; ++s) {
      rig->world().rows().clear();
      rig->world().step(1.0f / 60);
    }
    model::ModelPose after;
    rig->readPose(after);
    const auto k0 = model::keypoints21(hand, pose);
    const auto k1 = model::keypoints21(hand, after);
    float worst = 0;
    for (int i = 0; i < 21; ++i)
      worst = std::max(worst,
                       (k0[static_cast<std::size_t>(i)] - k1[static_cast<std::size_t>(i)]).norm());
    EXPECT_LT(worst, 0.002f) << "trial " << trial;
  }
}

TEST(HandRig, PhysicsJointAnglesMatchModelAngles) {
  const auto hand = model::makeDefaultHand();
  auto rig = HandRig::create(hand, physics::WorldSettings{}, RigSettings{}, 1.0f / 60);
  ASSERT_TRUE(rig.ok());
  model::JointAngles a = model::zeroAngles(hand);
  for (int j = 0; j < hand.jointCount(); ++j) {
    const auto& joint = hand.joints()[static_cast<std::size_t>(j)];
    a.angles[static_cast<std::size_t>(j)] = 0.5f * (joint.minAngle + joint.maxAngle);
  }
  rig->setPose(model::forwardKinematics(hand, a));
  for (int j = 0; j < hand.jointCount(); ++j) {
    const Vec3 m = a.angles[static_cast<std::size_t>(j)];
    const Vec3 p = rig->world().jointAngles(j);
    EXPECT_NEAR(p.x(), m.x(), 1e-4f) << "joint " << j;
    EXPECT_NEAR(p.y(), -m.y(), 1e-4f) << "joint " << j;
    EXPECT_NEAR(p.z(), m.z(), 1e-4f) << "joint " << j;
  }
}

}  // namespace
}  // namespace dynahand::track
