// Free motion, pendulum, chains, energy: the world against closed forms.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "dynahand/physics_world.h"
#include "physics/physics_scenes.h"

namespace dynahand::physics {
namespace {

constexpr float kDt = 1.0f / 60.0f;

BodyDef boxBody(int shape, const Vec3& position, float mass = 1.0f) {
  BodyDef d;
  d.shape = shape;
  d.pose.p = position;
  d.mass = mass;
  return d;
}

TEST(Dynamics, FreeFallMatchesAnalyticTrajectory) {
  WorldSettings settings;
  settings.gravity = Vec3(0.0f, 9.81f, 0.0f);  // camera frame: y down
  World w(settings);
  const int box = w.addShape(ConvexShape::box(Vec3(0.01f, 0.01f, 0.01f)));
  BodyDef d = boxBody(box, Vec3(0.1f, -0.2f, 0.5f));
  d.linearVelocity = Vec3(0.3f, -2.0f, 0.1f);
  const BodyId b = w.addBody(d);
  const int steps = 120;
  for (int i = 0; i < steps; ++i) w.step(kDt);
  const float t = steps * kDt;
  const Vec3 analytic = d.pose.p + d.linearVelocity * t + 0.5f * settings.gravity * t * t;
  // Semi-implicit Euler: x_n = x0 + v0 t + g h^2 n(n+1)/2, i.e. analytic + g h t / 2.
  const Vec3 discrete = analytic + 0.5f * settings.gravity * kDt * t;
  EXPECT_LT((w.pose(b).p - discrete).norm(), 1e-4f);
  EXPECT_LT((w.pose(b).p - analytic).norm(), 0.5f * 9.81f * kDt * t + 1e-4f);
  EXPECT_LT((w.linearVelocity(b) - (d.linearVelocity + settings.gravity * t)).norm(), 1e-4f);
}

// Compound pendulum: a box hanging from a static body by a ball joint 0.3 m above its centre.
TEST(Dynamics, PendulumPeriodWithinOnePercent) {
  WorldSettings settings;
  settings.gravity = Vec3(0.0f, -9.81f, 0.0f);
  settings.enableContacts = false;
  World w(settings);
  const int small = w.addShape(ConvexShape::box(Vec3(0.02f, 0.02f, 0.02f)));
  BodyDef anchorDef = boxBody(small, Vec3::Zero());
  anchorDef.type = BodyType::Static;
  const BodyId anchor = w.addBody(anchorDef);
  const float length = 0.3f, amplitude = 0.05f;
  BodyDef bobDef =
      boxBody(small, Vec3(length * std::sin(amplitude), -length * std::cos(amplitude), 0.0f));
  const BodyId bob = w.addBody(bobDef);
  JointDef j;
  j.parent = anchor;
  j.child = bob;
  j.anchorChild = w.pose(bob).inverseTransform(Vec3::Zero());
  w.addJoint(j);
  const float side = 0.04f;
  const float inertiaCm = side * side / 6.0f;  // m (s^2 + s^2) / 12 with m = 1
  const float expected =
      2.0f * static_cast<float>(M_PI) * std::sqrt((inertiaCm + length * length) / (9.81f * length));
  // Period from upward zero crossings of x over ~8 periods (linear interpolation).
  std::vector<float> crossings;
  float prevX = w.centerOfMass(bob).x();
  for (int i = 1; i <= static_cast<int>(9.0f * expected / kDt); ++i) {
    w.step(kDt);
    const float x = w.centerOfMass(bob).x();
    if (prevX < 0.0f && x >= 0.0f)
      crossings.push_back((static_cast<float>(i) - x / (x - prevX)) * kDt);
    prevX = x;
  }
  ASSERT_GE(crossings.size(), 6u);
  const float period =
      (crossings.back() - crossings.front()) / static_cast<float>(crossings.size() - 1);
  EXPECT_NEAR(period, expected, 0.01f * expected) << "expected " << expected;
}

// 17 finger-bone-sized links (3 cm, 1 kg) in a chain whose root is a kinematic body waved
// around (0.05 m at 1 Hz, turning at up to 2 rad/s) for 10 s without gravity, stepped at the
// tracker's substep rate (240 Hz): every anchor pair stays within 0.1 mm.
TEST(Dynamics, SeventeenBodyChainAnchorsDriftUnderTenthMillimetre) {
  World w;
  const float half = 0.015f, dt = 1.0f / 240.0f;
  const int link = w.addShape(ConvexShape::box(Vec3(half, 0.005f, 0.005f)));
  BodyDef rootDef = boxBody(link, Vec3::Zero());
  rootDef.type = BodyType::Kinematic;
  const BodyId root = w.addBody(rootDef);
  BodyId prev = root;
  std::vector<JointId> joints;
  for (int i = 1; i <= 17; ++i) {
    const BodyId b =
        w.addBody(boxBody(link, Vec3(2.0f * half * static_cast<float>(i), 0.0f, 0.0f)));
    JointDef j;
    j.parent = prev;
    j.child = b;
    j.anchorParent = Vec3(half, 0, 0);
    j.anchorChild = Vec3(-half, 0, 0);
    joints.push_back(w.addJoint(j));
    prev = b;
  }
  const float twoPi = 2.0f * static_cast<float>(M_PI);
  float worst = 0.0f, tipTravel = 0.0f;
  Vec3 tipPrev = w.centerOfMass(prev);
  for (int i = 0; i < 2400; ++i) {
    const float t = static_cast<float>(i) * dt;
    w.setVelocity(root, Vec3(0, 0.05f * twoPi * std::cos(twoPi * t), 0),
                  Vec3(0, 0, 2.0f * std::cos(3.0f * t)));
    w.step(dt);
    for (JointId j : joints) worst = std::max(worst, w.jointSeparation(j));
    tipTravel += (w.centerOfMass(prev) - tipPrev).norm();
    tipPrev = w.centerOfMass(prev);
  }
  EXPECT_LT(worst, 1e-4f);
  EXPECT_GT(tipTravel, 1.0f);  // the chain really moved (m)
}

TEST(Dynamics, UndampedUnconstrainedEnergyDoesNotGrow) {
  World w;  // no gravity, no damping
  const int plank = w.addShape(ConvexShape::box(Vec3(0.05f, 0.02f, 0.01f)));
  const int cube = w.addShape(ConvexShape::box(Vec3(0.03f, 0.03f, 0.03f)));
  scenes::Rng rng(3);
  for (int i = 0; i < 6; ++i) {
    BodyDef d = boxBody(i % 2 ? plank : cube, Vec3(0.15f * static_cast<float>(i % 3),
                                                   0.15f * static_cast<float>(i / 3), 0.0f));
    d.linearVelocity =
        Vec3(rng.uniform(-0.2f, 0.2f), rng.uniform(-0.2f, 0.2f), rng.uniform(-0.2f, 0.2f));
    d.angularVelocity = Vec3(rng.uniform(-8, 8), rng.uniform(-8, 8), rng.uniform(-8, 8));
    w.addBody(d);
  }
  // Two of them head for each other so contacts take part.
  w.setVelocity(0, Vec3(0.5f, 0, 0), w.angularVelocity(0));
  w.setVelocity(1, Vec3(-0.5f, 0, 0), w.angularVelocity(1));
  const float e0 = w.kineticEnergy();
  float emax = e0;
  for (int i = 0; i < 600; ++i) {
    w.step(kDt);
    emax = std::max(emax, w.kineticEnergy());
  }
  EXPECT_LE(emax, e0 * 1.0001f) << "e0 " << e0;
}

// Free asymmetric bodies tumbling (no contacts): energy is kept, neither gained nor bled.
TEST(Dynamics, TumblingBodiesKeepTheirEnergy) {
  World w;
  const int plank = w.addShape(ConvexShape::box(Vec3(0.05f, 0.02f, 0.01f)));
  scenes::Rng rng(8);
  for (int i = 0; i < 4; ++i) {
    BodyDef d = boxBody(plank, Vec3(0.3f * static_cast<float>(i), 0.0f, 0.0f));
    d.angularVelocity = Vec3(rng.uniform(-8, 8), rng.uniform(-8, 8), rng.uniform(-8, 8));
    w.addBody(d);
  }
  const float e0 = w.kineticEnergy();
  float emax = e0, emin = e0;
  for (int i = 0; i < 600; ++i) {
    w.step(kDt);
    emax = std::max(emax, w.kineticEnergy());
    emin = std::min(emin, w.kineticEnergy());
  }
  EXPECT_LE(emax, e0 * 1.0001f);
  EXPECT_GE(emin, e0 * 0.95f);
}

TEST(Dynamics, StaticBodiesNeverMove) {
  WorldSettings settings;
  settings.gravity = Vec3(0, -9.81f, 0);
  World w(settings);
  const int box = w.addShape(ConvexShape::box(Vec3(0.1f, 0.1f, 0.1f)));
  BodyDef d = boxBody(box, Vec3(1, 2, 3));
  d.type = BodyType::Static;
  d.linearVelocity = Vec3(1, 0, 0);
  const BodyId b = w.addBody(d);
  for (int i = 0; i < 10; ++i) w.step(kDt);
  EXPECT_EQ(w.pose(b).p, Vec3(1, 2, 3));
}

TEST(Dynamics, KinematicBodiesMoveWithTheirVelocityAndIgnoreGravity) {
  WorldSettings settings;
  settings.gravity = Vec3(0, -9.81f, 0);
  World w(settings);
  const int box = w.addShape(ConvexShape::box(Vec3(0.1f, 0.1f, 0.1f)));
  BodyDef d = boxBody(box, Vec3::Zero());
  d.type = BodyType::Kinematic;
  d.linearVelocity = Vec3(0.6f, 0, 0);
  const BodyId b = w.addBody(d);
  for (int i = 0; i < 60; ++i) w.step(kDt);
  EXPECT_LT((w.pose(b).p - Vec3(0.6f, 0, 0)).norm(), 1e-5f);
}

TEST(Dynamics, DampingFromRetentionScalesVelocityPerStep) {
  World w;
  const int box = w.addShape(ConvexShape::box(Vec3(0.1f, 0.1f, 0.1f)));
  BodyDef d = boxBody(box, Vec3::Zero());
  d.linearVelocity = Vec3(1, 0, 0);
  d.linearDamping = dampingFromRetention(0.8f, kDt);
  const BodyId b = w.addBody(d);
  w.step(kDt);
  EXPECT_NEAR(w.linearVelocity(b).x(), 0.8f, 1e-5f);
}

TEST(JointAngles, ComposeDecomposeRoundTrip) {
  for (const Vec3& a : {Vec3(0.3f, 0.1f, -0.2f), Vec3(-1.2f, 0.4f, 0.5f), Vec3(1.5f, -0.3f, 0.0f),
                        Vec3::Zero().eval()}) {
    const Vec3 back = decomposeJointRotation(composeJointRotation(a));
    EXPECT_LT((back - a).norm(), 1e-5f) << a.transpose() << " -> " << back.transpose();
  }
  // Pure rotations about the joint axes give pure angles.
  EXPECT_NEAR(decomposeJointRotation(Quat(Eigen::AngleAxisf(0.7f, Vec3::UnitZ()))).x(), 0.7f,
              1e-6f);
  EXPECT_NEAR(decomposeJointRotation(Quat(Eigen::AngleAxisf(0.3f, Vec3::UnitY()))).y(), 0.3f,
              1e-6f);
  EXPECT_NEAR(decomposeJointRotation(Quat(Eigen::AngleAxisf(0.2f, Vec3::UnitX()))).z(), 0.2f,
              1e-6f);
}

}  // namespace
}  // namespace dynahand::physics
