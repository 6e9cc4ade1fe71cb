// World::step: the projected Gauss-Seidel pipeline (stage order as Box2D v3's solver.c:
// integrate velocities -> warm start -> solve with bias -> integrate positions -> relax).
//
// Every constraint is a scalar row  Jv = axis·(vB - vA) + angA·wA + angB·wB  with
//   impulse increment  d = -effMass (Jv + bias),  accumulated impulse clamped to [lower, upper],
//   effMass = 1 / ((invMassA + invMassB)|axis|^2 + angA·IA^-1 angA + angB·IB^-1 angB).
// Position error C enters as bias = erp C / dt (rows that must reach C = 0) or, for one-sided
// rows (C >= 0) that are not yet violated, as the speculative bias C / dt (the row only acts
// if the velocity would cross the boundary within this step). The relax sweeps drop the erp
// part so the correction velocity does not survive as momentum. World::stepSideBySide runs
// several worlds' sweeps side by side, each in its own order (the same bits as stepping them
// alone).
#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <limits>
#include <span>

#include "core/simd/simd.h"
#include "physics/kernel_paths.h"
#include "physics/rows.h"

namespace dynahand::physics {
namespace {

constexpr float kLimitMargin = 0.15f;  // rad: limit rows exist this close to a limit (plus motion)
constexpr float kMaxRotationPerStep = 0.25f * 3.14159265f;  // rad
constexpr float kMaxJointCorrection = 0.005f;               // m per projection pass

Mat3 skew(const Vec3& v) {
  Mat3 m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

void setInvInertia(SolverBody& b, const Mat3& inv) {
  b.ixx = inv(0, 0);
  b.iyy = inv(1, 1);
  b.izz = inv(2, 2);
  b.ixy = 0.5f * (inv(0, 1) + inv(1, 0));
  b.ixz = 0.5f * (inv(0, 2) + inv(2, 0));
  b.iyz = 0.5f * (inv(1, 2) + inv(2, 1));
}

// Implicit gyroscopic step in body axes (one Newton iteration, as in Catto, GDC 2015):
// stable, and it does not add kinetic energy to a spinning asymmetric body.
Vec3 gyroscopicStep(const Vec3& wWorld, const Quat& q, const Mat3& inertiaLocal, float h) {
  const Vec3 wb = inverseRotateVector(q, wWorld);
  const Vec3 iw = inertiaLocal * wb;
  const Vec3 f = h * wb.cross(iw);
  const Mat3 jac = inertiaLocal + h * (skew(wb) * inertiaLocal - skew(iw));
  Vec3 next = wb - jac.inverse() * f;
  // Gyroscopic torque does no work: restore the kinetic energy the implicit step bled.
  const float before = wb.dot(iw), after = next.dot(inertiaLocal * next);
  if (after > 0.0f) next *= std::sqrt(before / after);
  return rotateVector(q, next);
}

inline void applyRowImpulse(std::vector<SolverBody>& sb, const Row& r, float d) {
  SolverBody& a = sb[static_cast<std::size_t>(r.slotA)];
  SolverBody& b = sb[static_cast<std::size_t>(r.slotB)];
  a.v -= (r.invMassA * d) * r.axis;
  a.w += d * r.invIAngA;
  b.v += (r.invMassB * d) * r.axis;
  b.w += d * r.invIAngB;
}

inline void solveRow(std::vector<SolverBody>& sb, std::vector<Row>& rows, Row& r, bool useBias) {
  SolverBody& a = sb[static_cast<std::size_t>(r.slotA)];
  SolverBody& b = sb[static_cast<std::size_t>(r.slotB)];
  if (r.angular) {  // joint limits, cones, joint drives: half the work of a general row
    const float jv = r.angA.dot(a.w) + r.angB.dot(b.w);
    const float target =
        useBias ? r.impulse - r.effMass * r.massScale * (jv + r.bias) - r.impulseScale * r.impulse
                : r.impulse - r.effMass * (jv + r.relaxBias);
    const float clamped = std::clamp(target, r.lower, r.upper);
    const float d = clamped - r.impulse;
    r.impulse = clamped;
    a.w += d * r.invIAngA;
    b.w += d * r.invIAngB;
    return;
  }
  const float jv = r.axis.dot(b.v - a.v) + r.angA.dot(a.w) + r.angB.dot(b.w);
  float lower = r.lower, upper = r.upper;
  if (r.frictionOf >= 0) {
    upper = r.friction * rows[static_cast<std::size_t>(r.frictionOf)].impulse;
    lower = -upper;
  }
  const float target =
      useBias ? r.impulse - r.effMass * r.massScale * (jv + r.bias) - r.impulseScale * r.impulse
              : r.impulse - r.effMass * (jv + r.relaxBias);
  const float clamped = std::clamp(target, lower, upper);
  const float d = clamped - r.impulse;
  r.impulse = clamped;
  applyRowImpulse(sb, r, d);
}

// One sweep over the rows in build order; later rows get the last word (joints and limits
// after drives, so a drive can never push through a limit). A block (one contact manifold)
// is iterated blockPasses times in place.
// The block of rows starting at row i, all its passes; returns the index after it.
inline std::size_t solveRowBlock(std::vector<SolverBody>& sb, std::vector<Row>& rows, std::size_t i,
                                 bool useBias) {
  const auto size = static_cast<std::size_t>(rows[i].blockSize);
  const int passes = rows[i].blockPasses;
  for (int pass = 0; pass < passes; ++pass) {
    for (std::size_t k = i; k < i + size; ++k) {
      Row& r = rows[k];
      if (useBias || r.relax) solveRow(sb, rows, r, useBias);
    }
  }
  return i + size;
}

void solveRows(std::vector<SolverBody>& sb, std::vector<Row>& rows, bool useBias) {
  for (std::size_t i = 0; i < rows.size();) i = solveRowBlock(sb, rows, i, useBias);
}

// solveRows of several worlds, block by block in turn: each world's rows in their own order
// (the same bits), the worlds' chains of dependent rows overlapping in the CPU.
void solveRowsSideBySide(std::span<World::Impl* const> worlds, bool useBias) {
  assert(worlds.size() <= World::kMaxSideBySide);
  std::array<std::size_t, World::kMaxSideBySide> at{};
  for (bool any = true; any;) {
    any = false;
    for (std::size_t w = 0; w < worlds.size(); ++w) {
      World::Impl& m = *worlds[w];
      if (at[w] == m.rows.size()) continue;
      at[w] = solveRowBlock(m.solverBodies, m.rows, at[w], useBias);
      any = true;
    }
  }
}

Mat3 invInertiaMatrix(const SolverBody& b) {
  Mat3 m;
  m << b.ixx, b.ixy, b.ixz, b.ixy, b.iyy, b.iyz, b.ixz, b.iyz, b.izz;
  return m;
}

inline void applyPointImpulse(std::vector<SolverBody>& sb, const World::Impl::PointBlock& p,
                              const Vec3& impulse) {
  SolverBody& a = sb[static_cast<std::size_t>(p.slotA)];
  SolverBody& b = sb[static_cast<std::size_t>(p.slotB)];
  a.v -= a.invMass * impulse;
  a.w -= applyInvInertia(a, p.rA.cross(impulse));
  b.v += b.invMass * impulse;
  b.w += applyInvInertia(b, p.rB.cross(impulse));
}

inline void solvePointBlock(std::vector<SolverBody>& sb, World::Impl::PointBlock& p, bool useBias) {
  const SolverBody& a = sb[static_cast<std::size_t>(p.slotA)];
  const SolverBody& b = sb[static_cast<std::size_t>(p.slotB)];
  const Vec3 cdot = (b.v + b.w.cross(p.rB)) - (a.v + a.w.cross(p.rA));
  const Vec3 d = -(p.invK * (useBias ? Vec3(cdot + p.bias) : cdot));
  p.impulse += d;
  applyPointImpulse(sb, p, d);
}

void solvePointBlocks(std::vector<SolverBody>& sb, std::vector<World::Impl::PointBlock>& blocks,
                      bool useBias) {
  for (World::Impl::PointBlock& p : blocks) solvePointBlock(sb, p, useBias);
}

// solvePointBlocks of several worlds, block by block in turn (as solveRowsSideBySide).
void solvePointBlocksSideBySide(std::span<World::Impl* const> worlds, bool useBias) {
  std::size_t most = 0;
  for (World::Impl* m : worlds) most = std::max(most, m->pointBlocks.size());
  for (std::size_t i = 0; i < most; ++i)
    for (World::Impl* m : worlds)
      if (i < m->pointBlocks.size()) solvePointBlock(m->solverBodies, m->pointBlocks[i], useBias);
}

// Nonlinear Gauss-Seidel on the joint anchors (Box2D v2's position solver, block 3x3):
// K = (mA^-1 + mB^-1) 1 - [rA] IA^-1 [rA] - [rB] IB^-1 [rB],  P = -K^-1 C, applied to positions
// and orientations only, with the arms re-evaluated at the current orientations.
// One joint of projectJointPositions' pass.
inline void projectJoint(World::Impl& m, std::size_t idx) {
  auto rotate = [](Quat& q, const Vec3& angle) {
    const Quat dq(0.0f, 0.5f * angle.x(), 0.5f * angle.y(), 0.5f * angle.z());
    q.coeffs() += (dq * q).coeffs();
    q.normalize();
  };
  const World::Impl::JointPosition& jp = m.jointPositions[idx];
  const auto ia = static_cast<std::size_t>(jp.slotA), ib = static_cast<std::size_t>(jp.slotB);
  const SolverBody& a = m.solverBodies[ia];
  const SolverBody& b = m.solverBodies[ib];
  const Vec3 rA = rotateVector(m.slotOrientation[ia], jp.armA);
  const Vec3 rB = rotateVector(m.slotOrientation[ib], jp.armB);
  const Vec3 c = (m.slotPosition[ib] + rB) - (m.slotPosition[ia] + rA);
  Mat3 invIA, invIB;
  invIA << a.ixx, a.ixy, a.ixz, a.ixy, a.iyy, a.iyz, a.ixz, a.iyz, a.izz;
  invIB << b.ixx, b.ixy, b.ixz, b.ixy, b.iyy, b.iyz, b.ixz, b.iyz, b.izz;
  const Mat3 sA = skew(rA), sB = skew(rB);
  const Mat3 k = (a.invMass + b.invMass) * Mat3::Identity() - sA * invIA * sA - sB * invIB * sB;
  if (!(std::abs(k.determinant()) > 1e-20f)) return;
  // Large errors are closed over several steps (a projection is only good for small ones).
  const float len = c.norm();
  const Vec3 clampedError = len > kMaxJointCorrection ? Vec3(c * (kMaxJointCorrection / len)) : c;
  const Vec3 p = -(k.inverse() * clampedError);
  m.slotPosition[ia] -= a.invMass * p;
  rotate(m.slotOrientation[ia], -(invIA * rA.cross(p)));
  m.slotPosition[ib] += b.invMass * p;
  rotate(m.slotOrientation[ib], invIB * rB.cross(p));
}

void projectJointPositions(World::Impl& m, int iterations) {
  for (int it = 0; it < iterations; ++it)
    for (std::size_t idx = 0; idx < m.jointPositions.size(); ++idx) projectJoint(m, idx);
}

// projectJointPositions of several worlds, joint by joint in turn (as solveRowsSideBySide).
void projectJointPositionsSideBySide(std::span<World::Impl* const> worlds, int iterations) {
  std::size_t most = 0;
  for (World::Impl* m : worlds) most = std::max(most, m->jointPositions.size());
  for (int it = 0; it < iterations; ++it)
    for (std::size_t idx = 0; idx < most; ++idx)
      for (World::Impl* m : worlds)
        if (idx < m->jointPositions.size()) projectJoint(*m, idx);
}
}  // namespace

void World::step(float h) {
  assert(h > 0.0f && std::isfinite(h) && "step: dt must be positive");
  const simd::FlushDenormals flushDenormals;
  beginStep(h);
  Impl& m = *impl_;
  auto sweep = [&](bool useBias) {
    m.surfaceBatches.solve(m.solverBodies, useBias);
    solveRows(m.solverBodies, m.rows, useBias);
    solvePointBlocks(m.solverBodies, m.pointBlocks, useBias);
  };
  for (int it = 0; it < settings_.iterations; ++it) sweep(true);
  integrate(h);
  projectJointPositions(m, settings_.positionIterations);
  for (int it = 0; it < settings_.relaxIterations; ++it) sweep(false);
  endStep();
}

bool useVectorSweeps(bool enabled) {
  return SurfaceBatches::useVectorSweeps(enabled);
}

void World::stepTogether(World& a, World& b, float h) {
  World* const both[2] = {&a, &b};
  stepSideBySide(both, h);
}

void World::stepSideBySide(std::span<World* const> worlds, float h) {
  assert(h > 0.0f && std::isfinite(h) && "stepSideBySide: dt must be positive");
  if (worlds.size() > kMaxSideBySide) {
    stepSideBySide(worlds.first(kMaxSideBySide), h);
    stepSideBySide(worlds.subspan(kMaxSideBySide), h);
    return;
  }
  bool alike = SurfaceBatches::canSolveSideBySide();
  for (std::size_t w = 1; w < worlds.size() && alike; ++w) {
    const WorldSettings& first = worlds[0]->settings_;
    const WorldSettings& other = worlds[w]->settings_;
    alike = first.iterations == other.iterations &&
            first.relaxIterations == other.relaxIterations &&
            first.positionIterations == other.positionIterations;
    for (std::size_t v = 0; v < w; ++v) alike = alike && worlds[v] != worlds[w];
  }
  if (!alike || worlds.size() < 2) {
    for (World* w : worlds) w->step(h);
    return;
  }
  const simd::FlushDenormals flushDenormals;
  std::array<Impl*, kMaxSideBySide> impls{};
  std::array<SurfaceBatches*, kMaxSideBySide> sweeps{};
  std::array<std::vector<SolverBody>*, kMaxSideBySide> bodies{};
  const std::size_t n = worlds.size();
  for (std::size_t w = 0; w < n; ++w) {
    worlds[w]->beginStep(h);
    impls[w] = worlds[w]->impl_.get();
    sweeps[w] = &impls[w]->surfaceBatches;
    bodies[w] = &impls[w]->solverBodies;
  }
  const std::span<Impl* const> all(impls.data(), n);
  auto sweep = [&](bool useBias) {
    SurfaceBatches::solveSideBySide({sweeps.data(), n}, {bodies.data(), n}, useBias);
    solveRowsSideBySide(all, useBias);
    solvePointBlocksSideBySide(all, useBias);
  };
  const WorldSettings& settings = worlds[0]->settings_;
  for (int it = 0; it < settings.iterations; ++it) sweep(true);
  for (World* w : worlds) w->integrate(h);
  projectJointPositionsSideBySide(all, settings.positionIterations);
  for (int it = 0; it < settings.relaxIterations; ++it) sweep(false);
  for (World* w : worlds) w->endStep();
}

namespace {

// Solver slots: free bodies, weld groups, static dummy; velocities integrated (gravity,
// gyroscopic term, damping).
void prepareSolverSlots(World::Impl& m, const WorldState& s, const WorldSettings& settings,
                        float h) {
  const std::size_t n = m.bodies.size();
  const std::size_t groupCount = s.groups.size();
  const std::size_t slotCount = n + groupCount + 1;
  m.solverBodies.resize(slotCount);
  m.slotPosition.resize(slotCount);
  m.slotOrientation.resize(slotCount);
  const SolverBody zero{Vec3::Zero(), 0.0f, Vec3::Zero(), 0.0f, 0, 0, 0, 0, 0, 0, 0.0f, 0.0f};
  std::fill(m.solverBodies.begin(), m.solverBodies.end(), zero);
  std::fill(m.slotPosition.begin(), m.slotPosition.end(), Vec3::Zero());
  std::fill(m.slotOrientation.begin(), m.slotOrientation.end(), Quat::Identity());
  for (std::size_t i = 0; i < n; ++i) {
    const BodyConfig& c = m.bodies[i];
    m.slotPosition[i] = s.position[i];
    m.slotOrientation[i] = s.orientation[i];
    if (s.group[i] >= 0 || c.type == BodyType::Static) continue;
    SolverBody& b = m.solverBodies[i];
    b.v = s.linearVelocity[i];
    b.w = s.angularVelocity[i];
    if (c.type != BodyType::Dynamic) continue;
    b.invMass = 1.0f / c.mass;
    const Mat3 r = s.orientation[i].toRotationMatrix();
    setInvInertia(b, r * c.inertiaLocal.inverse() * r.transpose());
    b.v += h * settings.gravity;
    if (settings.gyroscopic) b.w = gyroscopicStep(b.w, s.orientation[i], c.inertiaLocal, h);
    b.v *= 1.0f / (1.0f + h * c.linearDamping);
    b.w *= 1.0f / (1.0f + h * c.angularDamping);
  }
  for (std::size_t g = 0; g < groupCount; ++g) {
    const WorldState::Group& grp = s.groups[g];
    if (!grp.alive) continue;
    float linDamp = 0.0f, angDamp = 0.0f;  // mass-weighted over the members
    for (std::size_t i = 0; i < n; ++i) {
      if (s.group[i] != static_cast<int>(g)) continue;
      linDamp += m.bodies[i].mass * m.bodies[i].linearDamping;
      angDamp += m.bodies[i].mass * m.bodies[i].angularDamping;
    }
    SolverBody& b = m.solverBodies[n + g];
    m.slotPosition[n + g] = grp.position;
    m.slotOrientation[n + g] = grp.orientation;
    b.invMass = 1.0f / grp.mass;
    const Mat3 r = grp.orientation.toRotationMatrix();
    setInvInertia(b, r * grp.inertiaLocal.inverse() * r.transpose());
    b.v = grp.linearVelocity + h * settings.gravity;
    b.w = settings.gyroscopic
              ? gyroscopicStep(grp.angularVelocity, grp.orientation, grp.inertiaLocal, h)
              : grp.angularVelocity;
    b.v *= 1.0f / (1.0f + h * linDamp / grp.mass);
    b.w *= 1.0f / (1.0f + h * angDamp / grp.mass);
  }
}

// Body drives: 3 linear + 3 angular motor rows against the static dummy slot.
void addBodyDriveRows(World::Impl& m, const WorldState& s, int dummy, float h) {
  RowBuilder rb{m};
  for (std::size_t i = 0; i < m.bodies.size(); ++i) {
    const BodyConfig& c = m.bodies[i];
    if (!c.driveEnabled || c.type != BodyType::Dynamic) continue;
    const int slot = m.slotOf(s, static_cast<BodyId>(i));
    const float rate = 1.0f / std::max(c.driveTimeConstant, h);
    const Vec3 targetCom = c.driveTarget.p + c.driveTarget.q * c.centroid;
    const Vec3 linVel = (targetCom - s.position[i]) * rate;
    Quat err = c.driveTarget.q * s.orientation[i].conjugate();
    if (err.w() < 0.0f) err.coeffs() *= -1.0f;
    const Eigen::AngleAxisf aa(err);
    const Vec3 angVel = aa.axis() * (aa.angle() * rate);
    const Vec3 r = s.position[i] - m.slotPosition[static_cast<std::size_t>(slot)];
    const float fMax = c.driveMaxForce * h, tMax = c.driveMaxTorque * h;
    for (int k = 0; k < 3; ++k) {
      const Vec3 e = Vec3::Unit(k);
      rb.add(dummy, slot, e, Vec3::Zero(), r.cross(e), {-linVel[k], 0.0f}, -fMax, fMax, 0.0f,
             false);
    }
    for (int k = 0; k < 3; ++k) {
      const Vec3 e = Vec3::Unit(k);
      rb.add(dummy, slot, Vec3::Zero(), Vec3::Zero(), e, {-angVel[k], 0.0f}, -tMax, tMax, 0.0f,
             false);
    }
  }
}

// Joint drives: 3 angular motor rows towards the target relative rotation.
void addJointDriveRows(World::Impl& m, const WorldState& s, float h) {
  RowBuilder rb{m};
  for (const JointConfig& j : m.joints) {
    if (!j.driveEnabled) continue;
    const auto pa = static_cast<std::size_t>(j.def.parent),
               pb = static_cast<std::size_t>(j.def.child);
    const int sa = m.slotOf(s, static_cast<BodyId>(pa)), sb = m.slotOf(s, static_cast<BodyId>(pb));
    if (sa == sb) continue;
    const Quat desired = s.orientation[pa] * j.def.frameParent * j.driveTarget;
    const Quat actual = s.orientation[pb] * j.def.frameChild;
    Quat err = desired * actual.conjugate();
    if (err.w() < 0.0f) err.coeffs() *= -1.0f;
    const Eigen::AngleAxisf aa(err);
    const Vec3 relVel = aa.axis() * (aa.angle() / std::max(j.driveTimeConstant, h));
    const float tMax = j.driveMaxTorque * h;
    const Vec3 error = aa.axis() * aa.angle();  // rad, desired relative to actual
    for (int k = 0; k < 3; ++k) {
      const Vec3 e = Vec3::Unit(k);
      rb.add(sa, sb, Vec3::Zero(), -e, e, {-relVel[k], 0.0f}, -tMax, tMax, 0.0f, false);
      Row& r = m.rows.back();
      if (j.driveStiffness > 0.0f && r.effMass > 0.0f) {
        // Spring k and damping ratio zeta on this row's effective inertia I: omega^2 = k / I.
        // The soft step settles at error = torque / k whatever I is.
        const float omega = std::sqrt(j.driveStiffness / r.effMass);
        const Softness soft = makeSoft(omega / (2.0f * 3.14159265f), j.driveDampingRatio, h);
        r.bias = -soft.biasRate * error[k];
        r.massScale = soft.massScale;
        r.impulseScale = soft.impulseScale;
      }
    }
  }
}

// Angular cones: angle(uA, uB) <= maxAngle, one-sided.
void addConeRows(World::Impl& m, const WorldState& s, const WorldSettings& settings, float invH) {
  RowBuilder rb{m};
  for (const ConeConfig& c : m.cones) {
    if (!c.enabled) continue;
    const auto ia = static_cast<std::size_t>(c.a), ib = static_cast<std::size_t>(c.b);
    const int sa = m.slotOf(s, static_cast<BodyId>(ia)), sb = m.slotOf(s, static_cast<BodyId>(ib));
    if (sa == sb) continue;
    const Vec3 u = rotateVector(s.orientation[ia], c.axisA),
               v = rotateVector(s.orientation[ib], c.axisB);
    const float angle = std::acos(std::clamp(u.dot(v), -1.0f, 1.0f));
    const float err = c.maxAngle - angle;  // >= 0 allowed; speculative while inside
    Vec3 axis = u.cross(v);
    const float len = axis.norm();
    if (len > 1e-4f) {
      axis /= len;
      rb.add(sa, sb, Vec3::Zero(), axis, -axis, oneSidedBias(err, settings.limitErp, invH), 0.0f,
             kInf, 0.0f, true);
    } else {
      // (Anti)parallel: the opening direction is undefined, so bound the rotation rate about
      // both axes perpendicular to u (speculative; keeps the angle <= ~sqrt(2) maxAngle).
      const Vec3 p1 = u.unitOrthogonal(), p2 = u.cross(p1);
      for (const Vec3& p : {p1, p2}) {
        rb.add(sa, sb, Vec3::Zero(), p, -p, oneSidedBias(err, settings.limitErp, invH), 0.0f, kInf,
               0.0f, true);
        rb.add(sa, sb, Vec3::Zero(), -p, p, oneSidedBias(err, settings.limitErp, invH), 0.0f, kInf,
               0.0f, true);
      }
    }
  }
}

// Joint limits: per axis, a (speculative) one-sided row for each side the angle could reach
// within the step, warm-started from the joint's stored impulses.
void addJointLimitRows(World::Impl& m, WorldState& s, const WorldSettings& settings, float h,
                       float invH) {
  RowBuilder rb{m};
  for (std::size_t ji = 0; ji < m.joints.size(); ++ji) {
    const JointConfig& j = m.joints[ji];
    float* store = &s.jointImpulse[ji * kJointImpulses];
    const auto pa = static_cast<std::size_t>(j.def.parent),
               pb = static_cast<std::size_t>(j.def.child);
    const int sa = m.slotOf(s, static_cast<BodyId>(pa)), sb = m.slotOf(s, static_cast<BodyId>(pb));
    if (sa == sb) {  // welded together: the joint is internal to the group
      std::fill(store, store + kJointImpulses, 0.0f);
      continue;
    }
    if (!j.def.limitsEnabled) {
      std::fill(store + 3, store + kJointImpulses, 0.0f);
      continue;
    }
    const Quat frameA = s.orientation[pa] * j.def.frameParent;
    const Quat rel = frameA.conjugate() * (s.orientation[pb] * j.def.frameChild);
    const Vec3 angles = decomposeJointRotation(rel);
    const Vec3 wRel = m.solverBodies[static_cast<std::size_t>(sb)].w -
                      m.solverBodies[static_cast<std::size_t>(sa)].w;
    const Vec3 d = rel * Vec3::UnitX();
    const float dxy2 = std::max(d.x() * d.x() + d.y() * d.y(), 1e-12f);
    // Rate axes (joint frame): d(angle)/dt = axis · (wB - wA) expressed in frame A.
    Vec3 axes[3];
    axes[0] = Vec3(-d.z() * d.x(), -d.z() * d.y(), dxy2) / dxy2;
    axes[1] = Vec3(-d.y(), d.x(), 0.0f) / std::sqrt(dxy2);
    // Twist = 2 atan2(q.x, q.w) of the relative rotation (its swing has no x part), so under
    // a small left rotation δ (dq = ½ (0, δ) q) its rate is
    // (w² + x², w z + x y, x z - w y) / (w² + x²) · δ.
    {
      const float w = rel.w(), x = rel.x(), y = rel.y(), z = rel.z();
      const float wx2 = std::max(w * w + x * x, 1e-12f);
      axes[2] = Vec3(1.0f, (w * z + x * y) / wx2, (x * z - w * y) / wx2);
    }
    for (int k = 0; k < 3; ++k) {
      const Vec3 axisWorld = frameA * axes[k];
      const float toLower = angles[k] - j.def.lower[k];
      const float toUpper = j.def.upper[k] - angles[k];
      float* lowStore = store + 3 + 2 * k;
      float* upStore = lowStore + 1;
      // A side gets a (speculative) row when the angle could reach it within this step:
      // within kLimitMargin plus twice the current relative rate. Drives raise the rate
      // inside the solve, so they should not close more than kLimitMargin per step.
      const float rate = std::abs(axisWorld.dot(wRel));
      const float reach = kLimitMargin + 2.0f * rate * h;
      if (toLower < reach) {
        rb.add(sa, sb, Vec3::Zero(), -axisWorld, axisWorld,
               oneSidedBias(toLower, settings.limitErp, invH), 0.0f, kInf, *lowStore, true);
        m.rows.back().store = lowStore;
      } else {
        *lowStore = 0.0f;
      }
      if (toUpper < reach) {
        rb.add(sa, sb, Vec3::Zero(), axisWorld, -axisWorld,
               oneSidedBias(toUpper, settings.limitErp, invH), 0.0f, kInf, *upStore, true);
        m.rows.back().store = upStore;
      } else {
        *upStore = 0.0f;
      }
    }
  }
}

// Joint points: one 3x3 block per joint (its anchors held together), and the position
// projection's anchors.
void buildJointPointBlocks(World::Impl& m, WorldState& s, const WorldSettings& settings,
                           float invH) {
  m.jointPositions.clear();
  m.pointBlocks.clear();
  for (std::size_t ji = 0; ji < m.joints.size(); ++ji) {
    const JointConfig& j = m.joints[ji];
    const auto pa = static_cast<std::size_t>(j.def.parent),
               pb = static_cast<std::size_t>(j.def.child);
    const int sa = m.slotOf(s, static_cast<BodyId>(pa)), sb = m.slotOf(s, static_cast<BodyId>(pb));
    if (sa == sb) continue;
    float* store = &s.jointImpulse[ji * kJointImpulses];
    Vec3 worldA, worldB;
    const Vec3 rA = armOf(m, s, pa, j.comAnchorParent, &worldA);
    const Vec3 rB = armOf(m, s, pb, j.comAnchorChild, &worldB);
    const Vec3 c = worldB - worldA;
    m.jointPositions.push_back({sa, sb,
                                m.slotOrientation[static_cast<std::size_t>(sa)].conjugate() * rA,
                                m.slotOrientation[static_cast<std::size_t>(sb)].conjugate() * rB});
    const SolverBody& a = m.solverBodies[static_cast<std::size_t>(sa)];
    const SolverBody& b = m.solverBodies[static_cast<std::size_t>(sb)];
    const Mat3 skA = skew(rA), skB = skew(rB);
    const Mat3 k = (a.invMass + b.invMass) * Mat3::Identity() - skA * invInertiaMatrix(a) * skA -
                   skB * invInertiaMatrix(b) * skB;
    const Mat3 invK = std::abs(k.determinant()) > 1e-30f ? Mat3(k.inverse())
                                                         : Mat3::Zero();  // both static: inert
    m.pointBlocks.push_back({sa, sb, rA, rB, invK, settings.jointErp * invH * c,
                             Vec3(store[0], store[1], store[2]), store});
  }
}

// Warm start: last step's impulses applied (then step() solves with bias, integrates
// positions and relaxes).
void warmStart(World::Impl& m) {
  for (const Row& r : m.rows) {
    if (r.impulse != 0.0f) applyRowImpulse(m.solverBodies, r, r.impulse);
  }
  for (const World::Impl::PointBlock& pb : m.pointBlocks)
    applyPointImpulse(m.solverBodies, pb, pb.impulse);
}

}  // namespace

void World::beginStep(float h) {
  Impl& m = *impl_;
  WorldState& s = state_;
  const float invH = 1.0f / h;
  prepareSolverSlots(m, s, settings_, h);
  const int dummy = static_cast<int>(m.solverBodies.size() - 1);
  // Rows. Order of the sweeps: drives, cones, contacts, limits, joint points last so the
  // skeleton is the best-satisfied constraint at the end of every sweep.
  m.rows.clear();
  addBodyDriveRows(m, s, dummy, h);
  addJointDriveRows(m, s, h);
  addConeRows(m, s, settings_, invH);
  buildContacts(h);  // narrow phase + contact rows (contact.cpp)
  addJointLimitRows(m, s, settings_, h, invH);
  buildJointPointBlocks(m, s, settings_, invH);
  // Surface rows (one body each), packed eight to a batch on different slots.
  prepareSurfaceRows(m, s, rows_, settings_.surfaceErp, invH);
  m.surfaceBatches.build(m.surfaceRows, m.solverBodies, dummy);
  warmStart(m);
}

void World::integrate(float h) {
  Impl& m = *impl_;
  const std::size_t slotCount = m.solverBodies.size();  // the last is the static dummy
  for (std::size_t slot = 0; slot + 1 < slotCount; ++slot) {
    const SolverBody& b = m.solverBodies[slot];
    Quat& q = m.slotOrientation[slot];
    m.slotPosition[slot] += h * b.v;
    // Linearised rotation is meaningless beyond a quarter turn per step: clamp (Box2D does too).
    Vec3 rot = h * b.w;
    const float angle = rot.norm();
    if (angle > kMaxRotationPerStep) {
      rot *= kMaxRotationPerStep / angle;
      m.solverBodies[slot].w *= kMaxRotationPerStep / angle;
    }
    const Quat dq(0.0f, 0.5f * rot.x(), 0.5f * rot.y(), 0.5f * rot.z());
    q.coeffs() += (dq * q).coeffs();
    q.normalize();
  }
}

void World::endStep() {
  Impl& m = *impl_;
  WorldState& s = state_;
  const std::size_t n = m.bodies.size();
  const std::size_t groupCount = s.groups.size();
  for (const Row& r : m.rows) {
    if (r.store) *r.store = r.impulse;
  }
  for (const Impl::PointBlock& pb : m.pointBlocks) {
    for (int k = 0; k < 3; ++k) pb.store[k] = pb.impulse[k];
  }
  storeContactImpulses();
  m.surfaceBatches.writeImpulses(rows_.impulse.data());

  // --- Write back: free bodies from their slots, welded members from their group. ---
  for (std::size_t i = 0; i < n; ++i) {
    if (s.group[i] >= 0 || m.bodies[i].type == BodyType::Static) continue;
    s.position[i] = m.slotPosition[i];
    s.orientation[i] = m.slotOrientation[i];
    s.linearVelocity[i] = m.solverBodies[i].v;
    s.angularVelocity[i] = m.solverBodies[i].w;
  }
  for (std::size_t g = 0; g < groupCount; ++g) {
    WorldState::Group& grp = s.groups[g];
    if (!grp.alive) continue;
    grp.position = m.slotPosition[n + g];
    grp.orientation = m.slotOrientation[n + g];
    grp.linearVelocity = m.solverBodies[n + g].v;
    grp.angularVelocity = m.solverBodies[n + g].w;
  }
  for (std::size_t i = 0; i < n; ++i) {
    const int g = s.group[i];
    if (g < 0) continue;
    const WorldState::Group& grp = s.groups[static_cast<std::size_t>(g)];
    s.position[i] = grp.position + grp.orientation * s.memberOffset[i];
    s.orientation[i] = (grp.orientation * s.memberRotation[i]).normalized();
    s.linearVelocity[i] =
        grp.linearVelocity + grp.angularVelocity.cross(s.position[i] - grp.position);
    s.angularVelocity[i] = grp.angularVelocity;
  }
  ++s.stepCount;
}

}  // namespace dynahand::physics
