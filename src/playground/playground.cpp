// The playground: scene objects plus the powered-ragdoll virtual hand (docs/playground.md).
//
// The hand is the tracking model without its forearm, plus three pads welded under the palm
// (thenar, hypothenar, distal) so the palm is deeper and slightly concave, as the paper
// recommends for grasping. Each input frame the tracked pose (camera frame) is mapped into
// the scene; the palm gets a body drive towards its target (force/torque capped), every
// finger joint a joint drive towards the tracked relative rotation (torque capped). The palm
// target is interpolated over the physics steps of one input frame so it moves smoothly.
#include <algorithm>
#include <cassert>
#include <cmath>

#include "dynahand/model_world.h"
#include "dynahand/playground.h"
#include "scene_build.h"

namespace dynahand::playground {

// Joint drive targets stay this far inside the joint limits (rad, 4 degrees; see setTargets).
constexpr float kLimitMargin = 0.07f;
// Axes the hand model locks (min == max: abduction and twist of the finger PIP/DIP and thumb
// IP joints) get this much play either side (rad, 1 degree). The physics engine limits a
// locked axis with two opposing one-sided rows; on the thumb IP they fought each other and
// the thumb swung 20-60 degrees off its target in free air, shaking the whole hand (fingers
// 40 degrees off theirs, objects rattling in the grip). One degree of play keeps only one
// row active at a time and the thumb within 1-4 degrees of its target.
constexpr float kLockedAxisPlay = 0.0175f;

struct Playground::Impl {
  SceneSpec scene;
  model::ArticulatedModel handCopy;
  physics::World world;
  std::vector<SceneBody> bodies;
  std::vector<detail::HingeRecord> hinges;
  std::vector<physics::BodyId> handBodies;   // per model body, -1 for the forearm
  std::vector<physics::JointId> handJoints;  // per model joint, -1 for the wrist
  std::vector<float> jointTorque;            // per model joint, N m
  std::vector<unsigned char> handFlag;       // per world body
  int forearm = -1, palm = -1;               // model body indices
  model::ModelPose target;                   // tracked hand in the scene
  model::JointAngles driveAngles;            // scratch: tracked angles kept off the limits
  model::ModelPose drivePose;                // scratch: the pose of driveAngles
  bool hasTarget = false;
  std::optional<ViewNavigator> navigator;
  double time = 0.0;

  Impl(const SceneSpec& s, const model::ArticulatedModel& hand) : scene(s), handCopy(hand) {}

  Pose trackingToScene() const {
    const Vec3 offset = navigator ? navigator->offset() : Vec3::Zero();
    return scene.camera * Pose{offset, Quat::Identity()};
  }

  // The arm's muscles carry the fingers' own weight: cancelling gravity on the finger
  // bodies before each step keeps a still hand still with few sweeps (without it the drives
  // and joints, solved in 8 sweeps, leave the fingertips sagging 5-20 mm). Objects the hand
  // holds still weigh on it through the contacts. The palm's drive carries its own weight.
  void compensateFingerWeight() {
    const Vec3 dv = -scene.gravity * scene.stepDt;
    for (std::size_t b = 0; b < handBodies.size(); ++b) {
      const physics::BodyId id = handBodies[b];
      if (id < 0 || static_cast<int>(b) == palm) continue;
      world.setVelocity(id, world.linearVelocity(id) + dv, world.angularVelocity(id));
    }
  }

  void setTargets(const model::ModelPose& camera) {
    const Pose toScene = trackingToScene();
    target.bodies.resize(camera.bodies.size());
    for (std::size_t b = 0; b < camera.bodies.size(); ++b)
      target.bodies[b] = toScene * camera.bodies[b];
    const HandDriveSettings& h = scene.hand;
    // A drive aiming at (or past) a joint limit pushes into the limit row with its full torque
    // every step and the two fight; the tracker's poses and the clips do reach the limits, so
    // the drive targets are kept kLimitMargin inside them.
    model::jointAnglesInto(handCopy, camera, driveAngles);
    for (std::size_t j = 0; j < driveAngles.angles.size(); ++j) {
      const model::Joint& mj = handCopy.joints()[j];
      for (int k = 0; k < 3; ++k) {
        const float lo = mj.minAngle[k], hi = mj.maxAngle[k];
        const float margin = std::min(kLimitMargin, 0.5f * (hi - lo));
        driveAngles.angles[j][k] = std::clamp(driveAngles.angles[j][k], lo + margin, hi - margin);
      }
    }
    model::forwardKinematicsInto(handCopy, driveAngles, drivePose);
    for (std::size_t j = 0; j < handJoints.size(); ++j) {
      if (handJoints[j] < 0) continue;
      const physics::JointDef& def = world.joint(handJoints[j]);
      const model::Joint& mj = handCopy.joints()[j];
      const Quat parent = drivePose.bodies[static_cast<std::size_t>(mj.parent)].q * def.frameParent;
      const Quat child = drivePose.bodies[static_cast<std::size_t>(mj.child)].q * def.frameChild;
      world.setJointDrive(handJoints[j], (parent.conjugate() * child).normalized(), jointTorque[j],
                          h.jointTimeConstant);
    }
  }
};

namespace {

constexpr float kFingerMass = 0.04f;  // kg, least mass of a finger body (see create)

float jointTorqueFor(const std::string& childName, const HandDriveSettings& h) {
  auto endsWith = [&](const char* suffix) {
    const std::string s(suffix);
    return childName.size() >= s.size() &&
           childName.compare(childName.size() - s.size(), s.size(), s) == 0;
  };
  const bool thumb = childName.rfind("thumb", 0) == 0;
  const float base = thumb ? h.thumbMaxTorque : h.fingerMaxTorque;
  if (endsWith("_distal")) return 0.35f * base;
  if (endsWith("_middle") || (thumb && endsWith("_proximal"))) return 0.6f * base;
  return base;  // finger proximal (MCP), thumb metacarpal (CMC)
}

// Palm extents in its body frame: min and max over the hull vertices.
void palmBounds(const physics::ConvexShape& shape, Vec3& lo, Vec3& hi) {
  lo = Vec3::Constant(1e9f);
  hi = Vec3::Constant(-1e9f);
  for (const Vec3& v : shape.vertices()) {
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
}

}  // namespace

namespace {

physics::World makeWorld(const SceneSpec& scene) {
  physics::WorldSettings ws;
  ws.gravity = scene.gravity;
  ws.friction = scene.friction;
  // 32 sweeps: with 16, a thumb tucked in a fist that the palm drive (40 N) pressed into a
  // wall folded past its joint limits (unconverged chain palm-thumb-wall) and then sprang
  // free, ending 1-2 cm inside the wall; 32 keep it under 0.5 mm. About 90 us more per step.
  ws.iterations = 32;
  ws.relaxIterations = 2;
  ws.positionIterations = 0;
  // One pass per manifold per sweep: 32 sweeps spread the load without the extra pass, which
  // cost a third of the step (grasp scene 459 -> 320 us CPU) and held no scenario better.
  ws.contactInnerIterations = 1;
  ws.contactErp = 0.5f;
  // Speculative contacts reach this far (m): more than the palm moves in one step at its
  // speed cap (palmMaxSpeed 0.5 m/s -> 8 mm at 60 Hz), so it does not tunnel. Larger margins
  // (2.5 cm tried) make libccd's MPR pick side faces of the table for small resting objects.
  ws.contactMargin = 0.01f;
  return physics::World(ws);
}

// The hand's bodies (all but the forearm) at restPose, far above the scene.
std::vector<physics::BodyId> addHandBodies(const model::ArticulatedModel& hand, int forearm,
                                           int palm, const model::ModelPose& restPose,
                                           detail::SceneBuilder& builder, float damping) {
  std::vector<physics::BodyId> handBodies(hand.bodies().size(), -1);
  for (std::size_t b = 0; b < hand.bodies().size(); ++b) {
    if (static_cast<int>(b) == forearm) continue;
    const model::Body& body = hand.bodies()[b];
    // Phalanges of 3-10 g against a 0.3 kg palm make a stiff chain the sweeps cannot settle
    // when the palm drive pushes a finger into a wall (it sank 5-10 mm); a mass floor
    // conditions the chain. Their weight is carried (compensateFingerWeight), so it only
    // adds inertia.
    const float mass = static_cast<int>(b) == palm ? body.mass : std::max(body.mass, kFingerMass);
    handBodies[b] =
        builder.add("hand/" + body.name, body.shape, restPose.bodies[b], mass, false, damping);
  }
  return handBodies;
}

// The hand's joints (handJoints, jointTorque: per model joint) with their limits and spring
// drives; no self-collision.
void addHandJoints(physics::World& world, const model::ArticulatedModel& hand, int forearm,
                   const std::vector<physics::BodyId>& handBodies, const SceneSpec& scene,
                   std::vector<physics::JointId>& handJoints, std::vector<float>& jointTorque) {
  const Quat toPhysics = model::modelToPhysicsFrame();
  handJoints.assign(hand.joints().size(), -1);
  jointTorque.assign(hand.joints().size(), 0.0f);
  for (std::size_t j = 0; j < hand.joints().size(); ++j) {
    const model::Joint& joint = hand.joints()[j];
    if (joint.parent == forearm) continue;
    physics::JointDef def;
    def.parent = handBodies[static_cast<std::size_t>(joint.parent)];
    def.child = handBodies[static_cast<std::size_t>(joint.child)];
    def.anchorParent = joint.anchorParent;
    def.anchorChild = joint.anchorChild;
    def.frameParent = (joint.frame * toPhysics).normalized();
    def.frameChild = toPhysics;
    def.limitsEnabled = true;
    def.lower = Vec3(joint.minAngle.x(), -joint.maxAngle.y(), joint.minAngle.z());
    def.upper = Vec3(joint.maxAngle.x(), -joint.minAngle.y(), joint.maxAngle.z());
    for (int k = 0; k < 3; ++k) {
      if (def.upper[k] - def.lower[k] < kLockedAxisPlay) {
        def.lower[k] -= kLockedAxisPlay;
        def.upper[k] += kLockedAxisPlay;
      }
    }
    handJoints[j] = world.addJoint(def);
    jointTorque[j] =
        jointTorqueFor(hand.bodies()[static_cast<std::size_t>(joint.child)].name, scene.hand);
    // A spring-damper, not a velocity servo: a servo reaches its torque cap at the smallest
    // error, so fingers and thumb squeezing an object from both sides each pushed with their
    // full cap and the object, between two unbalanced constant forces, was shaken loose
    // within a second. With a spring the digits settle where their torques balance.
    if (scene.hand.jointSpringAngle > 0.0f)
      world.setJointDriveSpring(handJoints[j], jointTorque[j] / scene.hand.jointSpringAngle,
                                scene.hand.jointDampingRatio);
  }
  // No self-collision: the tracker already keeps its bones apart, and poses such as a tight
  // fist touch bone to bone, where contacts would fight the drives and spring the fingers open.
  for (int a = 0; a < hand.bodyCount(); ++a)
    for (int b = a + 1; b < hand.bodyCount(); ++b)
      if (handBodies[a] >= 0 && handBodies[b] >= 0)
        world.setCollisionEnabled(handBodies[a], handBodies[b], false);
}

// Palm pads: ellipsoids whose centres sit just inside the palmar surface (-y), so they stand
// ~4 mm proud of it and leave the palm's centre slightly hollow; welded to the palm.
void addPalmPads(physics::World& world, const model::ArticulatedModel& hand, int palm,
                 const std::vector<physics::BodyId>& handBodies, const model::ModelPose& restPose,
                 detail::SceneBuilder& builder, float damping) {
  Vec3 lo, hi;
  palmBounds(hand.bodies()[palm].shape, lo, hi);
  const float halfWidth = 0.5f * (hi.x() - lo.x()), reach = hi.z();
  struct Pad {
    const char* name;
    Vec3 centre, semiAxes;
  };
  const Pad pads[] = {
      {"pad_thenar",
       {0.45f * hi.x(), lo.y() + 0.002f, 0.3f * reach},
       {0.35f * halfWidth, 0.006f, 0.25f * reach}},
      {"pad_hypothenar",
       {0.5f * lo.x(), lo.y() + 0.002f, 0.35f * reach},
       {0.3f * halfWidth, 0.006f, 0.28f * reach}},
      {"pad_distal",
       {0.0f, lo.y() + 0.003f, 0.78f * reach},
       {0.75f * halfWidth, 0.006f, 0.12f * reach}},
  };
  const physics::BodyId palmId = handBodies[static_cast<std::size_t>(palm)];
  std::vector<physics::BodyId> welded = {palmId};
  for (const Pad& pad : pads) {
    const Pose padPose =
        restPose.bodies[static_cast<std::size_t>(palm)] * Pose{pad.centre, Quat::Identity()};
    const physics::BodyId id =
        builder.add(std::string("hand/") + pad.name, detail::ellipsoidShape(pad.semiAxes), padPose,
                    0.01f, false, damping);
    for (physics::BodyId h : handBodies)
      if (h >= 0) world.setCollisionEnabled(id, h, false);
    for (physics::BodyId w : welded) world.setCollisionEnabled(id, w, false);
    welded.push_back(id);
  }
  world.weld(welded);
}

}  // namespace

Playground::Playground(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Playground::~Playground() = default;

Result<std::unique_ptr<Playground>> Playground::create(const SceneSpec& scene,
                                                       const model::ArticulatedModel& hand) {
  auto impl = std::make_unique<Impl>(scene, hand);
  Impl& m = *impl;
  m.forearm = hand.bodyIndex("forearm");
  m.palm = hand.bodyIndex("palm");
  if (m.forearm != hand.root() || m.palm < 0 || hand.bodies()[m.palm].parent != m.forearm)
    return Error{"the playground hand needs the default hand's layout (forearm root, palm)"};
  m.world = makeWorld(scene);

  detail::SceneBuilder builder(m.world, m.bodies);
  for (const ObjectSpec& o : scene.objects)
    if (Status s = builder.addObject(o); !s) return Error{s.message()};
  m.hinges = builder.hinges();

  // The hand at the model's rest pose, far above the scene until placeHand/step.
  model::JointAngles rest = model::zeroAngles(hand);
  model::clampToLimits(hand, rest);
  rest.root.p = Vec3(0, 100, 0);
  const model::ModelPose restPose = model::forwardKinematics(hand, rest);
  const float damping = 2.0f;  // 1/s: calms finger chatter without visible lag
  m.handBodies = addHandBodies(hand, m.forearm, m.palm, restPose, builder, damping);
  addHandJoints(m.world, hand, m.forearm, m.handBodies, scene, m.handJoints, m.jointTorque);
  addPalmPads(m.world, hand, m.palm, m.handBodies, restPose, builder, damping);

  m.handFlag.assign(static_cast<std::size_t>(m.world.bodyCount()), 0);
  for (SceneBody& body : m.bodies) {
    if (body.name.rfind("hand/", 0) == 0) {
      body.isHand = true;
      m.handFlag[static_cast<std::size_t>(body.id)] = 1;
    }
  }
  return std::unique_ptr<Playground>(new Playground(std::move(impl)));
}

void Playground::setCameraIntrinsics(const Intrinsics& camera) {
  if (impl_->scene.navigation.enabled) impl_->navigator.emplace(impl_->scene.navigation, camera);
}

void Playground::placeHand(const model::ModelPose& trackedInCamera) {
  Impl& m = *impl_;
  assert(trackedInCamera.bodies.size() == m.handBodies.size());
  m.setTargets(trackedInCamera);
  m.hasTarget = true;
  // Move the welded palm group rigidly, then every finger body to its target.
  const physics::BodyId palm = m.handBodies[static_cast<std::size_t>(m.palm)];
  m.world.setPose(palm, m.target.bodies[static_cast<std::size_t>(m.palm)]);
  m.world.setVelocity(palm, Vec3::Zero(), Vec3::Zero());
  for (std::size_t b = 0; b < m.handBodies.size(); ++b) {
    if (m.handBodies[b] < 0 || static_cast<int>(b) == m.palm) continue;
    m.world.setPose(m.handBodies[b], m.target.bodies[b]);
    m.world.setVelocity(m.handBodies[b], Vec3::Zero(), Vec3::Zero());
  }
}

void Playground::step(const std::optional<model::ModelPose>& trackedInCamera, float dt) {
  Impl& m = *impl_;
  const std::size_t palm = static_cast<std::size_t>(m.palm);
  if (trackedInCamera && !m.hasTarget) placeHand(*trackedInCamera);
  const Pose previousPalm = m.hasTarget ? m.target.bodies[palm] : Pose{};
  if (trackedInCamera) {
    assert(trackedInCamera->bodies.size() == m.handBodies.size());
    if (m.navigator) m.navigator->update(trackedInCamera->bodies[palm].p, dt);
    m.setTargets(*trackedInCamera);
  }
  const int steps = std::max(1, static_cast<int>(std::lround(dt / m.scene.stepDt)));
  const HandDriveSettings& h = m.scene.hand;
  const physics::BodyId palmId = m.handBodies[palm];
  for (int k = 0; k < steps; ++k) {
    if (m.hasTarget) {
      const float t = static_cast<float>(k + 1) / static_cast<float>(steps);
      Pose aim = interpolate(previousPalm, m.target.bodies[palm], t);
      // The drive's velocity is error / time constant: cap the error so the palm never
      // outruns the speculative contact margin (no tunnelling through walls or the table).
      const Vec3 at = m.world.pose(palmId).p;
      const float reach = h.palmMaxSpeed * std::max(h.palmTimeConstant, m.scene.stepDt);
      if ((aim.p - at).norm() > reach) aim.p = at + (aim.p - at).normalized() * reach;
      m.world.setBodyDrive(palmId, aim, h.palmMaxForce, h.palmMaxTorque, h.palmTimeConstant);
    }
    m.compensateFingerWeight();
    m.world.step(m.scene.stepDt);
    m.time += static_cast<double>(m.scene.stepDt);
  }
}

const SceneSpec& Playground::scene() const {
  return impl_->scene;
}
const physics::World& Playground::world() const {
  return impl_->world;
}
physics::World& Playground::world() {
  return impl_->world;
}
const std::vector<SceneBody>& Playground::bodies() const {
  return impl_->bodies;
}

int Playground::bodyIndex(const std::string& name) const {
  for (std::size_t i = 0; i < impl_->bodies.size(); ++i)
    if (impl_->bodies[i].name == name) return static_cast<int>(i);
  return -1;
}

Pose Playground::bodyPose(int index) const {
  return impl_->world.pose(impl_->bodies[static_cast<std::size_t>(index)].id);
}

const model::ModelPose& Playground::handTarget() const {
  return impl_->target;
}

model::ModelPose Playground::handPose() const {
  const Impl& m = *impl_;
  model::ModelPose out;
  out.bodies.resize(m.handBodies.size());
  for (std::size_t b = 0; b < m.handBodies.size(); ++b) {
    if (m.handBodies[b] >= 0) {
      out.bodies[b] = m.world.pose(m.handBodies[b]);
    } else if (m.hasTarget) {
      // The forearm is not simulated: keep it where the tracked wrist-to-palm relation puts
      // it relative to the simulated palm.
      const std::size_t palm = static_cast<std::size_t>(m.palm);
      out.bodies[b] =
          m.world.pose(m.handBodies[palm]) * (m.target.bodies[palm].inverse() * m.target.bodies[b]);
    }
  }
  return out;
}

bool Playground::isHandBody(physics::BodyId body) const {
  return impl_->handFlag[static_cast<std::size_t>(body)] != 0;
}

std::optional<float> Playground::hingeAngle(const std::string& object) const {
  for (const detail::HingeRecord& h : impl_->hinges)
    if (h.object == object) return impl_->world.jointAngles(h.joint).x();
  return std::nullopt;
}

Pose Playground::trackingToScene() const {
  return impl_->trackingToScene();
}
double Playground::time() const {
  return impl_->time;
}

float handPenetration(const Playground& playground, physics::BodyId other) {
  float deepest = 0.0f;
  for (const physics::ContactPoint& c : playground.world().contacts()) {
    const bool pair = (c.a == other && playground.isHandBody(c.b)) ||
                      (c.b == other && playground.isHandBody(c.a));
    if (pair) deepest = std::max(deepest, -c.separation);
  }
  return deepest;
}

void ViewNavigator::update(const Vec3& palmInCamera, float dt) {
  if (!settings_.enabled || !(palmInCamera.z() > 0.0f)) return;
  const Vec2 pixel = camera_.project(palmInCamera);
  // Normalised position in [-1, 1] across the image; beyond 1 - margin the offset moves.
  const float halfW = 0.5f * static_cast<float>(camera_.width);
  const float halfH = 0.5f * static_cast<float>(camera_.height);
  const Vec2 n((pixel.x() - halfW) / halfW, (pixel.y() - halfH) / halfH);
  const float start = 1.0f - settings_.edgeMargin;
  auto push = [&](float x) {
    const float over = (std::abs(x) - start) / std::max(settings_.edgeMargin, 1e-6f);
    return over > 0.0f ? std::copysign(std::min(over, 1.0f), x) : 0.0f;
  };
  offset_.x() += push(n.x()) * settings_.speed * dt;
  offset_.y() += push(n.y()) * settings_.speed * dt;
}

}  // namespace dynahand::playground
