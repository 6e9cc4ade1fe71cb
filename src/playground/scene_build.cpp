// Scene objects into a physics::World: simple convex bodies, and the compound objects built
// from them (barbell = bar + two caps welded; lever and dial = hinge joints with limits on a
// static mount; swing = a chain of ball joints under a static anchor).
#include "scene_build.h"

#include <cmath>
#include <numbers>

namespace dynahand::playground::detail {
namespace {

using physics::BodyDef;
using physics::BodyType;
using physics::ConvexShape;
using physics::JointDef;

constexpr float kPi = std::numbers::pi_v<float>;
constexpr int kRoundSegments = 16;  // facets around cylinders and spheres

ConvexShape hull(const std::vector<Vec3>& points) {
  auto shape = ConvexShape::fromPoints(points);
  assert(shape.ok() && "generated hulls are valid");
  return std::move(*shape);
}

}  // namespace

ConvexShape cylinderShape(float radius, float length, int sides) {
  std::vector<Vec3> points;
  for (int i = 0; i < sides; ++i) {
    const float a = 2.0f * kPi * static_cast<float>(i) / static_cast<float>(sides);
    for (float x : {-0.5f * length, 0.5f * length})
      points.emplace_back(x, radius * std::cos(a), radius * std::sin(a));
  }
  return hull(points);
}

ConvexShape ellipsoidShape(const Vec3& semiAxes) {
  std::vector<Vec3> points;
  constexpr int kRings = 7;
  for (int r = 0; r <= kRings; ++r) {
    const float polar = kPi * static_cast<float>(r) / kRings;
    const int count = (r == 0 || r == kRings) ? 1 : kRoundSegments;
    for (int i = 0; i < count; ++i) {
      const float a = 2.0f * kPi * static_cast<float>(i) / static_cast<float>(count);
      points.emplace_back(semiAxes.x() * std::sin(polar) * std::cos(a),
                          semiAxes.y() * std::cos(polar),
                          semiAxes.z() * std::sin(polar) * std::sin(a));
    }
  }
  return hull(points);
}

Result<ConvexShape> objectShape(const ObjectSpec& o) {
  switch (o.kind) {
    case ObjectKind::Box:
      return ConvexShape::box(0.5f * o.size);
    case ObjectKind::Sphere:
      return ellipsoidShape(Vec3::Constant(o.radius));
    case ObjectKind::Cylinder:
      return cylinderShape(o.radius, o.length, kRoundSegments);
    case ObjectKind::Convex:
      return ConvexShape::fromPoints(o.points);
    default:
      return Error{"not a simple object"};
  }
}

SceneBuilder::SceneBuilder(physics::World& world, std::vector<SceneBody>& bodies)
    : world_(world), bodies_(bodies) {}

physics::BodyId SceneBuilder::add(const std::string& name, const ConvexShape& shape,
                                  const Pose& pose, float mass, bool isStatic, float damping) {
  BodyDef def;
  def.shape = world_.addShape(shape);
  def.type = isStatic ? BodyType::Static : BodyType::Dynamic;
  def.pose = pose;
  def.mass = mass;
  def.angularDamping = damping;
  const physics::BodyId id = world_.addBody(def);
  bodies_.push_back({name, id, false, isStatic});
  return id;
}

// A hinge on a static parent with identity orientation: physics flexion (about the joint
// frame's Z) is the angle about `axis`; abduction and twist are locked at 0 by the limits.
void SceneBuilder::hinge(physics::BodyId mount, physics::BodyId child, const Vec3& hingePoint,
                         const Vec3& anchorChild, const Quat& childRest, const ObjectSpec& o) {
  JointDef def;
  def.parent = mount;
  def.child = child;
  def.anchorParent = world_.pose(mount).inverseTransform(hingePoint);
  def.anchorChild = anchorChild;
  const Quat h = shortestRotation(Vec3::UnitZ(), o.axis);
  def.frameParent = h;
  def.frameChild = (childRest.conjugate() * h).normalized();
  def.limitsEnabled = true;
  def.lower = Vec3(o.lowerLimit, 0.0f, 0.0f);
  def.upper = Vec3(o.upperLimit, 0.0f, 0.0f);
  hinges_.push_back({o.name, world_.addJoint(def)});
}

Status SceneBuilder::addObject(const ObjectSpec& o) {
  const Quat start(Eigen::AngleAxisf(o.startAngle, o.axis));
  switch (o.kind) {
    case ObjectKind::Box:
    case ObjectKind::Sphere:
    case ObjectKind::Cylinder:
    case ObjectKind::Convex: {
      auto shape = objectShape(o);
      if (!shape) return Error{"object '" + o.name + "': " + shape.message()};
      add(o.name, *shape, {o.position, o.orientation}, o.mass, o.isStatic);
      return Ok{};
    }
    case ObjectKind::Barbell: {
      // The caps overlap the bar's ends so the bar passes through them.
      const physics::BodyId bar =
          add(o.name + "/bar", cylinderShape(o.radius, o.length, kRoundSegments),
              {o.position, o.orientation}, 0.5f * o.mass, false);
      // Hexagonal caps (a hex dumbbell): the barbell does not roll away from the fingers.
      const ConvexShape cap = cylinderShape(o.capRadius, o.capLength, 6);
      std::vector<physics::BodyId> group = {bar};
      for (int side = 0; side < 2; ++side) {
        const float x = (side == 0 ? -1.0f : 1.0f) * 0.5f * (o.length - o.capLength);
        group.push_back(add(o.name + "/cap" + std::to_string(side), cap,
                            {o.position + o.orientation * Vec3(x, 0, 0), o.orientation},
                            0.25f * o.mass, false));
      }
      world_.weld(group);
      return Ok{};
    }
    case ObjectKind::Lever: {
      // Static base under the hinge; the arm (size: x, y = length, z) stands on the hinge.
      constexpr float kBaseHalfHeight = 0.01f;
      const Vec3 baseHalf(0.5f * o.size.x() + 0.01f, kBaseHalfHeight, 0.5f * o.size.z() + 0.02f);
      const physics::BodyId base =
          add(o.name + "/base", ConvexShape::box(baseHalf),
              {o.position - Vec3(0, kBaseHalfHeight + 0.5f * o.size.z(), 0), Quat::Identity()},
              1.0f, true);
      const Quat rest = o.orientation;
      const Quat q = (start * rest).normalized();
      const Vec3 half = 0.5f * o.size;
      const physics::BodyId arm =
          add(o.name + "/arm", ConvexShape::box(half), {o.position + q * Vec3(0, half.y(), 0), q},
              o.mass, false, o.hingeDamping);
      hinge(base, arm, o.position, Vec3(0, -half.y(), 0), rest, o);
      return Ok{};
    }
    case ObjectKind::Dial: {
      // A knob (radius, thickness `length` along the axis) on a static mount, with a fin
      // (size: across, thickness, protrusion) on its front face to grip or push.
      const physics::BodyId mount =
          add(o.name + "/mount", ConvexShape::box(Vec3::Constant(0.01f)),
              {o.position - 0.01f * o.axis, Quat::Identity()}, 1.0f, true);
      const Quat rest = (shortestRotation(Vec3::UnitX(), o.axis) * o.orientation).normalized();
      const Quat q = (start * rest).normalized();
      const physics::BodyId knob =
          add(o.name + "/knob", cylinderShape(o.radius, o.length, kRoundSegments),
              {o.position + (0.5f * o.length) * o.axis, q}, 0.5f * o.mass, false, o.hingeDamping);
      const Vec3 finCentre(0.5f * o.length + 0.5f * o.size.z(), 0, 0);
      const physics::BodyId fin =
          add(o.name + "/fin",
              ConvexShape::box(Vec3(0.5f * o.size.z(), 0.5f * o.size.x(), 0.5f * o.size.y())),
              {world_.pose(knob).transform(finCentre), q}, 0.5f * o.mass, false, o.hingeDamping);
      const std::vector<physics::BodyId> group = {knob, fin};
      world_.weld(group);
      hinge(mount, knob, o.position, Vec3(-0.5f * o.length, 0, 0), rest, o);
      return Ok{};
    }
    case ObjectKind::Swing: {
      // Links (size each) hanging from a static anchor, the last one a flat seat.
      const physics::BodyId anchor =
          add(o.name + "/anchor", ConvexShape::box(Vec3::Constant(0.01f)),
              {o.position, Quat::Identity()}, 1.0f, true);
      physics::BodyId parent = anchor;
      Vec3 top = o.position - Vec3(0, 0.01f, 0);
      for (int i = 0; i < o.links; ++i) {
        const bool seat = i + 1 == o.links;
        const Vec3 half = seat ? Vec3(0.5f * o.size.y(), 0.5f * o.size.x(), 0.3f * o.size.y())
                               : Vec3(0.5f * o.size.x(), 0.5f * o.size.y(), 0.5f * o.size.z());
        const physics::BodyId link =
            add(o.name + (seat ? std::string("/seat") : "/link" + std::to_string(i)),
                ConvexShape::box(half), {top - Vec3(0, half.y(), 0), Quat::Identity()}, o.mass,
                false, o.hingeDamping);
        JointDef def;
        def.parent = parent;
        def.child = link;
        def.anchorParent = world_.pose(parent).inverseTransform(top);
        def.anchorChild = Vec3(0, half.y(), 0);
        world_.addJoint(def);
        parent = link;
        top -= Vec3(0, 2.0f * half.y(), 0);
      }
      return Ok{};
    }
  }
  return Error{"object '" + o.name + "': unknown kind"};
}

}  // namespace dynahand::playground::detail
