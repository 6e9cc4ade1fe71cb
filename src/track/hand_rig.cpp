#include "track/hand_rig.h"

#include "dynahand/model_world.h"

#include <cmath>
#include <numbers>

namespace dynahand::track {

namespace {

// Keypoint names at the distal end of each body of a finger (tip of the chain last).
constexpr std::array<std::array<const char*, 3>, kFingerCount> kBodyEndKeypoint = {{
    {"thumb_mcp", "thumb_ip", "thumb_tip"},
    {"index_pip", "index_dip", "index_tip"},
    {"middle_pip", "middle_dip", "middle_tip"},
    {"ring_pip", "ring_dip", "ring_tip"},
    {"pinky_pip", "pinky_dip", "pinky_tip"},
}};

}  // namespace

Quat HandRig::modelToPhysics() {
  return model::modelToPhysicsFrame();
}

Result<HandRig> HandRig::create(const model::ArticulatedModel& model,
                                const physics::WorldSettings& worldSettings,
                                const RigSettings& settings, float stepDt) {
  if (model.bodyCount() != 17 || model.jointCount() != 16 || !model.hasKeypoints21()) {
    return Error{
        "the tracker needs a hand model: 17 bodies, 16 joints and the 21 hand keypoints (model '" +
        model.metadata().name + "' has " + std::to_string(model.bodyCount()) + " bodies)"};
  }
  HandRig rig;
  rig.model_ = &model;
  rig.world_ = physics::World(worldSettings);
  auto& world = rig.world_;
  const int n = model.bodyCount();
  HandAnatomy& a = rig.anatomy_;
  for (int f = 0; f < kFingerCount; ++f) {
    for (int k = 0; k < 3; ++k)
      a.fingers[static_cast<std::size_t>(f)][static_cast<std::size_t>(k)] = 2 + 3 * f + k;
  }
  a.jointOfBody.assign(static_cast<std::size_t>(n), -1);
  for (int j = 0; j < model.jointCount(); ++j) {
    a.jointOfBody[static_cast<std::size_t>(model.joints()[static_cast<std::size_t>(j)].child)] = j;
  }

  // Bone axes from the zero pose: joint anchor toward the body's distal keypoint.
  const model::ModelPose rest = model::forwardKinematics(model, model::zeroAngles(model));
  std::vector<Vec3> keypoints;
  model::keypointPositionsInto(model, rest, keypoints);
  a.boneAxis.assign(static_cast<std::size_t>(n), Vec3::UnitZ());
  for (int f = 0; f < kFingerCount; ++f) {
    for (int k = 0; k < 3; ++k) {
      const int body = a.fingers[static_cast<std::size_t>(f)][static_cast<std::size_t>(k)];
      const int kp = model.keypointIndex(
          kBodyEndKeypoint[static_cast<std::size_t>(f)][static_cast<std::size_t>(k)]);
      const int j = a.jointOfBody[static_cast<std::size_t>(body)];
      if (kp < 0 || j < 0)
        return Error{"hand model lacks the keypoints of finger " + std::to_string(f)};
      const Pose& pose = rest.bodies[static_cast<std::size_t>(body)];
      const Vec3 from = model.joints()[static_cast<std::size_t>(j)].anchorChild;
      const Vec3 to = pose.inverseTransform(keypoints[static_cast<std::size_t>(kp)]);
      if ((to - from).norm() < 1e-4f)
        return Error{"degenerate bone axis on body " +
                     model.bodies()[static_cast<std::size_t>(body)].name};
      a.boneAxis[static_cast<std::size_t>(body)] = (to - from).normalized();
      if (k == 2) a.tipLocal[static_cast<std::size_t>(f)] = to;
    }
  }

  {
    const int wristJoint = a.jointOfBody[static_cast<std::size_t>(a.palm)];
    const Vec3 wrist =
        model.joints()[static_cast<std::size_t>(wristJoint)].anchorParent;  // forearm frame
    const Vec3 toElbow =
        model.bodies()[static_cast<std::size_t>(a.forearm)].shape.centroid() - wrist;
    if (toElbow.norm() < 1e-4f) return Error{"the forearm's centroid is at the wrist"};
    a.forearmAxis = toElbow.normalized();
  }
  // Bodies, joints with limits and the collision filter as the model defines them; the
  // tracker's own masses (the original used 1 per bone, heavier palm and wrist) and damping.
  model::WorldBuildOptions build;
  build.linearDamping = physics::dampingFromRetention(settings.velocityRetention, stepDt);
  build.angularDamping = build.linearDamping;
  const model::ModelInWorld ids = model::addToWorld(world, model, rest, build);
  for (int b = 0; b < n; ++b) {
    if (ids.bodies[static_cast<std::size_t>(b)] != b)
      return Error{"unexpected body order in the physics world"};
    world.setMass(b, b == a.forearm ? settings.forearmMass
                                    : (b == a.palm ? settings.palmMass : settings.boneMass));
  }
  // Grasp bias: neighbouring fingers' middle and distal bones within a cone (index..pinky).
  const float cone = settings.graspConeDeg * std::numbers::pi_v<float> / 180.0f;
  for (int k = 1; k <= 2; ++k) {
    for (int f = 1; f + 1 < kFingerCount; ++f) {
      const int b0 = a.fingers[static_cast<std::size_t>(f)][static_cast<std::size_t>(k)];
      const int b1 = a.fingers[static_cast<std::size_t>(f + 1)][static_cast<std::size_t>(k)];
      const auto id = world.addAngularCone(b0, a.boneAxis[static_cast<std::size_t>(b0)], b1,
                                           a.boneAxis[static_cast<std::size_t>(b1)], cone);
      world.setConeEnabled(id, false);
      rig.graspCones_.push_back(id);
    }
  }
  return rig;
}

void HandRig::setPose(const model::ModelPose& pose) {
  for (int b = 0; b < world_.bodyCount(); ++b) {
    world_.setPose(b, pose.bodies[static_cast<std::size_t>(b)]);
    world_.setVelocity(b, Vec3::Zero(), Vec3::Zero());
  }
}

void HandRig::readPose(model::ModelPose& out) const {
  out.bodies.resize(static_cast<std::size_t>(world_.bodyCount()));
  for (int b = 0; b < world_.bodyCount(); ++b)
    out.bodies[static_cast<std::size_t>(b)] = world_.pose(b);
}

Quat HandRig::physicsJointRotation(int /*joint*/, const Vec3& modelAngles) const {
  const Quat q = modelToPhysics();
  return (q.conjugate() * model::jointRotation(modelAngles) * q).normalized();
}

}  // namespace dynahand::track
