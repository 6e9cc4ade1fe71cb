// Scenes shared by the physics tests and bench/physics: a 17-body hand-like articulated model
// built directly from physics primitives (no dependency on the model module) and random
// surface rows like the tracker's.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "dynahand/physics_world.h"

namespace dynahand::physics::scenes {

// Small deterministic generator (the same sequence on every platform, unlike <random>'s
// distributions): xorshift64*.
class Rng {
 public:
  explicit Rng(std::uint64_t seed) : s_(seed * 2654435761u + 1u) {}
  std::uint64_t next() {
    s_ ^= s_ >> 12;
    s_ ^= s_ << 25;
    s_ ^= s_ >> 27;
    return s_ * 2685821657736338717ull;
  }
  float uniform(float lo, float hi) {  // [lo, hi)
    const float u = static_cast<float>(next() >> 40) / static_cast<float>(1ull << 24);
    return lo + (hi - lo) * u;
  }
  int index(int count) { return static_cast<int>(next() % static_cast<std::uint64_t>(count)); }

 private:
  std::uint64_t s_;
};

// An octagonal prism along x from 0 to length (body frame), half widths hy, hz, with the
// corners bevelled: a finger-bone-like convex shape (16 vertices).
inline ConvexShape bonePrism(float length, float hy, float hz) {
  std::vector<Vec3> pts;
  for (float x : {0.0f, length}) {
    for (int k = 0; k < 8; ++k) {
      const float a = (static_cast<float>(k) + 0.5f) * 0.78539816f;
      pts.emplace_back(x, hy * std::cos(a) / 0.92387953f, hz * std::sin(a) / 0.92387953f);
    }
  }
  return ConvexShape::fromPoints(pts).value();
}

struct HandLike {
  World world;
  std::vector<BodyId> bodies;   // 0 wrist (forearm end), 1 palm, then 5 digits x 3 bones
  std::vector<JointId> joints;  // 16
};

// 17 bodies, 16 ball joints with flexion/abduction/twist limits, contacts between every pair
// that is not joined (so neighbouring fingers collide). Fingers point along +x of the hand
// frame, the palm normal is +z; the hand frame is placed 0.4 m in front of the camera.
inline HandLike makeHandLike(const WorldSettings& settings = {}) {
  HandLike h{World(settings), {}, {}};
  World& w = h.world;
  const Pose handPose{Vec3(0.0f, 0.0f, 0.4f), Quat(Eigen::AngleAxisf(0.3f, Vec3::UnitZ()))};
  // Joint frame: joint X along the bone (body x), joint Z (flexion axis) along body -y.
  const Quat frame(Eigen::AngleAxisf(1.5707963f, Vec3::UnitX()));
  auto addBone = [&](float length, float hy, float hz, const Pose& local, float mass) {
    const int shape = w.addShape(bonePrism(length, hy, hz));
    BodyDef def;
    def.shape = shape;
    def.pose = handPose * local;
    def.mass = mass;
    def.linearDamping = 1.0f;
    def.angularDamping = 1.0f;
    h.bodies.push_back(w.addBody(def));
    return h.bodies.back();
  };
  auto addJoint = [&](BodyId parent, const Vec3& anchorParent, BodyId child, const Vec3& lower,
                      const Vec3& upper) {
    JointDef j;
    j.parent = parent;
    j.child = child;
    j.anchorParent = anchorParent;
    j.anchorChild = Vec3::Zero();
    const Quat childInParent = w.pose(parent).q.conjugate() * w.pose(child).q;
    j.frameParent = childInParent * frame;
    j.frameChild = frame;
    j.limitsEnabled = true;
    j.lower = lower;
    j.upper = upper;
    h.joints.push_back(w.addJoint(j));
  };
  const BodyId wrist = addBone(0.05f, 0.03f, 0.015f, {Vec3(-0.05f, 0, 0), Quat::Identity()}, 2.0f);
  const BodyId palm = addBone(0.09f, 0.042f, 0.013f, {Vec3(0, 0, 0), Quat::Identity()}, 2.0f);
  addJoint(wrist, Vec3(0.05f, 0, 0), palm, Vec3(-1.0f, -0.4f, -0.3f), Vec3(1.0f, 0.4f, 0.3f));
  const std::array<float, 4> fingerY = {-0.03f, -0.01f, 0.01f, 0.03f};
  const std::array<float, 4> fingerScale = {0.95f, 1.0f, 0.95f, 0.8f};
  const std::array<float, 3> bone = {0.045f, 0.028f, 0.022f};
  for (int f = 0; f < 5; ++f) {
    const bool thumb = f == 4;
    Pose base =
        thumb ? Pose{Vec3(0.015f, -0.042f, 0.0f), Quat(Eigen::AngleAxisf(-0.9f, Vec3::UnitZ()))}
              : Pose{Vec3(0.09f, fingerY[static_cast<std::size_t>(f)], 0.0f), Quat::Identity()};
    const float scale = thumb ? 1.0f : fingerScale[static_cast<std::size_t>(f)];
    BodyId parent = palm;
    Vec3 anchor = w.pose(palm).inverseTransform(handPose.transform(base.p));
    for (int b = 0; b < 3; ++b) {
      const float len = bone[static_cast<std::size_t>(b)] * scale;
      const BodyId child = addBone(len, 0.0085f, 0.008f, base, 1.0f);
      const Vec3 lower = b == 0 ? Vec3(-0.3f, -0.35f, -0.1f) : Vec3(-0.1f, -0.05f, -0.05f);
      const Vec3 upper = b == 0 ? Vec3(1.6f, 0.35f, 0.1f) : Vec3(1.7f, 0.05f, 0.05f);
      addJoint(parent, anchor, child, lower, upper);
      parent = child;
      anchor = Vec3(len, 0, 0);
      base = base * Pose{Vec3(len, 0, 0), Quat::Identity()};
    }
  }
  return h;
}

// Adds `count` random surface rows: a random body, a random point on its surface, pulled
// along the face normal towards a target up to 5 mm off, with the given cap (N s).
inline void addRandomSurfaceRows(World& w, int count, std::uint64_t seed, float cap) {
  Rng rng(seed);
  SurfaceRows& rows = w.rows();
  for (int i = 0; i < count; ++i) {
    const BodyId b = rng.index(w.bodyCount());
    const ConvexShape& s = w.bodyShape(b);
    const Vec3 probe =
        s.centroid() +
        Vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)) * s.boundingRadius();
    Vec3 anchor;
    int face = 0;
    s.query(probe, &anchor, &face);
    const Pose p = w.pose(b);
    const Vec3 normal = p.rotate(s.faces()[static_cast<std::size_t>(face)].normal);
    const Vec3 target = p.transform(anchor) + normal * rng.uniform(-0.005f, 0.005f) +
                        Vec3(rng.uniform(-0.002f, 0.002f), rng.uniform(-0.002f, 0.002f), 0.0f);
    rows.addSurface(b, anchor, normal, target, cap);
  }
}

}  // namespace dynahand::physics::scenes
