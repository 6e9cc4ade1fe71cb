// Constraint rows: limits, drives, cones, the tracker's surface / line-of-sight / boundary rows.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "dynahand/physics_world.h"
#include "physics/physics_scenes.h"

namespace dynahand::physics {
namespace {

constexpr float kDt = 1.0f / 60.0f;
constexpr float kDeg = 0.017453293f;

struct Hinge {
  World world;
  BodyId parent, child;
  JointId joint;
};

// A static parent and a finger-bone child joined at the child's base; joint X along the bone.
Hinge makeJointScene(const Vec3& lower, const Vec3& upper) {
  WorldSettings settings;
  Hinge h{World(settings), 0, 0, 0};
  const int bone = h.world.addShape(scenes::bonePrism(0.04f, 0.009f, 0.008f));
  BodyDef p;
  p.shape = bone;
  p.type = BodyType::Static;
  p.pose.p = Vec3(-0.04f, 0, 0);
  h.parent = h.world.addBody(p);
  BodyDef c;
  c.shape = bone;
  c.angularDamping = 2.0f;
  h.child = h.world.addBody(c);
  JointDef j;
  j.parent = h.parent;
  j.child = h.child;
  j.anchorParent = Vec3(0.04f, 0, 0);
  j.limitsEnabled = true;
  j.lower = lower;
  j.upper = upper;
  h.joint = h.world.addJoint(j);
  return h;
}

// Drive angles past their limits with a strong motor (5 N m on a 1 kg bone). While the drive
// keeps pushing (after the first second) every limit holds within 0.5 deg; arriving at the
// limit overshoots by at most 3 deg (linearised angles over one step).
TEST(JointLimits, HoldWithinHalfDegreeWhileDrivePushesPast) {
  const Vec3 lower(-0.3f, -0.2f, -0.1f), upper(1.2f, 0.25f, 0.15f);
  const std::vector<Vec3> targets = {
      Vec3(2.0f, 0, 0),    Vec3(-1.0f, 0, 0),   Vec3(0, 0.6f, 0),
      Vec3(0, -0.6f, 0),   Vec3(0, 0, 0.5f),    Vec3(0, 0, -0.5f),
      Vec3(1.6f, 0.5f, 0), Vec3(1.6f, 0, 0.4f), Vec3(-1.0f, -0.5f, 0)};
  for (const Vec3& target : targets) {
    Hinge h = makeJointScene(lower, upper);
    h.world.setJointDrive(h.joint, composeJointRotation(target), 5.0f, 0.1f);
    float transient = 0.0f, held = 0.0f;
    for (int i = 0; i < 180; ++i) {
      h.world.step(kDt);
      const Vec3 a = h.world.jointAngles(h.joint);
      for (int k = 0; k < 3; ++k) {
        const float violation = std::max(lower[k] - a[k], a[k] - upper[k]);
        transient = std::max(transient, violation);
        if (i >= 60) held = std::max(held, violation);
      }
    }
    EXPECT_LT(held, 0.5f * kDeg) << "target " << target.transpose();
    EXPECT_LT(transient, 3.0f * kDeg) << "target " << target.transpose();
    // A single-axis drive did push the joint to the limit it aims past.
    const Vec3 a = h.world.jointAngles(h.joint);
    const bool singleAxis = (target.array() != 0.0f).count() == 1;
    for (int k = 0; k < 3 && singleAxis; ++k) {
      if (target[k] > upper[k]) {
        EXPECT_GT(a[k], upper[k] - 1.0f * kDeg) << k;
      }
      if (target[k] < lower[k]) {
        EXPECT_LT(a[k], lower[k] + 1.0f * kDeg) << k;
      }
    }
    EXPECT_LT(h.world.jointSeparation(h.joint), 1e-4f);
  }
}

TEST(JointDrive, ReachesTargetInsideLimits) {
  Hinge h = makeJointScene(Vec3(-1, -1, -1), Vec3(1, 1, 1));
  const Vec3 target(0.5f, -0.2f, 0.1f);
  h.world.setJointDrive(h.joint, composeJointRotation(target), 2.0f, 0.05f);
  for (int i = 0; i < 120; ++i) h.world.step(kDt);
  EXPECT_LT((h.world.jointAngles(h.joint) - target).norm(), 1.0f * kDeg);
}

TEST(JointDrive, TorqueLimitBoundsTheMotion) {
  // A tiny torque cannot turn the bone far in a short time: |angle| <= 1/2 (tau/I) t^2.
  Hinge h = makeJointScene(Vec3(-2, -1, -1), Vec3(2, 1, 1));
  h.world.setDamping(h.child, 0.0f, 0.0f);
  const float torque = 1e-4f;
  h.world.setJointDrive(h.joint, composeJointRotation(Vec3(1.5f, 0, 0)), torque);
  const int steps = 10;
  for (int i = 0; i < steps; ++i) h.world.step(kDt);
  // Moment of inertia about the joint (at the bone's end) along the flexion axis.
  const ConvexShape& s = h.world.bodyShape(h.child);
  const Vec3 c = s.centroid();
  const float inertia = s.inertiaAboutCentroid(1.0f)(2, 2) + c.x() * c.x() + c.y() * c.y();
  const float t = steps * kDt;
  const float bound = 0.5f * torque / inertia * t * t;
  EXPECT_LT(h.world.jointAngles(h.joint).x(), bound * 1.2f);
  EXPECT_GT(h.world.jointAngles(h.joint).x(), 0.3f * bound);
}

// A spring drive (setJointDriveSpring) holding a bone out sideways under gravity settles
// where the spring balances the load: stiffness x angle = m g d cos(angle), d the centre of
// mass's distance from the joint, whatever the bone's inertia. The velocity servo (no
// spring) holds the same bone within a degree of its target.
TEST(JointDrive, SpringSettlesWhereItBalancesTheLoad) {
  for (const float stiffness : {1.0f, 4.0f}) {
    Hinge h = makeJointScene(Vec3(-1, -1, -1), Vec3(1, 1, 1));
    h.world.settings().gravity = Vec3(0, -9.81f, 0);
    h.world.setJointDrive(h.joint, Quat::Identity(), 10.0f, 0.05f);
    h.world.setJointDriveSpring(h.joint, stiffness, 1.0f);
    for (int i = 0; i < 240; ++i) h.world.step(kDt);
    const float d = h.world.bodyShape(h.child).centroid().x();  // the joint is at x = 0
    const float load = h.world.mass(h.child) * 9.81f * d;
    float angle = load / stiffness;  // small-angle start, then the fixed point with cos
    for (int k = 0; k < 20; ++k) angle = load * std::cos(angle) / stiffness;
    const float measured = h.world.jointAngles(h.joint).norm();
    EXPECT_NEAR(measured, angle, 0.03f * angle) << "stiffness " << stiffness;
  }
  Hinge servo = makeJointScene(Vec3(-1, -1, -1), Vec3(1, 1, 1));
  servo.world.settings().gravity = Vec3(0, -9.81f, 0);
  servo.world.setJointDrive(servo.joint, Quat::Identity(), 10.0f, 0.05f);
  for (int i = 0; i < 240; ++i) servo.world.step(kDt);
  EXPECT_LT(servo.world.jointAngles(servo.joint).norm(), 1.0f * kDeg);
}

TEST(AngularCone, KeepsAxesWithinTenDegrees) {
  Hinge h = makeJointScene(Vec3(-2, -1, -1), Vec3(2, 1, 1));
  const float maxAngle = 10.0f * kDeg;
  h.world.addAngularCone(h.parent, Vec3::UnitX(), h.child, Vec3::UnitX(), maxAngle);
  h.world.setJointDrive(h.joint, composeJointRotation(Vec3(0.8f, 0.3f, 0)), 5.0f, 0.1f);
  float worst = 0.0f;
  for (int i = 0; i < 120; ++i) {
    h.world.step(kDt);
    const Vec3 u = h.world.pose(h.parent).rotate(Vec3::UnitX());
    const Vec3 v = h.world.pose(h.child).rotate(Vec3::UnitX());
    worst = std::max(worst, std::acos(std::clamp(u.dot(v), -1.0f, 1.0f)));
  }
  EXPECT_LT(worst, maxAngle + 0.5f * kDeg);
  EXPECT_GT(worst, maxAngle - 1.0f * kDeg);  // the drive pushed it to the cone
}

TEST(AngularCone, DisabledConeDoesNotAct) {
  Hinge h = makeJointScene(Vec3(-2, -1, -1), Vec3(2, 1, 1));
  const ConeId cone = h.world.addAngularCone(h.parent, Vec3::UnitX(), h.child, Vec3::UnitX(), 0.1f);
  h.world.setConeEnabled(cone, false);
  h.world.setJointDrive(h.joint, composeJointRotation(Vec3(0.8f, 0, 0)), 5.0f, 0.05f);
  for (int i = 0; i < 120; ++i) h.world.step(kDt);
  EXPECT_NEAR(h.world.jointAngles(h.joint).x(), 0.8f, 1.0f * kDeg);
}

World freeBoxWorld(BodyId* body) {
  World w;
  const int box = w.addShape(ConvexShape::box(Vec3(0.02f, 0.02f, 0.02f)));
  BodyDef d;
  d.shape = box;
  *body = w.addBody(d);
  return w;
}

TEST(SurfaceRows, AccumulatedImpulseNeverExceedsCap) {
  BodyId b = 0;
  World w = freeBoxWorld(&b);
  w.reserveRows(64);
  const float cap = 0.002f;  // N s
  const int steps = 30, rowCount = 40;
  for (int step = 0; step < steps; ++step) {
    w.rows().clear();
    for (int i = 0; i < rowCount; ++i) {
      const Vec3 anchor(0.02f, 0.01f * static_cast<float>(i % 3) - 0.01f, 0.0f);
      // Targets far away: every row wants more than its cap.
      w.rows().addSurface(b, anchor, Vec3::UnitX(), Vec3(1.0f, 0, 0), cap);
    }
    w.step(kDt);
    for (float imp : w.rows().impulse) {
      EXPECT_LE(std::abs(imp), cap * (1.0f + 1e-6f));
    }
  }
  // Per step the capped rows can give the 1 kg box at most rowCount x cap of momentum, and the
  // far target keeps them saturated during the biased sweeps: x ~ steps x dt x rowCount x cap.
  const float reach = steps * kDt * rowCount * cap;
  EXPECT_LE(w.pose(b).p.x(), reach * 1.001f);
  EXPECT_GT(w.pose(b).p.x(), 0.9f * reach);
}

TEST(SurfaceRows, MajorityOverpowersOutliers) {
  BodyId b = 0;
  World w = freeBoxWorld(&b);
  w.setDamping(b, dampingFromRetention(0.8f, kDt), dampingFromRetention(0.8f, kDt));
  const Vec3 shift(0.01f, -0.005f, 0.003f);  // where the data says the box is
  const float cap = 0.01f;
  const ConvexShape& s = w.bodyShape(b);
  scenes::Rng rng(5);
  std::vector<Vec3> anchors;
  std::vector<int> faces;
  for (int i = 0; i < 120; ++i) {
    Vec3 p;
    int f = 0;
    s.query(Vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)) * 0.05f, &p, &f);
    anchors.push_back(p);
    faces.push_back(f);
  }
  for (int step = 0; step < 120; ++step) {
    w.rows().clear();
    for (std::size_t i = 0; i < anchors.size(); ++i) {
      const Vec3 n = w.pose(b).rotate(s.faces()[static_cast<std::size_t>(faces[i])].normal);
      const bool outlier = i % 10 == 0;  // 10% pull 5 cm the other way
      const Vec3 target = anchors[i] + (outlier ? Vec3(-0.05f, 0.04f, 0.0f) : shift);
      w.rows().addSurface(b, anchors[i], n, target, cap);
    }
    w.step(kDt);
  }
  EXPECT_LT((w.pose(b).p - shift).norm(), 1e-3f) << w.pose(b).p.transpose();
  EXPECT_LT(Eigen::AngleAxisf(w.pose(b).q).angle(), 2.0f * kDeg);
}

// A body holding every surface row is solved over four copies of itself (mass splitting);
// the same rows with three more bodies holding as many rows each are solved on the body
// itself. Both fits agree: splitting changes how a sweep converges, not the answer. (That
// each copy carries its share of the mass shows in AccumulatedImpulseNeverExceedsCap: its 40
// saturated rows on one box are split, and the box must travel the full capped momentum.)
TEST(SurfaceRows, BodyHoldingEveryRowFitsAsWhenItHoldsAQuarter) {
  const Vec3 shift(0.008f, -0.004f, 0.005f);
  const Quat turn(Eigen::AngleAxisf(0.1f, Vec3(0.3f, 1.0f, 0.2f).normalized()));
  Pose fitted[2];
  for (int others = 0; others < 2; ++others) {
    World w;
    const int box = w.addShape(ConvexShape::box(Vec3(0.02f, 0.015f, 0.01f)));
    std::vector<BodyId> bodies;
    for (int k = 0; k < (others == 1 ? 4 : 1); ++k) {
      BodyDef d;
      d.shape = box;
      d.pose.p = Vec3(0.2f * static_cast<float>(k), 0, 0);  // far apart: no contacts
      bodies.push_back(w.addBody(d));
    }
    for (const BodyId b : bodies)
      w.setDamping(b, dampingFromRetention(0.8f, kDt), dampingFromRetention(0.8f, kDt));
    const ConvexShape& s = w.bodyShape(bodies[0]);
    for (int step = 0; step < 40; ++step) {
      w.rows().clear();
      for (const BodyId b : bodies) {
        const Pose target{Vec3(0.2f * static_cast<float>(b), 0, 0) + shift, turn};
        for (std::size_t f = 0; f < s.faces().size(); ++f) {
          for (const int v : s.faces()[f].vertices) {
            for (const float inward : {0.8f, 0.5f}) {  // 48 rows per box: a lone box is split
              const Vec3 anchor = inward * s.vertices()[static_cast<std::size_t>(v)];
              const Vec3 local = anchor + 0.01f * s.faces()[f].normal;
              w.rows().addSurface(b, local, w.pose(b).rotate(s.faces()[f].normal),
                                  target.transform(local), 0.05f);
            }
          }
        }
      }
      w.step(kDt);
    }
    fitted[others] = w.pose(bodies[0]);
  }
  EXPECT_LT((fitted[0].p - shift).norm(), 2e-4f);
  EXPECT_LT((fitted[0].p - fitted[1].p).norm(), 2e-4f);
  EXPECT_LT(fitted[0].q.angularDistance(fitted[1].q), 0.5f * kDeg);
  EXPECT_LT(fitted[0].q.angularDistance(turn), 0.5f * kDeg);
}

TEST(SurfaceRows, PullsBodyPointOntoTarget) {
  BodyId b = 0;
  World w = freeBoxWorld(&b);
  for (int step = 0; step < 60; ++step) {
    w.rows().clear();
    w.rows().addSurface(b, Vec3(0.02f, 0, 0), Vec3::UnitX(), Vec3(0.05f, 0, 0), 1.0f);
    w.step(kDt);
  }
  EXPECT_NEAR(w.pose(b).transform(Vec3(0.02f, 0, 0)).x(), 0.05f, 1e-4f);
}

TEST(LineOfSight, PushesOnlyWhenInFrontOfTheObservedPoint) {
  BodyId b = 0;
  World w = freeBoxWorld(&b);
  const Vec3 ray = Vec3::UnitZ();  // camera looks along +z
  // The body's front point is at z = -0.02; the observed surface is at z = 0.01: the body is
  // in front of data, i.e. in free space, and must be pushed back behind it.
  for (int step = 0; step < 60; ++step) {
    w.rows().clear();
    w.rows().addLineOfSight(b, Vec3(0, 0, -0.02f), ray, Vec3(0, 0, 0.01f), 1.0f);
    w.step(kDt);
    EXPECT_GE(w.rows().impulse[0], 0.0f);
  }
  EXPECT_GE(w.pose(b).transform(Vec3(0, 0, -0.02f)).z(), 0.01f - 1e-4f);
  // Behind the target already: the row does nothing.
  World w2 = freeBoxWorld(&b);
  w2.rows().addLineOfSight(b, Vec3(0, 0, -0.02f), ray, Vec3(0, 0, -0.05f), 1.0f);
  w2.step(kDt);
  EXPECT_EQ(w2.rows().impulse[0], 0.0f);
  EXPECT_EQ(w2.pose(b).p, Vec3::Zero());
}

// Every vertex within the margin gets a row, or (band 5 mm) those near the deepest only.
TEST(BoundaryPlane, KeepsExtremePointOnAllowedSide) {
  for (const float band : {std::numeric_limits<float>::infinity(), 0.005f}) {
    BodyId b = 0;
    World w = freeBoxWorld(&b);
    w.setVelocity(b, Vec3(0, 0.5f, 0), Vec3(0, 0, 3.0f));  // heading into the plane, spinning
    const Vec3 n(0, -1, 0);                                // allowed side: y <= 0.05
    const float offset = -0.05f;
    float worst = 0.0f;
    for (int step = 0; step < 120; ++step) {
      w.rows().clear();
      w.addBoundary(b, n, offset, 1.0f, 0.01f, band);
      w.step(kDt);
      for (const Vec3& v : w.bodyShape(b).vertices()) {
        worst = std::max(worst, w.pose(b).transform(v).y() - 0.05f);
      }
    }
    EXPECT_LT(worst, 1e-3f) << "band " << band;
  }
}

// A 4 cm box tilted towards a plane: the margin takes in vertices up to 2 cm from it, the
// band only those within 5 mm of the deepest (KeepsExtremePointOnAllowedSide spins it).
TEST(BoundaryPlane, BandKeepsOnlyTheVerticesNearTheDeepest) {
  BodyId b = 0;
  World w = freeBoxWorld(&b);
  // Turned 0.35 rad about z: vertex edges 4 mm and 18 mm from the plane.
  w.setPose(b, Pose{Vec3(0, 0.02f, 0), Quat(Eigen::AngleAxisf(0.35f, Vec3::UnitZ()))});
  const Vec3 n(0, -1, 0);  // allowed side: y <= 0.05
  const float offset = -0.05f, margin = 0.02f, band = 0.005f;
  auto gap = [&](const Vec3& anchor) { return n.dot(w.pose(b).transform(anchor)) - offset; };
  float deepest = std::numeric_limits<float>::infinity();
  int withinMargin = 0, withinBand = 0;
  for (const Vec3& v : w.bodyShape(b).vertices()) {
    deepest = std::min(deepest, gap(v));
  }
  for (const Vec3& v : w.bodyShape(b).vertices()) {
    withinMargin += gap(v) <= margin ? 1 : 0;
    withinBand += gap(v) <= std::min(margin, deepest + band) ? 1 : 0;
  }
  ASSERT_GT(withinMargin, withinBand) << "the pose must put some vertices outside the band";
  ASSERT_GE(withinBand, 1);
  w.addBoundary(b, n, offset, 1.0f, margin);
  EXPECT_EQ(static_cast<int>(w.rows().body.size()), withinMargin);
  w.rows().clear();
  w.addBoundary(b, n, offset, 1.0f, margin, band);
  ASSERT_EQ(static_cast<int>(w.rows().body.size()), withinBand);
  for (const Vec3& anchor : w.rows().anchor) EXPECT_LE(gap(anchor), deepest + band + 1e-6f);
}

TEST(BodyDrive, ReachesTargetPoseWithinLimits) {
  BodyId b = 0;
  World w = freeBoxWorld(&b);
  const Pose target{Vec3(0.05f, -0.02f, 0.01f),
                    Quat(Eigen::AngleAxisf(0.5f, Vec3(0, 1, 1).normalized()))};
  w.setBodyDrive(b, target, 10.0f, 0.1f, 0.05f);
  for (int i = 0; i < 120; ++i) w.step(kDt);
  EXPECT_LT((w.pose(b).p - target.p).norm(), 1e-4f);
  EXPECT_LT(target.q.angularDistance(w.pose(b).q), 0.5f * kDeg);
}

TEST(BodyDrive, ForceLimitBoundsAcceleration) {
  BodyId b = 0;
  World w = freeBoxWorld(&b);
  const float maxForce = 0.5f;  // N on 1 kg: at most 0.5 m/s^2
  w.setBodyDrive(b, Pose{Vec3(1, 0, 0), Quat::Identity()}, maxForce, 1.0f);
  for (int i = 0; i < 30; ++i) w.step(kDt);
  const float t = 30 * kDt;
  EXPECT_LE(w.linearVelocity(b).x(), maxForce * t * 1.0001f);
  EXPECT_GT(w.linearVelocity(b).x(), 0.9f * maxForce * t);
}

TEST(BodyDrive, ClearedDriveStopsPulling) {
  BodyId b = 0;
  World w = freeBoxWorld(&b);
  w.setBodyDrive(b, Pose{Vec3(1, 0, 0), Quat::Identity()}, 0.5f, 1.0f);
  for (int i = 0; i < 30; ++i) w.step(kDt);
  const float vx = w.linearVelocity(b).x();
  ASSERT_GT(vx, 0.0f);
  w.clearBodyDrive(b);
  for (int i = 0; i < 30; ++i) w.step(kDt);
  // No force any more: the box coasts at the velocity the drive had given it.
  EXPECT_NEAR(w.linearVelocity(b).x(), vx, 1e-3f * vx);
}

}  // namespace
}  // namespace dynahand::physics
