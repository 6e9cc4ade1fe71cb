/// @file
/// An articulated model as physics: its bodies (shapes, masses, poses), ball joints with the
/// model's angle limits, and its collision filter, added to a physics::World. Generic: any
/// model file, hand or not, simulates this way.
#pragma once

#include <vector>

#include "dynahand/model_pose.h"
#include "dynahand/physics_world.h"

namespace dynahand::model {

/// How addToWorld builds the bodies and joints.
struct WorldBuildOptions {
  bool limitsEnabled = true;    ///< the joints' angle limits
  bool staticRoot = false;      ///< the root body never moves (e.g. a robot base)
  float linearDamping = 0.0f;   ///< 1/s, every dynamic body
  float angularDamping = 0.0f;  ///< 1/s
};

/// Ids of the model's bodies and joints in the world (indexed like model.bodies() / joints()).
struct ModelInWorld {
  std::vector<physics::BodyId> bodies;   ///< world body of each model body
  std::vector<physics::JointId> joints;  ///< world joint of each model joint
};

/// Adds the model at `pose` (body frames, world). Collisions between every pair of the
/// model's bodies follow model.collides().
ModelInWorld addToWorld(physics::World& world, const ArticulatedModel& model, const ModelPose& pose,
                        const WorldBuildOptions& options = {});

/// The model's body poses read back from the world (no allocation once `out` is sized).
void readPose(const physics::World& world, const ModelInWorld& ids, ModelPose& out);

/// Joint frames: a model joint frame F (in the parent) becomes the physics frames
/// frameParent = F * kModelToPhysics, frameChild = kModelToPhysics (physics X, Y, Z = model
/// z, -y, x), and model angles (f, a, t) are physics angles (f, -a, t).
Quat modelToPhysicsFrame();
/// Model joint angles (f, a, t) as physics angles (f, -a, t).
inline Vec3 toPhysicsAngles(const Vec3& modelAngles) {
  return {modelAngles.x(), -modelAngles.y(), modelAngles.z()};
}
/// Physics joint angles back to model angles: the inverse of toPhysicsAngles.
inline Vec3 fromPhysicsAngles(const Vec3& physicsAngles) {
  return {physicsAngles.x(), -physicsAngles.y(), physicsAngles.z()};
}

}  // namespace dynahand::model
