/// @file
/// The rigid-body world: convex bodies, ball-and-socket joints with angular limits and drives,
/// convex contacts, the tracker's one-body rows, welding, and one projected Gauss-Seidel solver
/// (sequential impulses with per-row impulse bounds). Units: m, kg, s, rad; impulses N s.
///
/// One step(dt) = integrate velocities -> prepare rows -> warm start persistent rows ->
/// `iterations` sweeps with position bias -> integrate positions -> `positionIterations` joint
/// position projections -> `relaxIterations` sweeps without bias (so error correction does not
/// remain as momentum, as Box2D v3's relax stage).
/// Deterministic: same inputs, same build -> identical bytes (fixed orders, no hashing).
///
/// Tracker usage per depth frame (see docs/physics.md):
///   world.saveState(frameStart);                        // once
///   for each simulation: world.restoreState(frameStart); configure drives/cones/weld;
///     for each substep: rows.clear(); fill rows (addSurface/addLineOfSight/addBoundary);
///                       world.step(dt);
#pragma once

#include <cassert>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <span>
#include <vector>

#include "dynahand/convex_shape.h"
#include "dynahand/core.h"
#include "dynahand/physics_angles.h"

namespace dynahand::physics {

using BodyId = int;   ///< index in creation order
using JointId = int;  ///< index in creation order
using ConeId = int;   ///< index in creation order
using GroupId = int;  ///< weld group, index in creation order within the current state

/// How a body moves.
enum class BodyType : std::uint8_t {
  Dynamic,    ///< moved by forces and rows
  Static,     ///< never moves (infinite mass)
  Kinematic,  ///< moves with the velocity you set; infinite mass for rows
};

/// Solver and contact settings of a World.
struct WorldSettings {
  Vec3 gravity = Vec3::Zero();  ///< m/s^2; off by default (tracking)
  int iterations = 16;          ///< Gauss-Seidel sweeps with position bias per step
  int relaxIterations = 4;      ///< sweeps without bias after position integration
  /// Nonlinear Gauss-Seidel passes that move positions (not velocities) to close the joint
  /// anchors after integration: removes the arc error of linearised rotation without momentum.
  int positionIterations = 4;
  float jointErp = 0.5f;    ///< fraction of joint position error removed per step, [0, 1]
  float contactErp = 0.2f;  ///< fraction of penetration (beyond linearSlop) removed per step
  /// Optional soft contact instead of contactErp (Box2D v3 soft step): push-out spring, Hz
  /// (0: rigid rows with contactErp) and its damping ratio.
  float contactHertz = 0.0f;
  float contactDampingRatio = 10.0f;  ///< damping ratio of the contactHertz spring
  int contactInnerIterations = 4;   ///< passes over one contact manifold per sweep (load spreading)
  float limitErp = 0.5f;            ///< fraction of angular-limit violation removed per step
  float surfaceErp = 0.5f;          ///< fraction of a surface/boundary row's gap removed per step
  float linearSlop = 1e-4f;         ///< m of penetration left uncorrected (prevents jitter)
  float maxCorrectionSpeed = 2.0f;  ///< m/s cap on contact push-out velocity
  float contactMargin = 2e-3f;      ///< m; pairs closer than this get speculative contacts
  float friction = 0.5f;            ///< Coulomb coefficient for contacts (0: frictionless)
  bool enableContacts = true;       ///< false: no contact rows between bodies at all
  bool gyroscopic = true;           ///< implicit gyroscopic torque (conserves spin energy)
  bool filterJointedPairs = true;   ///< bodies joined by a joint never collide
};

/// What World::addBody creates: shape, type, initial pose, velocity, mass and damping.
struct BodyDef {
  int shape = -1;                       ///< index from World::addShape
  BodyType type = BodyType::Dynamic;    ///< how the body moves
  Pose pose;                            ///< world pose of the body frame (the shape's frame)
  Vec3 linearVelocity = Vec3::Zero();   ///< of the centre of mass, m/s
  Vec3 angularVelocity = Vec3::Zero();  ///< rad/s, world axes
  float mass = 1.0f;                    ///< kg (dynamic bodies, > 0); inertia from the shape
  float linearDamping = 0.0f;           ///< 1/s; v *= 1 / (1 + dt * c) each step
  float angularDamping = 0.0f;          ///< 1/s
};

/// Per-step velocity retention r (e.g. 0.8) as the damping rate above for step dt: (1/r - 1)/dt.
inline float dampingFromRetention(float retentionPerStep, float dt) {
  return (1.0f / retentionPerStep - 1.0f) / dt;
}

/// A ball-and-socket joint between two bodies, with optional angular limits.
struct JointDef {
  BodyId parent = -1;                   ///< parent body
  BodyId child = -1;                    ///< child body (not the parent)
  Vec3 anchorParent = Vec3::Zero();     ///< joint centre in the parent body frame, m
  Vec3 anchorChild = Vec3::Zero();      ///< joint centre in the child body frame, m
  Quat frameParent = Quat::Identity();  ///< joint frame orientation in the parent body frame
  Quat frameChild = Quat::Identity();   ///< joint frame orientation in the child body frame
  bool limitsEnabled = false;           ///< whether lower/upper are enforced
  Vec3 lower = Vec3::Zero();  ///< (flexion, abduction, twist) lower limits, rad (physics_angles.h)
  Vec3 upper = Vec3::Zero();  ///< upper limits, rad; lower <= upper
};

/// The tracker's transient one-body rows, struct-of-arrays. Clear and refill before each
/// step; capacity is reserved once (World::reserveRows) so refilling never allocates.
/// Row i pulls the point anchor[i] (body frame of body[i]) along the unit world direction
/// normal[i] towards target[i]: C = normal·(x - target), driven to 0 with the accumulated
/// impulse clamped to [lower, upper] (N s). One-sided rows (lower = 0) only push along +normal.
struct SurfaceRows {
  std::vector<BodyId> body;    ///< body the row acts on
  std::vector<Vec3> anchor;    ///< body frame, m
  std::vector<Vec3> normal;    ///< world, unit
  std::vector<Vec3> target;    ///< world, m
  std::vector<float> lower;    ///< N s, <= 0
  std::vector<float> upper;    ///< N s, >= 0
  std::vector<float> impulse;  ///< accumulated impulse after step(), N s (output)

  int size() const { return static_cast<int>(body.size()); }  ///< number of rows
  void clear();            ///< removes every row, keeping capacity
  void reserve(int rows);  ///< reserves capacity for this many rows in every array
  /// Two-sided pull of a body point towards a target along normal; |impulse| <= cap.
  void addSurface(BodyId b, const Vec3& anchorLocal, const Vec3& normalWorld,
                  const Vec3& targetWorld, float cap) {
    add(b, anchorLocal, normalWorld, targetWorld, -cap, cap);
  }
  /// Line of sight: the body point must stay at or beyond the target along the unit camera ray
  /// direction rayDir (free space in front of an observed depth point); push-only, <= cap.
  void addLineOfSight(BodyId b, const Vec3& anchorLocal, const Vec3& rayDir,
                      const Vec3& targetWorld, float cap) {
    add(b, anchorLocal, rayDir, targetWorld, 0.0f, cap);
  }
  /// Half-space: the body point must stay on the side of the target plane that the unit
  /// normal points to (normal·(p - target) >= 0); push-only, <= cap.
  void addHalfSpace(BodyId b, const Vec3& anchorLocal, const Vec3& normalWorld,
                    const Vec3& targetWorld, float cap) {
    add(b, anchorLocal, normalWorld, targetWorld, 0.0f, cap);
  }

 private:
  /// Inline: the tracker adds a thousand rows per physics step.
  void add(BodyId b, const Vec3& anchorLocal, const Vec3& normalWorld, const Vec3& targetWorld,
           float low, float high) {
    assert(high >= 0.0f && anchorLocal.allFinite() && targetWorld.allFinite());
    assert(std::abs(normalWorld.squaredNorm() - 1.0f) < 1e-3f && "row normal must be unit");
    body.push_back(b);
    anchor.push_back(anchorLocal);
    normal.push_back(normalWorld);
    target.push_back(targetWorld);
    lower.push_back(low);
    upper.push_back(high);
    impulse.push_back(0.0f);
  }
};

/// Every mutable quantity of a world: poses, velocities, weld groups, warm-start impulses and
/// the contact cache. Copying is cheap; reusing one instance never reallocates.
struct WorldState {
  std::vector<Vec3> position;         ///< centre of mass per body, world, m
  std::vector<Quat> orientation;      ///< per body
  std::vector<Vec3> linearVelocity;   ///< per body, m/s
  std::vector<Vec3> angularVelocity;  ///< per body, rad/s
  std::vector<int> group;             ///< weld group per body, -1 when free
  /// A weld group: bodies frozen together and moving as one rigid body.
  struct Group {
    Vec3 position = Vec3::Zero();         ///< group centre of mass, world, m
    Vec3 linearVelocity = Vec3::Zero();   ///< m/s
    Vec3 angularVelocity = Vec3::Zero();  ///< rad/s
    Quat orientation = Quat::Identity();  ///< group axes (those of its first member at weld time)
    float mass = 0.0f;                    ///< kg
    Mat3 inertiaLocal = Mat3::Zero();     ///< about the group centre, group axes, kg m^2
    bool alive = false;                   ///< false once unwelded (slot free for reuse)
  };
  std::vector<Group> groups;         ///< weld groups, indexed by GroupId
  std::vector<Vec3> memberOffset;    ///< per body: COM in its group frame, m
  std::vector<Quat> memberRotation;  ///< per body: orientation in its group frame
  std::vector<float> jointImpulse;   ///< per joint: 3 point + 6 limit rows, N s
  /// One contact point kept from the last step to warm-start the next.
  struct CachedContact {
    std::uint32_t pair;   ///< bodyA * bodyCount + bodyB
    Vec3 localA;          ///< contact point in A's COM frame, m
    float normalImpulse,  ///< accumulated normal impulse, N s
        tangentImpulse1,  ///< accumulated impulse along the first friction direction, N s
        tangentImpulse2;  ///< same along the second friction direction, N s
  };
  std::vector<CachedContact> contacts;  ///< sorted by pair
  std::uint64_t stepCount = 0;  ///< steps taken (part of the state: restoreState rewinds it)
};

/// Read-only view of one of the last step's contacts.
struct ContactPoint {
  BodyId a,          ///< first body of the pair (the lower id)
      b;             ///< second body of the pair
  Vec3 position;     ///< world, on A's surface, m
  Vec3 normal;       ///< world, from A to B
  float separation;  ///< m, negative when penetrating
  float impulse;     ///< normal impulse, N s
};

/// A rigid-body world: shapes, bodies, joints, cones, drives, weld groups and the solver.
class World {
 public:
  explicit World(const WorldSettings& settings = {});  ///< An empty world.
  World(const World& other);                           ///< Deep copy.
  World& operator=(const World& other);                ///< Deep copy.
  World(World&&) noexcept;                             ///< Moves the world.
  World& operator=(World&&) noexcept;                  ///< Moves the world.
  ~World();                                            ///< Frees the world.

  WorldSettings& settings() { return settings_; }  ///< Settings, changeable between steps.
  const WorldSettings& settings() const { return settings_; }  ///< Settings.

  /// Shapes are stored once and shared by any number of bodies.
  int addShape(ConvexShape shape);
  const ConvexShape& shape(int index) const;  ///< shape by index from addShape

  BodyId addBody(const BodyDef& def);            ///< Adds a body; returns its id.
  int bodyCount() const;                         ///< number of bodies
  float mass(BodyId b) const;                    ///< kg (0 for static/kinematic)
  const ConvexShape& bodyShape(BodyId b) const;  ///< the body's shape
  Pose pose(BodyId b) const;                     ///< world pose of the body frame
  Vec3 centerOfMass(BodyId b) const;             ///< world, m
  Vec3 linearVelocity(BodyId b) const;           ///< of the centre of mass, world, m/s
  Vec3 angularVelocity(BodyId b) const;          ///< world axes, rad/s
  /// Velocity of the body's material point at worldPoint (world, m), m/s.
  Vec3 pointVelocity(BodyId b, const Vec3& worldPoint) const;
  /// Setting the pose or velocity of a welded body moves/sets its whole group.
  void setPose(BodyId b, const Pose& pose);
  /// Sets the centre-of-mass velocity (m/s) and angular velocity (rad/s); ignored for static
  /// bodies. A welded body sets its whole group's rigid motion.
  void setVelocity(BodyId b, const Vec3& linear, const Vec3& angular);
  /// Sets a dynamic, unwelded body's mass (kg, > 0) and rescales its inertia.
  void setMass(BodyId b, float mass);
  /// Sets linear and angular damping rates, 1/s (see BodyDef).
  void setDamping(BodyId b, float linear, float angular);
  /// Collision filter (symmetric). Pairs with a static/kinematic pair never collide.
  void setCollisionEnabled(BodyId a, BodyId b, bool enabled);
  bool collisionEnabled(BodyId a, BodyId b) const;  ///< whether the pair may collide

  /// Adds a joint; with filterJointedPairs its two bodies stop colliding.
  JointId addJoint(const JointDef& def);
  int jointCount() const;                  ///< number of joints
  const JointDef& joint(JointId j) const;  ///< definition, with the current limits
  /// Enables or disables the joint's angular limits and sets them, rad; lower <= upper.
  void setJointLimits(JointId j, bool enabled, const Vec3& lower, const Vec3& upper);
  /// Current (flexion, abduction, twist) of the joint, rad.
  Vec3 jointAngles(JointId j) const;
  /// World distance between the two anchor points of a joint, m.
  float jointSeparation(JointId j) const;
  /// Motor towards a relative joint rotation (parent frame to child frame) with |torque| <=
  /// maxTorque (N m): closes the angle error over max(timeConstant, dt) seconds.
  void setJointDrive(JointId j, const Quat& targetRelative, float maxTorque,
                     float timeConstant = 0);
  /// Makes the joint's drive a torsional spring-damper: torque = stiffness x angle error
  /// (N m/rad) with the given damping ratio, still capped at maxTorque (solved as a soft row,
  /// Box2D v3's soft step, so it is stable for any stiffness). Two drives pressing on one
  /// object from both sides then reach a force balance instead of fighting at their caps.
  /// stiffness 0 restores the velocity servo of setJointDrive.
  void setJointDriveSpring(JointId j, float stiffness, float dampingRatio = 1.0f);
  void clearJointDrive(JointId j);  ///< Turns the joint's drive off.

  /// Drives a body's frame towards a world pose with |force| <= maxForce (N) and |torque| <=
  /// maxTorque (N m), closing the error over max(timeConstant, dt) seconds.
  void setBodyDrive(BodyId b, const Pose& target, float maxForce, float maxTorque,
                    float timeConstant = 0);
  void clearBodyDrive(BodyId b);  ///< Turns the body's drive off.

  /// Keeps axisA (body frame of a) within maxAngle (rad) of axisB (body frame of b).
  ConeId addAngularCone(BodyId a, const Vec3& axisA, BodyId b, const Vec3& axisB, float maxAngle);
  void setConeEnabled(ConeId c, bool enabled);  ///< Turns a cone on or off.

  /// Freezes bodies into one rigid group (momentum preserved); a body already welded is first
  /// released from its group. Rows on members act on the group. Returns the group id.
  GroupId weld(std::span<const BodyId> bodies);
  /// Releases every member with the group's rigid velocity field.
  void unweld(GroupId g);
  void unweldAll();                 ///< Releases every group.
  GroupId groupOf(BodyId b) const;  ///< -1 when free

  /// Transient one-body rows for the next step (see SurfaceRows).
  SurfaceRows& rows() { return rows_; }
  /// Reserves row storage so filling up to maxRows never allocates.
  void reserveRows(int maxRows);
  /// A boundary plane (unit normal, n·x >= offset is the allowed side) for body b: adds a
  /// push-only row (impulse <= cap) on every hull vertex within margin (m) of the plane at the
  /// current pose and within band (m) of the body's deepest vertex; nothing when the bounding
  /// sphere is farther than margin. A vertex more than band behind the deepest one only
  /// reaches the plane after the body turns by about band / its width, which one step does
  /// not do: its row would cost a solver row every sweep and never act.
  void addBoundary(BodyId b, const Vec3& normal, float offset, float cap, float margin = 0.01f,
                   float band = std::numeric_limits<float>::infinity());

  /// Advances the world by dt seconds (> 0): one full solver step (see the file comment).
  void step(float dt);
  /// Most worlds whose sweeps stepSideBySide runs at once.
  static constexpr std::size_t kMaxSideBySide = 4;
  /// w->step(dt) for each of several different worlds with the same iteration counts, with
  /// the same bits, in less time: their Gauss-Seidel sweeps run side by side, up to
  /// kMaxSideBySide at once (more are stepped in groups; the surface sweeps two by two on a
  /// CPU with AVX but not AVX-512VL), where the CPU has AVX and useVectorSweeps is on
  /// (otherwise simply one step after the other).
  static void stepSideBySide(std::span<World* const> worlds, float dt);
  /// stepSideBySide of two worlds.
  static void stepTogether(World& a, World& b, float dt);

  void saveState(WorldState& out) const { out = state_; }  ///< Copies the state into out.
  /// Replaces the state with one saved from this world (same bodies and joints).
  void restoreState(const WorldState& in);
  const WorldState& state() const { return state_; }  ///< the current state

  std::span<const ContactPoint> contacts() const;  ///< contacts found by the last step
  /// Kinetic energy (sum over free bodies and groups), J.
  float kineticEnergy() const;
  /// FNV-1a over every body's pose and velocity bits (determinism checks).
  std::uint64_t stateHash() const;

  struct Impl;  ///< body/row arrays and scratch (src/physics/world_impl.h)

 private:
  /// step() in parts (solver.cpp), so that stepSideBySide can interleave worlds' sweeps:
  /// slots, rows and warm start; positions integrated (then the joints projected); impulses
  /// stored and the state written back. Between them, the sweeps.
  void beginStep(float h);
  void integrate(float h);
  void endStep();
  void buildContacts(float dt);  ///< narrow phase + contact rows (contact.cpp)
  void storeContactImpulses();   ///< contact cache for the next step's warm start

  WorldSettings settings_;
  WorldState state_;
  SurfaceRows rows_;
  std::vector<ConvexShape> shapes_;
  std::unique_ptr<Impl> impl_;  ///< copied deeply
};

}  // namespace dynahand::physics
