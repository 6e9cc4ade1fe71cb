// Forward kinematics and its inverse (angles from orientations), limits, interpolation.
// Joint angles follow the physics swing-twist convention (physics_angles.h) expressed in the
// model's joint axes (bone +z, flexion about +x, abduction toward +x); model angles
// (f, a, t) are physics angles (f, -a, t) in the joint frame rotated by (z, -y, x). Singular
// only at |abduction| = 90 degrees, which the limits exclude.
#include <algorithm>
#include <cassert>
#include <cmath>
#include <numbers>

#include "dynahand/model_pose.h"

namespace dynahand::model {

JointAngles zeroAngles(const ArticulatedModel& model) {
  JointAngles angles;
  angles.angles.assign(static_cast<size_t>(model.jointCount()), Vec3::Zero());
  return angles;
}

void clampToLimits(const ArticulatedModel& model, JointAngles& angles) {
  assert(angles.angles.size() == model.joints().size());
  for (size_t j = 0; j < angles.angles.size(); ++j) {
    const Joint& joint = model.joints()[j];
    angles.angles[j] = angles.angles[j].cwiseMax(joint.minAngle).cwiseMin(joint.maxAngle);
  }
}

bool withinLimits(const ArticulatedModel& model, const JointAngles& angles, float tolerance) {
  assert(angles.angles.size() == model.joints().size());
  for (size_t j = 0; j < angles.angles.size(); ++j) {
    const Joint& joint = model.joints()[j];
    for (int axis = 0; axis < 3; ++axis) {
      const float a = angles.angles[j][axis];
      if (!(a >= joint.minAngle[axis] - tolerance && a <= joint.maxAngle[axis] + tolerance))
        return false;
    }
  }
  return true;
}

Quat jointRotation(const Vec3& angles) {
  // physics::composeJointRotation(flexion, -abduction, twist) in the model's axes (physics
  // X, Y, Z = model z, -y, x): the bone direction d from flexion and abduction, the shortest
  // swing z -> d, then the twist about the bone.
  const float f = angles.x();
  const float a = angles.y();
  const Vec3 d(std::sin(a), -std::cos(a) * std::sin(f), std::cos(a) * std::cos(f));
  const Quat swing = shortestRotation(Vec3::UnitZ(), d);
  const Quat twist(std::cos(0.5f * angles.z()), 0.0f, 0.0f, std::sin(0.5f * angles.z()));
  return (swing * twist).normalized();
}

Vec3 jointRotationAngles(const Quat& rotation) {
  const Quat q = rotation.normalized();
  const Vec3 d = q * Vec3::UnitZ();
  const float flexion = std::atan2(-d.y(), d.z());
  const float abduction = std::asin(std::clamp(d.x(), -1.0f, 1.0f));
  const Quat twist = shortestRotation(Vec3::UnitZ(), d).conjugate() * q;
  float angle = 2.0f * std::atan2(twist.z(), twist.w());
  constexpr float kPi = std::numbers::pi_v<float>;
  if (angle > kPi) angle -= 2.0f * kPi;
  if (angle <= -kPi) angle += 2.0f * kPi;
  return {flexion, abduction, angle};
}

void forwardKinematicsInto(const ArticulatedModel& model, const JointAngles& angles,
                           ModelPose& out) {
  assert(angles.angles.size() == model.joints().size() && "one angle triple per joint");
  out.bodies.resize(model.bodies().size());
  const auto& bodies = model.bodies();
  const auto& joints = model.joints();
  for (const int b : model.kinematicOrder()) {
    const Body& body = bodies[static_cast<size_t>(b)];
    if (body.parent < 0) {
      out.bodies[static_cast<size_t>(b)] = angles.root;
      continue;
    }
    const Joint& joint = joints[static_cast<size_t>(body.joint)];
    const Pose& parent = out.bodies[static_cast<size_t>(body.parent)];
    Pose& child = out.bodies[static_cast<size_t>(b)];
    child.q =
        (parent.q * joint.frame * jointRotation(angles.angles[static_cast<size_t>(body.joint)]))
            .normalized();
    child.p = parent.p + parent.q * joint.anchorParent - child.q * joint.anchorChild;
  }
}

ModelPose forwardKinematics(const ArticulatedModel& model, const JointAngles& angles) {
  ModelPose pose;
  forwardKinematicsInto(model, angles, pose);
  return pose;
}

void jointAnglesInto(const ArticulatedModel& model, const ModelPose& pose, JointAngles& out) {
  assert(pose.bodies.size() == model.bodies().size() && "one pose per body");
  out.root = pose.bodies[static_cast<size_t>(model.root())];
  out.angles.resize(model.joints().size());
  for (size_t j = 0; j < model.joints().size(); ++j) {
    const Joint& joint = model.joints()[j];
    const Quat& parent = pose.bodies[static_cast<size_t>(joint.parent)].q;
    const Quat& child = pose.bodies[static_cast<size_t>(joint.child)].q;
    out.angles[j] = jointRotationAngles((parent * joint.frame).conjugate() * child);
  }
}

JointAngles jointAngles(const ArticulatedModel& model, const ModelPose& pose) {
  JointAngles angles;
  jointAnglesInto(model, pose, angles);
  return angles;
}

JointAngles interpolate(const JointAngles& a, const JointAngles& b, float t) {
  assert(a.angles.size() == b.angles.size());
  JointAngles out;
  out.root = dynahand::interpolate(a.root, b.root, t);
  out.angles.resize(a.angles.size());
  for (size_t j = 0; j < a.angles.size(); ++j)
    out.angles[j] = a.angles[j] + (b.angles[j] - a.angles[j]) * t;
  return out;
}

ModelPose interpolate(const ArticulatedModel& model, const ModelPose& a, const ModelPose& b,
                      float t) {
  return forwardKinematics(model, interpolate(jointAngles(model, a), jointAngles(model, b), t));
}

JointAngles mirrorAngles(const JointAngles& angles) {
  JointAngles out;
  const Pose& r = angles.root;
  out.root.p = Vec3(-r.p.x(), r.p.y(), r.p.z());
  out.root.q = Quat(r.q.w(), r.q.x(), -r.q.y(), -r.q.z());
  out.angles.resize(angles.angles.size());
  for (size_t j = 0; j < angles.angles.size(); ++j) {
    const Vec3& a = angles.angles[j];
    out.angles[j] = Vec3(a.x(), -a.y(), -a.z());
  }
  return out;
}

}  // namespace dynahand::model
