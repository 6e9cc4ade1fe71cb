// World: bodies, joints, cones, drives, weld groups and state snapshots. The step itself is in
// solver.cpp, the narrow phase in contact.cpp.
#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>

#include "physics/world_impl.h"

namespace dynahand::physics {

World::World(const WorldSettings& settings)
    : settings_(settings), impl_(std::make_unique<Impl>()) {}
World::World(const World& other)
    : settings_(other.settings_),
      state_(other.state_),
      rows_(other.rows_),
      shapes_(other.shapes_),
      impl_(std::make_unique<Impl>(*other.impl_)) {}
World& World::operator=(const World& other) {
  if (this != &other) {
    settings_ = other.settings_;
    state_ = other.state_;
    rows_ = other.rows_;
    shapes_ = other.shapes_;
    *impl_ = *other.impl_;
  }
  return *this;
}
World::World(World&&) noexcept = default;
World& World::operator=(World&&) noexcept = default;
World::~World() = default;

int World::addShape(ConvexShape shape) {
  shapes_.push_back(std::move(shape));
  return static_cast<int>(shapes_.size()) - 1;
}

const ConvexShape& World::shape(int index) const {
  assert(index >= 0 && index < static_cast<int>(shapes_.size()) && "bad shape index");
  return shapes_[static_cast<std::size_t>(index)];
}

BodyId World::addBody(const BodyDef& def) {
  assert(def.shape >= 0 && def.shape < static_cast<int>(shapes_.size()) && "addBody: bad shape");
  assert((def.type != BodyType::Dynamic || def.mass > 0.0f) && "addBody: dynamic mass must be > 0");
  const ConvexShape& s = shapes_[static_cast<std::size_t>(def.shape)];
  BodyConfig c;
  c.shape = def.shape;
  c.type = def.type;
  c.mass = def.type == BodyType::Dynamic ? def.mass : 0.0f;
  c.inertiaLocal = s.inertiaAboutCentroid(c.mass);
  c.centroid = s.centroid();
  c.boundingRadius = s.boundingRadius();
  c.linearDamping = def.linearDamping;
  c.angularDamping = def.angularDamping;
  const std::size_t oldCount = impl_->bodies.size();
  impl_->bodies.push_back(c);

  const Quat q = def.pose.q.normalized();
  state_.position.push_back(def.pose.p + q * c.centroid);
  state_.orientation.push_back(q);
  const bool moves = def.type != BodyType::Static;
  state_.linearVelocity.push_back(moves ? def.linearVelocity : Vec3::Zero());
  state_.angularVelocity.push_back(moves ? def.angularVelocity : Vec3::Zero());
  state_.group.push_back(-1);
  state_.memberOffset.push_back(Vec3::Zero());
  state_.memberRotation.push_back(Quat::Identity());

  // Grow the symmetric collision matrix; new pairs collide unless both cannot move.
  const std::size_t n = oldCount + 1;
  std::vector<std::uint8_t> grown(n * n, 0);
  for (std::size_t i = 0; i < oldCount; ++i) {
    for (std::size_t j = 0; j < oldCount; ++j) grown[i * n + j] = impl_->collide[i * oldCount + j];
  }
  for (std::size_t i = 0; i < oldCount; ++i) {
    const bool either = impl_->bodies[i].type == BodyType::Dynamic || def.type == BodyType::Dynamic;
    grown[i * n + oldCount] = grown[oldCount * n + i] = either ? 1 : 0;
  }
  impl_->collide = std::move(grown);
  impl_->separatingAxis.assign(n * n, Vec3::Zero());
  return static_cast<BodyId>(oldCount);
}

int World::bodyCount() const {
  return static_cast<int>(impl_->bodies.size());
}
float World::mass(BodyId b) const {
  return impl_->bodies[static_cast<std::size_t>(b)].mass;
}
const ConvexShape& World::bodyShape(BodyId b) const {
  return shapes_[static_cast<std::size_t>(impl_->bodies[static_cast<std::size_t>(b)].shape)];
}

Pose World::pose(BodyId b) const {
  const auto i = static_cast<std::size_t>(b);
  const Quat& q = state_.orientation[i];
  return {state_.position[i] - rotateVector(q, impl_->bodies[i].centroid), q};
}
Vec3 World::centerOfMass(BodyId b) const {
  return state_.position[static_cast<std::size_t>(b)];
}
Vec3 World::linearVelocity(BodyId b) const {
  return state_.linearVelocity[static_cast<std::size_t>(b)];
}
Vec3 World::angularVelocity(BodyId b) const {
  return state_.angularVelocity[static_cast<std::size_t>(b)];
}
Vec3 World::pointVelocity(BodyId b, const Vec3& worldPoint) const {
  const auto i = static_cast<std::size_t>(b);
  return state_.linearVelocity[i] +
         state_.angularVelocity[i].cross(worldPoint - state_.position[i]);
}

void World::setPose(BodyId b, const Pose& p) {
  const auto i = static_cast<std::size_t>(b);
  const Quat q = p.q.normalized();
  const Vec3 com = p.p + q * impl_->bodies[i].centroid;
  const int g = state_.group[i];
  if (g < 0) {
    state_.position[i] = com;
    state_.orientation[i] = q;
    return;
  }
  // Move the whole group so that this member lands on the requested pose.
  WorldState::Group& grp = state_.groups[static_cast<std::size_t>(g)];
  grp.orientation = (q * state_.memberRotation[i].conjugate()).normalized();
  grp.position = com - grp.orientation * state_.memberOffset[i];
  for (std::size_t m = 0; m < state_.group.size(); ++m) {
    if (state_.group[m] != g) continue;
    state_.position[m] = grp.position + grp.orientation * state_.memberOffset[m];
    state_.orientation[m] = (grp.orientation * state_.memberRotation[m]).normalized();
  }
}

void World::setVelocity(BodyId b, const Vec3& linear, const Vec3& angular) {
  const auto i = static_cast<std::size_t>(b);
  if (impl_->bodies[i].type == BodyType::Static) return;
  const int g = state_.group[i];
  if (g < 0) {
    state_.linearVelocity[i] = linear;
    state_.angularVelocity[i] = angular;
    return;
  }
  WorldState::Group& grp = state_.groups[static_cast<std::size_t>(g)];
  grp.angularVelocity = angular;
  grp.linearVelocity = linear - angular.cross(state_.position[i] - grp.position);
  for (std::size_t m = 0; m < state_.group.size(); ++m) {
    if (state_.group[m] != g) continue;
    state_.linearVelocity[m] =
        grp.linearVelocity + angular.cross(state_.position[m] - grp.position);
    state_.angularVelocity[m] = angular;
  }
}

void World::setMass(BodyId b, float m) {
  BodyConfig& c = impl_->bodies[static_cast<std::size_t>(b)];
  assert(c.type == BodyType::Dynamic && m > 0.0f && "setMass: dynamic bodies, mass > 0");
  assert(state_.group[static_cast<std::size_t>(b)] < 0 && "setMass: unweld first");
  c.mass = m;
  c.inertiaLocal = shapes_[static_cast<std::size_t>(c.shape)].inertiaAboutCentroid(m);
}

void World::setDamping(BodyId b, float linear, float angular) {
  BodyConfig& c = impl_->bodies[static_cast<std::size_t>(b)];
  c.linearDamping = linear;
  c.angularDamping = angular;
}

void World::setCollisionEnabled(BodyId a, BodyId b, bool enabled) {
  const auto n = impl_->bodies.size();
  const auto ia = static_cast<std::size_t>(a), ib = static_cast<std::size_t>(b);
  assert(ia < n && ib < n);
  impl_->collide[ia * n + ib] = impl_->collide[ib * n + ia] = enabled ? 1 : 0;
}

bool World::collisionEnabled(BodyId a, BodyId b) const {
  const auto n = impl_->bodies.size();
  return impl_->collide[static_cast<std::size_t>(a) * n + static_cast<std::size_t>(b)] != 0;
}

JointId World::addJoint(const JointDef& def) {
  [[maybe_unused]] const int n = bodyCount();
  assert(def.parent >= 0 && def.parent < n && def.child >= 0 && def.child < n &&
         def.parent != def.child && "addJoint: bad bodies");
  assert((def.lower.array() <= def.upper.array()).all() && "addJoint: lower > upper");
  JointConfig c;
  c.def = def;
  c.def.frameParent.normalize();
  c.def.frameChild.normalize();
  c.comAnchorParent =
      def.anchorParent - impl_->bodies[static_cast<std::size_t>(def.parent)].centroid;
  c.comAnchorChild = def.anchorChild - impl_->bodies[static_cast<std::size_t>(def.child)].centroid;
  impl_->joints.push_back(c);
  state_.jointImpulse.resize(state_.jointImpulse.size() + kJointImpulses, 0.0f);
  if (settings_.filterJointedPairs) setCollisionEnabled(def.parent, def.child, false);
  return static_cast<JointId>(impl_->joints.size()) - 1;
}

int World::jointCount() const {
  return static_cast<int>(impl_->joints.size());
}
const JointDef& World::joint(JointId j) const {
  return impl_->joints[static_cast<std::size_t>(j)].def;
}

void World::setJointLimits(JointId j, bool enabled, const Vec3& lower, const Vec3& upper) {
  assert((lower.array() <= upper.array()).all() && "setJointLimits: lower > upper");
  JointDef& d = impl_->joints[static_cast<std::size_t>(j)].def;
  d.limitsEnabled = enabled;
  d.lower = lower;
  d.upper = upper;
}

Vec3 World::jointAngles(JointId j) const {
  const JointDef& d = impl_->joints[static_cast<std::size_t>(j)].def;
  const Quat fa = state_.orientation[static_cast<std::size_t>(d.parent)] * d.frameParent;
  const Quat fb = state_.orientation[static_cast<std::size_t>(d.child)] * d.frameChild;
  return decomposeJointRotation(fa.conjugate() * fb);
}

float World::jointSeparation(JointId j) const {
  const JointDef& d = impl_->joints[static_cast<std::size_t>(j)].def;
  return (pose(d.parent).transform(d.anchorParent) - pose(d.child).transform(d.anchorChild)).norm();
}

void World::setJointDrive(JointId j, const Quat& targetRelative, float maxTorque,
                          float timeConstant) {
  assert(maxTorque >= 0.0f && timeConstant >= 0.0f);
  JointConfig& c = impl_->joints[static_cast<std::size_t>(j)];
  c.driveEnabled = true;
  c.driveTarget = targetRelative.normalized();
  c.driveMaxTorque = maxTorque;
  c.driveTimeConstant = timeConstant;
}

void World::clearBodyDrive(BodyId b) {
  impl_->bodies[static_cast<std::size_t>(b)].driveEnabled = false;
}

void World::setJointDriveSpring(JointId j, float stiffness, float dampingRatio) {
  assert(stiffness >= 0.0f && dampingRatio >= 0.0f);
  JointConfig& c = impl_->joints[static_cast<std::size_t>(j)];
  c.driveStiffness = stiffness;
  c.driveDampingRatio = dampingRatio;
}

void World::clearJointDrive(JointId j) {
  impl_->joints[static_cast<std::size_t>(j)].driveEnabled = false;
}

void World::setBodyDrive(BodyId b, const Pose& target, float maxForce, float maxTorque,
                         float timeConstant) {
  assert(maxForce >= 0.0f && maxTorque >= 0.0f && timeConstant >= 0.0f);
  BodyConfig& c = impl_->bodies[static_cast<std::size_t>(b)];
  c.driveEnabled = true;
  c.driveTarget = {target.p, target.q.normalized()};
  c.driveMaxForce = maxForce;
  c.driveMaxTorque = maxTorque;
  c.driveTimeConstant = timeConstant;
}

ConeId World::addAngularCone(BodyId a, const Vec3& axisA, BodyId b, const Vec3& axisB,
                             float maxAngle) {
  assert(a != b && axisA.norm() > 0.0f && axisB.norm() > 0.0f && maxAngle >= 0.0f);
  impl_->cones.push_back({a, b, axisA.normalized(), axisB.normalized(), maxAngle, true});
  return static_cast<ConeId>(impl_->cones.size()) - 1;
}

void World::setConeEnabled(ConeId c, bool enabled) {
  impl_->cones[static_cast<std::size_t>(c)].enabled = enabled;
}

GroupId World::weld(std::span<const BodyId> members) {
  for (BodyId b : members) {
    const int g = state_.group[static_cast<std::size_t>(b)];
    if (g >= 0) unweld(g);
  }
  // Reuse a dead group slot so repeated weld/unweld does not grow the state.
  std::size_t gi = 0;
  while (gi < state_.groups.size() && state_.groups[gi].alive) ++gi;
  if (gi == state_.groups.size()) state_.groups.push_back({});
  WorldState::Group g{};
  g.alive = true;
  float mass = 0.0f;
  Vec3 com = Vec3::Zero(), momentum = Vec3::Zero();
  for (BodyId b : members) {
    const auto i = static_cast<std::size_t>(b);
    assert(impl_->bodies[i].type == BodyType::Dynamic && "weld: only dynamic bodies");
    mass += impl_->bodies[i].mass;
    com += impl_->bodies[i].mass * state_.position[i];
    momentum += impl_->bodies[i].mass * state_.linearVelocity[i];
  }
  assert(mass > 0.0f && "weld: no bodies");
  com /= mass;
  // Group axes: those of the first member. Inertia and angular momentum about the group centre.
  g.orientation = state_.orientation[static_cast<std::size_t>(members[0])];
  const Mat3 rg = g.orientation.toRotationMatrix();
  Mat3 inertiaWorld = Mat3::Zero();
  Vec3 angularMomentum = Vec3::Zero();
  for (BodyId b : members) {
    const auto i = static_cast<std::size_t>(b);
    const BodyConfig& c = impl_->bodies[i];
    const Mat3 r = state_.orientation[i].toRotationMatrix();
    const Mat3 ii = r * c.inertiaLocal * r.transpose();
    const Vec3 d = state_.position[i] - com;
    inertiaWorld += ii + c.mass * (d.squaredNorm() * Mat3::Identity() - d * d.transpose());
    angularMomentum += ii * state_.angularVelocity[i] + c.mass * d.cross(state_.linearVelocity[i]);
  }
  g.mass = mass;
  g.position = com;
  g.linearVelocity = momentum / mass;
  g.angularVelocity = inertiaWorld.inverse() * angularMomentum;
  g.inertiaLocal = rg.transpose() * inertiaWorld * rg;
  state_.groups[gi] = g;
  const int id = static_cast<int>(gi);
  for (BodyId b : members) {
    const auto i = static_cast<std::size_t>(b);
    state_.group[i] = id;
    state_.memberOffset[i] = g.orientation.conjugate() * (state_.position[i] - com);
    state_.memberRotation[i] = (g.orientation.conjugate() * state_.orientation[i]).normalized();
    state_.linearVelocity[i] = g.linearVelocity + g.angularVelocity.cross(state_.position[i] - com);
    state_.angularVelocity[i] = g.angularVelocity;
  }
  return id;
}

void World::unweld(GroupId gid) {
  assert(gid >= 0 && gid < static_cast<int>(state_.groups.size()));
  WorldState::Group& g = state_.groups[static_cast<std::size_t>(gid)];
  if (!g.alive) return;
  for (std::size_t i = 0; i < state_.group.size(); ++i) {
    if (state_.group[i] != gid) continue;
    state_.group[i] = -1;
    state_.linearVelocity[i] =
        g.linearVelocity + g.angularVelocity.cross(state_.position[i] - g.position);
    state_.angularVelocity[i] = g.angularVelocity;
  }
  g.alive = false;
}

void World::unweldAll() {
  for (std::size_t g = 0; g < state_.groups.size(); ++g) unweld(static_cast<GroupId>(g));
}

GroupId World::groupOf(BodyId b) const {
  return state_.group[static_cast<std::size_t>(b)];
}

void World::reserveRows(int maxRows) {
  rows_.reserve(maxRows);
  const auto n = static_cast<std::size_t>(maxRows);
  impl_->surfaceRows.reserve(n);
  impl_->surfaceBatches.reserve(maxRows);
}

void World::addBoundary(BodyId b, const Vec3& normal, float offset, float cap, float margin,
                        float band) {
  assert(std::abs(normal.squaredNorm() - 1.0f) < 1e-3f && std::isfinite(offset) && cap >= 0.0f);
  const auto i = static_cast<std::size_t>(b);
  const BodyConfig& c = impl_->bodies[i];
  const float centreDist = normal.dot(state_.position[i]) - offset;
  if (centreDist - c.boundingRadius > margin) return;  // sphere entirely on the allowed side
  // Every hull vertex within margin of the plane gets a push-only row: a rotating body brings
  // other corners to the plane within the step, not just the current extreme one.
  // A first cut in the body frame (the normal turned once, not every vertex moved); the
  // vertices near the margin are then measured as before, so the rows do not change.
  const Pose p = pose(b);
  const Vec3 localNormal = inverseRotateVector(p.q, normal);
  const float originDist = normal.dot(p.p) - offset;
  constexpr float kRoundingSlack = 1e-4f;  // m, far above float rounding at hand scale
  const ConvexShape& shape = shapes_[static_cast<std::size_t>(c.shape)];
  const auto& vertices = shape.vertices();
  std::vector<float>& heights = impl_->boundaryHeights;  // localNormal·v per vertex
  heights.resize(vertices.size());
  shape.vertexHeights(localNormal, heights.data());
  float reach = margin;  // rows for vertices at most this far from the plane
  if (band < margin) {
    float deepest = std::numeric_limits<float>::infinity();
    for (const float h : heights) deepest = std::min(deepest, h);
    reach = std::min(margin, deepest + originDist + band);
  }
  for (std::size_t k = 0; k < vertices.size(); ++k) {
    if (heights[k] + originDist > reach + kRoundingSlack) continue;
    const Vec3& v = vertices[k];
    const Vec3 world = p.transform(v);
    const float dist = normal.dot(world) - offset;
    if (dist > reach) continue;
    rows_.body.push_back(b);
    rows_.anchor.push_back(v);
    rows_.normal.push_back(normal);
    rows_.target.push_back(world - dist * normal);
    rows_.lower.push_back(0.0f);
    rows_.upper.push_back(cap);
    rows_.impulse.push_back(0.0f);
  }
}

void World::restoreState(const WorldState& in) {
  assert(in.position.size() == impl_->bodies.size() && "restoreState: state of another world");
  assert(in.jointImpulse.size() == impl_->joints.size() * kJointImpulses);
  state_ = in;
}

std::span<const ContactPoint> World::contacts() const {
  return impl_->contactView;
}

float World::kineticEnergy() const {
  double e = 0.0;
  for (std::size_t i = 0; i < impl_->bodies.size(); ++i) {
    const BodyConfig& c = impl_->bodies[i];
    if (c.type != BodyType::Dynamic || state_.group[i] >= 0) continue;
    const Mat3 r = state_.orientation[i].toRotationMatrix();
    const Vec3& w = state_.angularVelocity[i];
    e += 0.5 * static_cast<double>(c.mass * state_.linearVelocity[i].squaredNorm()) +
         0.5 * static_cast<double>(w.dot(r * c.inertiaLocal * r.transpose() * w));
  }
  for (const WorldState::Group& g : state_.groups) {
    if (!g.alive) continue;
    const Mat3 r = g.orientation.toRotationMatrix();
    e += 0.5 * static_cast<double>(g.mass * g.linearVelocity.squaredNorm()) +
         0.5 * static_cast<double>(
                   g.angularVelocity.dot(r * g.inertiaLocal * r.transpose() * g.angularVelocity));
  }
  return static_cast<float>(e);
}

std::uint64_t World::stateHash() const {
  Fnv1a h;
  for (std::size_t i = 0; i < impl_->bodies.size(); ++i) {
    h.add(state_.position[i]);
    h.add(state_.orientation[i]);
    h.add(state_.linearVelocity[i]);
    h.add(state_.angularVelocity[i]);
  }
  return h.value();
}

void SurfaceRows::clear() {
  body.clear();
  anchor.clear();
  normal.clear();
  target.clear();
  lower.clear();
  upper.clear();
  impulse.clear();
}

void SurfaceRows::reserve(int rows) {
  const auto n = static_cast<std::size_t>(rows);
  body.reserve(n);
  anchor.reserve(n);
  normal.reserve(n);
  target.reserve(n);
  lower.reserve(n);
  upper.reserve(n);
  impulse.reserve(n);
}

}  // namespace dynahand::physics
