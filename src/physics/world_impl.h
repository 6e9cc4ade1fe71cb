// Internal arrays of a physics World: cold per-body configuration, persistent constraint
// configuration, and the per-step solver scratch (solver bodies and rows). Hot loops touch
// only SolverBody and the row arrays, all contiguous.
#pragma once

#include <cstdint>
#include <vector>

#include "dynahand/physics_world.h"
#include "physics/surface_batches.h"

namespace dynahand::physics {

// The velocity state the Gauss-Seidel sweeps read and write: one per solver slot (a free
// body, a weld group, or the static dummy). Static/kinematic slots have zero inverse mass.
struct SolverBody {
  Vec3 v;         // linear velocity of the centre of mass, m/s
  float invMass;  // 1/kg
  Vec3 w;         // angular velocity, rad/s
  float pad0;
  // Symmetric world inverse inertia (xx, yy, zz, xy, xz, yz), 1/(kg m^2).
  float ixx, iyy, izz, ixy, ixz, iyz;
  float pad1, pad2;
};
static_assert(sizeof(SolverBody) == 64,
              "SolverBody is the hot solver state: keep it one cache line");

inline Vec3 applyInvInertia(const SolverBody& b, const Vec3& x) {
  return {b.ixx * x.x() + b.ixy * x.y() + b.ixz * x.z(),
          b.ixy * x.x() + b.iyy * x.y() + b.iyz * x.z(),
          b.ixz * x.x() + b.iyz * x.y() + b.izz * x.z()};
}

// One scalar row between two solver slots: Jv = axis·(vB - vA) + angA·wA + angB·wB.
// The accumulated impulse stays in [lower, upper]; friction rows take their bounds from
// their normal row (± friction x normal impulse).
struct Row {
  Vec3 axis, angA, angB;    // Jacobian parts (axis is zero for angular rows)
  Vec3 invIAngA, invIAngB;  // inverse inertia times the angular parts
  int slotA, slotB;
  float invMassA, invMassB;
  float effMass;    // 1 / (J M^-1 J^T), kg (or kg m^2)
  float bias;       // velocity bias with position correction, m/s or rad/s
  float relaxBias;  // velocity bias in the relax sweeps (speculative part only)
  float massScale;  // soft rows (contacts): 1 / 0 for rigid rows
  float impulseScale;
  float lower, upper;  // impulse bounds, N s
  float impulse;       // accumulated impulse, N s
  int frictionOf;      // index of the normal row, or -1
  float friction;      // Coulomb coefficient when frictionOf >= 0
  bool relax;          // solved in the relax sweeps (motors are not)
  bool angular;        // axis is zero: only the angular velocities take part (limits, cones)
  int blockSize;       // rows [this, this + blockSize) are iterated blockPasses times
  int blockPasses;
  float* store;  // where the impulse is kept for warm starting, or nullptr
};

struct BodyConfig {
  int shape = -1;
  BodyType type = BodyType::Dynamic;
  float mass = 1.0f;                 // kg
  Mat3 inertiaLocal = Mat3::Zero();  // about the centre of mass, body axes, kg m^2
  Vec3 centroid = Vec3::Zero();      // centre of mass in the body frame, m
  float boundingRadius = 0.0f;       // about the centre of mass, m
  float linearDamping = 0.0f;        // 1/s
  float angularDamping = 0.0f;       // 1/s
  // Body drive.
  bool driveEnabled = false;
  Pose driveTarget;                // world pose of the body frame
  float driveMaxForce = 0.0f;      // N
  float driveMaxTorque = 0.0f;     // N m
  float driveTimeConstant = 0.0f;  // s
};

struct JointConfig {
  JointDef def;
  Vec3 comAnchorParent = Vec3::Zero();  // anchor relative to the parent's centre of mass, body axes
  Vec3 comAnchorChild = Vec3::Zero();
  bool driveEnabled = false;
  Quat driveTarget = Quat::Identity();  // relative joint rotation
  float driveMaxTorque = 0.0f;          // N m
  float driveTimeConstant = 0.0f;       // s
  float driveStiffness = 0.0f;          // N m/rad; 0: velocity servo (time constant)
  float driveDampingRatio = 1.0f;       // of the spring when driveStiffness > 0
};

struct ConeConfig {
  BodyId a = -1, b = -1;
  Vec3 axisA = Vec3::UnitX(), axisB = Vec3::UnitX();  // unit, body frames
  float maxAngle = 0.0f;                              // rad
  bool enabled = true;
};

// Contact point produced by the narrow phase, before it becomes rows.
struct ManifoldPoint {
  Vec3 position;     // world, m (on B's surface)
  float separation;  // m, negative when penetrating
};

// Narrow phase between two convex bodies (body-frame poses). Writes up to 4 points and the
// unit normal from A to B; returns the point count (0: farther apart than margin).
// faceAxes: also test the face normals of a hull with few faces (<= 12) as separating axes and
// take the one of least penetration when it beats MPR's direction (used against static
// bodies: walls and tables, where MPR's centre-line direction can pick the wrong face).
int collideConvex(const ConvexShape& a, const Pose& poseA, const ConvexShape& b, const Pose& poseB,
                  float margin, ManifoldPoint* points, Vec3* normal, bool faceAxes = false,
                  Vec3* cachedAxis = nullptr);

constexpr int kJointImpulses = 9;  // 3 point rows + (lower, upper) x 3 angles

struct World::Impl {
  std::vector<BodyConfig> bodies;
  std::vector<JointConfig> joints;
  std::vector<ConeConfig> cones;
  std::vector<std::uint8_t> collide;  // bodyCount x bodyCount, 1 when the pair may collide
  // Per pair (bodyCount x bodyCount): the axis that last showed it apart, in the first body's
  // frame (zero when none). Only saves work: the cull it feeds is exact, so results do not
  // depend on it (and it is not part of WorldState).
  std::vector<Vec3> separatingAxis;

  // Per-step scratch, sized at warm-up and reused.
  std::vector<SolverBody> solverBodies;  // slots: bodies, then groups, then the static dummy
  std::vector<Vec3> slotPosition;        // centre of mass per slot, m
  std::vector<Quat> slotOrientation;
  std::vector<Row> rows;
  struct JointPosition {
    int slotA, slotB;
    Vec3 armA, armB;  // anchor relative to the slot's centre of mass, slot axes, m
  };
  std::vector<JointPosition> jointPositions;
  // Ball-joint anchors solved as one 3x3 block per joint: Cdot = vB + wB x rB - vA - wA x rA,
  // impulse increment = -K^-1 (Cdot + bias), K = (mA^-1 + mB^-1) 1 - [rA] IA^-1 [rA] - [rB] IB^-1
  // [rB].
  struct PointBlock {
    int slotA, slotB;
    Vec3 rA, rB;   // arms from the slots' centres of mass, world, m
    Mat3 invK;     // kg
    Vec3 bias;     // m/s
    Vec3 impulse;  // accumulated, N s
    float* store;  // 3 floats of WorldState::jointImpulse
  };
  std::vector<PointBlock> pointBlocks;
  std::vector<ContactPoint> contactView;
  std::vector<WorldState::CachedContact> newContacts;
  // Prepared surface rows (parallel to SurfaceRows), packed for the solver.
  std::vector<PreparedSurfaceRow> surfaceRows;
  std::vector<int> surfaceRowsByBody, surfaceBodyStart;  // prepareSurfaceRows' scratch
  std::vector<float> boundaryHeights;                    // addBoundary's scratch
  SurfaceBatches surfaceBatches;

  int slotOf(const WorldState& s, BodyId b) const {
    const int g = s.group[static_cast<std::size_t>(b)];
    return g < 0 ? b : static_cast<int>(bodies.size()) + g;
  }
  int dummySlot(const WorldState& s) const {
    return static_cast<int>(bodies.size() + s.groups.size());
  }
};

// A body point given relative to the centre of mass (body axes): its world position, and its
// arm from the centre of the solver slot moving it (the body's, or its weld group's).
inline Vec3 armOf(const World::Impl& m, const WorldState& s, std::size_t body, const Vec3& comLocal,
                  Vec3* world) {
  *world = s.position[body] + rotateVector(s.orientation[body], comLocal);
  return *world - m.slotPosition[static_cast<std::size_t>(m.slotOf(s, static_cast<BodyId>(body)))];
}

// The step's surface rows into m.surfaceRows (surface_prepare.cpp): arms, inverse-inertia
// products, effective masses and biases, at the slots' current velocities and inertia.
void prepareSurfaceRows(World::Impl& m, const WorldState& s, const SurfaceRows& rows, float erp,
                        float invH);

}  // namespace dynahand::physics
