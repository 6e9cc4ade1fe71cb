// Adding a model to a physics world; see model_world.h for the frame and angle mapping.
#include <cassert>

#include "dynahand/model_world.h"

namespace dynahand::model {

Quat modelToPhysicsFrame() {
  // Columns: the physics joint axes X (along the bone), Y, Z in model joint axes.
  Mat3 m;
  m.col(0) = Vec3::UnitZ();
  m.col(1) = -Vec3::UnitY();
  m.col(2) = Vec3::UnitX();
  return Quat(m).normalized();
}

ModelInWorld addToWorld(physics::World& world, const ArticulatedModel& model, const ModelPose& pose,
                        const WorldBuildOptions& options) {
  assert(pose.bodies.size() == model.bodies().size() && "one pose per body");
  ModelInWorld ids;
  for (size_t b = 0; b < model.bodies().size(); ++b) {
    const Body& body = model.bodies()[b];
    physics::BodyDef def;
    def.shape = world.addShape(body.shape);
    def.pose = pose.bodies[b];
    def.mass = body.mass;
    def.type = options.staticRoot && static_cast<int>(b) == model.root()
                   ? physics::BodyType::Static
                   : physics::BodyType::Dynamic;
    def.linearDamping = options.linearDamping;
    def.angularDamping = options.angularDamping;
    ids.bodies.push_back(world.addBody(def));
  }
  const Quat toPhysics = modelToPhysicsFrame();
  for (const Joint& joint : model.joints()) {
    physics::JointDef def;
    def.parent = ids.bodies[static_cast<size_t>(joint.parent)];
    def.child = ids.bodies[static_cast<size_t>(joint.child)];
    def.anchorParent = joint.anchorParent;
    def.anchorChild = joint.anchorChild;
    def.frameParent = (joint.frame * toPhysics).normalized();
    def.frameChild = toPhysics;
    def.limitsEnabled = options.limitsEnabled;
    // Abduction changes sign, so the bounds swap.
    def.lower = Vec3(joint.minAngle.x(), -joint.maxAngle.y(), joint.minAngle.z());
    def.upper = Vec3(joint.maxAngle.x(), -joint.minAngle.y(), joint.maxAngle.z());
    ids.joints.push_back(world.addJoint(def));
  }
  for (int a = 0; a < model.bodyCount(); ++a) {
    for (int b = a + 1; b < model.bodyCount(); ++b) {
      world.setCollisionEnabled(ids.bodies[static_cast<size_t>(a)],
                                ids.bodies[static_cast<size_t>(b)], model.collides(a, b));
    }
  }
  return ids;
}

void readPose(const physics::World& world, const ModelInWorld& ids, ModelPose& out) {
  out.bodies.resize(ids.bodies.size());
  for (size_t b = 0; b < ids.bodies.size(); ++b) out.bodies[b] = world.pose(ids.bodies[b]);
}

}  // namespace dynahand::model
