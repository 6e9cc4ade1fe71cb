/// @file
/// The physics playground (paper section "Application"): a scene of boxes, spheres, convex
/// meshes, a barbell, a lever, a dial, a swing and static walls/table under gravity, with a
/// virtual hand driven as a powered ragdoll by tracked hand poses. Geometry and friction, not
/// gestures, grasp and move things: the palm follows the tracked palm through a force- and
/// torque-limited drive and each finger joint is driven towards the tracked relative rotation
/// with a torque limit, so the hand stops at walls and cannot fling heavy objects.
///
/// Frames: the scene frame is metres with +y up (gravity along -y by default); tracked poses
/// are in the tracking camera's frame (OpenCV: x right, y down, z forward) and are mapped into
/// the scene through the scene's camera pose plus the navigation offset (docs/playground.md).
///
///   auto scene = playground::loadScene("examples/scenes/grasp.json");
///   auto pg = playground::Playground::create(*scene, model::makeDefaultHand());
///   pg->step(trackedPoseInCamera, 1.0f / 30.0f);   // one input frame (2 physics steps)
///   pg->bodyPose(pg->bodyIndex("box"));
#pragma once

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "dynahand/core.h"
#include "dynahand/depth_frame.h"
#include "dynahand/model.h"
#include "dynahand/model_pose.h"
#include "dynahand/physics_world.h"

namespace dynahand::playground {

/// Scene file format version (docs/formats/scene.md).
inline constexpr int kSceneFormatVersion = 1;

/// What a scene object is (docs/formats/scene.md).
enum class ObjectKind { Box, Sphere, Cylinder, Convex, Barbell, Lever, Dial, Swing };

/// One entry of the scene's "objects" list. Which fields matter depends on the kind
/// (docs/formats/scene.md); all lengths m, angles rad, masses kg.
struct ObjectSpec {
  std::string name;                   ///< unique, non-empty, no '/'; names the object's bodies
  ObjectKind kind = ObjectKind::Box;  ///< what the object is
  bool isStatic = false;              ///< box/sphere/cylinder/convex: never moves (walls, table)
  Vec3 position = Vec3::Zero();  ///< scene frame: body centre (box, sphere, ...), hinge (lever,
                                 ///< dial), top anchor (swing)
  Quat orientation = Quat::Identity();    ///< body orientation in the scene frame
  float mass = 0.2f;                      ///< whole object (barbell: bar + caps; swing: per link)
  Vec3 size = Vec3(0.05f, 0.05f, 0.05f);  ///< box: full edge lengths; lever arm; dial fin
  float radius = 0.03f;                   ///< sphere, cylinder, barbell bar, dial knob
  float length = 0.1f;                    ///< cylinder, barbell bar (along the body's x axis)
  float capRadius = 0.045f;               ///< barbell end caps
  float capLength = 0.02f;                ///< barbell end cap thickness
  std::vector<Vec3> points;               ///< convex: hull points, body frame
  Vec3 axis = Vec3::UnitX();              ///< lever/dial hinge axis, scene frame (unit)
  float lowerLimit = 0.0f;                ///< lever/dial hinge limits, rad about axis
  float upperLimit = 0.0f;                ///< see lowerLimit
  float startAngle = 0.0f;                ///< lever/dial initial hinge angle, rad
  float hingeDamping = 0.0f;              ///< lever/dial angular damping, 1/s
  int links = 3;                          ///< swing: chain links (the last is the seat)
};

/// Limits of the virtual hand's drives ("realistic" human values, docs/playground.md).
struct HandDriveSettings {
  float palmMaxForce = 40.0f;       ///< N
  float palmMaxTorque = 3.0f;       ///< N m
  float palmTimeConstant = 0.05f;   ///< s
  float palmMaxSpeed = 0.5f;        ///< m/s the palm drive aims for at most (<= 0.6: see
                                    ///< the contact margin in playground.cpp)
  float fingerMaxTorque = 0.6f;     ///< N m, finger MCP joints (PIP 60 %, DIP 35 %)
  float thumbMaxTorque = 0.8f;      ///< N m, thumb CMC (MCP 60 %, IP 35 %)
  float jointTimeConstant = 0.04f;  ///< s (unused while jointSpringAngle > 0)
  /// Joint drives are springs (World::setJointDriveSpring) reaching their torque cap at this
  /// angle error (rad): stiffness = cap / jointSpringAngle. 0: velocity servos (time constant).
  float jointSpringAngle = 2.0f;
  float jointDampingRatio = 1.0f;  ///< damping ratio of the joint drive springs
};

/// View navigation: while the tracked palm is within `edgeMargin` (fraction of the image half
/// size) of the image border, the workspace offset moves that way at up to `speed` m/s.
struct NavigationSettings {
  bool enabled = true;       ///< false: the offset stays zero
  float edgeMargin = 0.15f;  ///< fraction of the half-width/half-height, [0, 1)
  float speed = 0.3f;        ///< m/s at the border
};

/// A playground scene: physics settings, camera pose, hand drives and objects.
struct SceneSpec {
  std::string name;                         ///< scene name
  Vec3 gravity = Vec3(0.0f, -9.81f, 0.0f);  ///< m/s^2, scene frame
  Pose camera;  ///< the tracking camera's pose in the scene (camera frame -> scene frame)
  float stepDt = 1.0f / 60.0f;      ///< s per physics step
  float friction = 0.9f;            ///< Coulomb coefficient of every contact (skin, objects)
  HandDriveSettings hand;           ///< limits of the virtual hand's drives
  NavigationSettings navigation;    ///< view navigation
  std::vector<ObjectSpec> objects;  ///< the scene's objects
};

/// A camera pose in the scene (y up) at `position`, looking along -z pitched down by pitch
/// rad, then turned by yaw rad about the scene's y axis. Pitch 35 degrees is the head-mounted
/// view; pitch -90 (looking up), yaw 180 maps a desk camera's view of a palm (synth
/// CameraPlacement::DeskFacing) to a palm facing the table (docs/playground.md).
Pose cameraLookingDown(const Vec3& position, float pitch, float yaw = 0.0f);

/// Scene files (JSON, docs/formats/scene.md). Errors name the file and the JSON path.
Result<SceneSpec> loadScene(const std::filesystem::path& path);
/// Parses scene JSON text; errors start with sourceName (a file name or similar).
Result<SceneSpec> parseScene(const std::string& jsonText, const std::string& sourceName);

/// Workspace offset from the palm's position in the tracking camera (see NavigationSettings).
class ViewNavigator {
 public:
  /// A navigator for the tracking camera `camera`, offset zero.
  ViewNavigator(const NavigationSettings& settings, const Intrinsics& camera)
      : settings_(settings), camera_(camera) {}
  /// Advances the offset by dt seconds for a palm at palmInCamera (m, camera frame); the
  /// offset is along the camera's x and y axes (in the camera frame, m).
  void update(const Vec3& palmInCamera, float dt);
  const Vec3& offset() const { return offset_; }  ///< the current offset, camera frame, m

 private:
  NavigationSettings settings_;
  Intrinsics camera_;
  Vec3 offset_ = Vec3::Zero();
};

/// One scene body as named in the output (compound objects give several: "barbell/bar").
struct SceneBody {
  std::string name;         ///< object name, or "object/part"; hand bodies "hand/..."
  physics::BodyId id = -1;  ///< the body in Playground::world()
  bool isHand = false;      ///< part of the virtual hand
  bool isStatic = false;    ///< never moves
};

/// A running physics playground: the scene's world with the virtual hand in it.
class Playground {
 public:
  /// The hand model must have the default hand's layout (a "forearm" root and a "palm").
  static Result<std::unique_ptr<Playground>> create(const SceneSpec& scene,
                                                    const model::ArticulatedModel& hand);
  ~Playground();

  /// Places the virtual hand at the tracked pose without simulating (first frame).
  void placeHand(const model::ModelPose& trackedInCamera);
  /// One input frame of dt seconds: sets the drive targets from the tracked pose (camera
  /// frame, all model bodies) and runs round(dt / stepDt) physics steps. With no tracked pose
  /// (hand lost) the previous targets are kept.
  void step(const std::optional<model::ModelPose>& trackedInCamera, float dt);
  /// Only enables navigation when the tracking camera's intrinsics are known.
  void setCameraIntrinsics(const Intrinsics& camera);

  const SceneSpec& scene() const;                ///< the scene it was created from
  const physics::World& world() const;           ///< the physics world
  physics::World& world();                       ///< the physics world
  const std::vector<SceneBody>& bodies() const;  ///< every body, hand bodies included
  int bodyIndex(const std::string& name) const;  ///< into bodies(), -1 when absent
  Pose bodyPose(int index) const;                ///< scene-frame pose of bodies()[index]
  /// The tracked hand mapped into the scene (what the drives aim for), per model body.
  const model::ModelPose& handTarget() const;
  /// The virtual hand's body poses (model layout; the forearm follows its target).
  model::ModelPose handPose() const;
  bool isHandBody(physics::BodyId body) const;  ///< whether a world body is part of the hand
  /// The current angle (rad about its axis) of the lever or dial named `object`; nullopt
  /// when there is no such hinged object.
  std::optional<float> hingeAngle(const std::string& object) const;
  /// Camera frame -> scene frame including the navigation offset.
  Pose trackingToScene() const;
  double time() const;  ///< s simulated

 private:
  struct Impl;
  explicit Playground(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

/// Deepest penetration (m, >= 0) of any hand body into body `other` in the last step.
float handPenetration(const Playground& playground, physics::BodyId other);

}  // namespace dynahand::playground
