// The tracker's view of a hand model: a physics world built from the articulated
// model (bodies, ball joints with limits, collision filter), the grasp-bias cones
// (disabled until a strategy turns them on) and the hand's anatomy by body index.
//
// Joint angles: the model writes a child's orientation as parent * frame *
// Rx(flexion) Ry(abduction) Rz(twist) with the bone along the joint frame's z; the
// physics limits use a swing-twist split with the bone along x (physics_angles.h).
// The physics joint frame is therefore the model frame rotated by kModelToPhysics
// (physics x = model z, y = -model y, z = model x), which maps model angles
// (f, a, t) to physics angles (f, -a, ~t): flexion and abduction exactly, twist up to
// the difference between an Euler and a swing-twist split (small for hand joints).
#pragma once

#include <array>
#include <vector>

#include "dynahand/model.h"
#include "dynahand/model_pose.h"
#include "dynahand/physics_world.h"

namespace dynahand::track {

inline constexpr int kFingerCount = 5;  // thumb, index, middle, ring, pinky

struct HandAnatomy {
  int forearm = 0;
  int palm = 1;
  // Per finger (thumb..pinky) its three bodies, proximal to distal.
  std::array<std::array<int, 3>, kFingerCount> fingers{};
  // Bone axis of each body in its body frame (unit), from its joint toward its child
  // joint or keypoint tip.
  std::vector<Vec3> boneAxis;
  std::vector<int> jointOfBody;  // joint whose child is the body, -1 for the root
  // Per finger, its tip keypoint in the distal body's frame, m.
  std::array<Vec3, kFingerCount> tipLocal{};
  // Forearm axis in the forearm's body frame, unit, from the wrist toward the elbow. The
  // forearm is cut off (by the image or by segmentation), so its elbow-side end is no
  // surface: samples there must not pull it (see Simulator).
  Vec3 forearmAxis = Vec3::UnitZ();
};

struct RigSettings {
  float boneMass = 1.0f;           // kg per finger bone (the original tracker used 1)
  float palmMass = 4.0f;           // kg
  float forearmMass = 6.0f;        // kg
  float velocityRetention = 0.8f;  // per physics step (the original's damping 0.8)
  float graspConeDeg = 10.0f;      // neighbouring fingertip / middle bones, deg
};

class HandRig {
 public:
  // model must be a hand: 17 bodies in the documented order with the 21 keypoints.
  static Result<HandRig> create(const model::ArticulatedModel& model,
                                const physics::WorldSettings& world, const RigSettings& settings,
                                float stepDt);

  const model::ArticulatedModel& model() const { return *model_; }
  physics::World& world() { return world_; }
  const physics::World& world() const { return world_; }
  const HandAnatomy& anatomy() const { return anatomy_; }
  const std::vector<physics::ConeId>& graspCones() const { return graspCones_; }

  // Sets every body's pose (velocities zero).
  void setPose(const model::ModelPose& pose);
  // The bodies' current world poses.
  void readPose(model::ModelPose& out) const;
  // Physics joint rotation (parent frame -> child frame) for model joint angles.
  Quat physicsJointRotation(int joint, const Vec3& modelAngles) const;

  static Quat modelToPhysics();

 private:
  HandRig() = default;
  const model::ArticulatedModel* model_ = nullptr;
  physics::World world_;
  HandAnatomy anatomy_;
  std::vector<physics::ConeId> graspCones_;
};

}  // namespace dynahand::track
