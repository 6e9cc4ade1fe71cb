// World::step: the projected Gauss-Seidel pipeline (stage order as Box2D v3's solver.c:
// integrate velocities -> warm start -> solve with bias -> integrate positions -> relax).
//
// Every constraint is a scalar row  Jv = axis·(vB - vA) + angA·wA + angB·wB  with
//   impulse increment  d = -effMass (Jv + bias),  accumulated impulse clamped to [lower, upper],
//   effMass = 1 / ((invMassA + invMassB)|axis|^2 + angA·IA^-1 angA + angB·IB^-1 angB).
// Position error C enters as bias = erp C / dt (rows that must reach C = 0) or, for one-sided
// rows (C >= 0) that are not yet violated, as the speculative bias C / dt (the row only acts
// if the velocity would cross the boundary within this step). The relax sweeps drop the erp
// part so the correction velocity does not survive as momentum.
#include <algorithm>
#include <atomic>
#include <cassert>
#include <cmath>
#include <limits>

#include "physics/rows.h"

#if defined(__SSE__)
#include <xmmintrin.h>
#endif

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
  const Vec3 wb = q.conjugate() * wWorld;
  const Vec3 iw = inertiaLocal * wb;
  const Vec3 f = h * wb.cross(iw);
  const Mat3 jac = inertiaLocal + h * (skew(wb) * inertiaLocal - skew(iw));
  Vec3 next = wb - jac.inverse() * f;
  // Gyroscopic torque does no work: restore the kinetic energy the implicit step bled.
  const float before = wb.dot(iw), after = next.dot(inertiaLocal * next);
  if (after > 0.0f) next *= std::sqrt(before / after);
  return q * next;
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
void solveRows(std::vector<SolverBody>& sb, std::vector<Row>& rows, bool useBias) {
  const std::size_t count = rows.size();
  for (std::size_t i = 0; i < count;) {
    const auto size = static_cast<std::size_t>(rows[i].blockSize);
    const int passes = rows[i].blockPasses;
    for (int pass = 0; pass < passes; ++pass) {
      for (std::size_t k = i; k < i + size; ++k) {
        Row& r = rows[k];
        if (useBias || r.relax) solveRow(sb, rows, r, useBias);
      }
    }
    i += size;
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

void solvePointBlocks(std::vector<SolverBody>& sb, std::vector<World::Impl::PointBlock>& blocks,
                      bool useBias) {
  for (World::Impl::PointBlock& p : blocks) {
    const SolverBody& a = sb[static_cast<std::size_t>(p.slotA)];
    const SolverBody& b = sb[static_cast<std::size_t>(p.slotB)];
    const Vec3 cdot = (b.v + b.w.cross(p.rB)) - (a.v + a.w.cross(p.rA));
    const Vec3 d = -(p.invK * (useBias ? Vec3(cdot + p.bias) : cdot));
    p.impulse += d;
    applyPointImpulse(sb, p, d);
  }
}

// Nonlinear Gauss-Seidel on the joint anchors (Box2D v2's position solver, block 3x3):
// K = (mA^-1 + mB^-1) 1 - [rA] IA^-1 [rA] - [rB] IB^-1 [rB],  P = -K^-1 C, applied to positions
// and orientations only, with the arms re-evaluated at the current orientations.
void projectJointPositions(World::Impl& m, int iterations) {
  auto rotate = [](Quat& q, const Vec3& angle) {
    const Quat dq(0.0f, 0.5f * angle.x(), 0.5f * angle.y(), 0.5f * angle.z());
    q.coeffs() += (dq * q).coeffs();
    q.normalize();
  };
  const std::size_t count = m.jointPositions.size();
  for (int it = 0; it < iterations; ++it) {
    for (std::size_t idx = 0; idx < count; ++idx) {
      const World::Impl::JointPosition& jp = m.jointPositions[idx];
      const auto ia = static_cast<std::size_t>(jp.slotA), ib = static_cast<std::size_t>(jp.slotB);
      const SolverBody& a = m.solverBodies[ia];
      const SolverBody& b = m.solverBodies[ib];
      const Vec3 rA = m.slotOrientation[ia] * jp.armA;
      const Vec3 rB = m.slotOrientation[ib] * jp.armB;
      const Vec3 c = (m.slotPosition[ib] + rB) - (m.slotPosition[ia] + rA);
      Mat3 invIA, invIB;
      invIA << a.ixx, a.ixy, a.ixz, a.ixy, a.iyy, a.iyz, a.ixz, a.iyz, a.izz;
      invIB << b.ixx, b.ixy, b.ixz, b.ixy, b.iyy, b.iyz, b.ixz, b.iyz, b.izz;
      const Mat3 sA = skew(rA), sB = skew(rB);
      const Mat3 k = (a.invMass + b.invMass) * Mat3::Identity() - sA * invIA * sA - sB * invIB * sB;
      if (!(std::abs(k.determinant()) > 1e-20f)) continue;
      // Large errors are closed over several steps (a projection is only good for small ones).
      const float len = c.norm();
      const Vec3 clampedError =
          len > kMaxJointCorrection ? Vec3(c * (kMaxJointCorrection / len)) : c;
      const Vec3 p = -(k.inverse() * clampedError);
      m.slotPosition[ia] -= a.invMass * p;
      rotate(m.slotOrientation[ia], -(invIA * rA.cross(p)));
      m.slotPosition[ib] += b.invMass * p;
      rotate(m.slotOrientation[ib], invIB * rB.cross(p));
    }
  }
}

}  // namespace

namespace {
// Flush denormals to zero for the duration of a step: velocities decaying towards rest pass
// through the denormal range, where each float operation costs ~100 cycles. Restores the
// caller's mode on exit. Deterministic either way (same mode every step).
class FlushDenormals {
 public:
#if defined(__SSE__)
  FlushDenormals() : saved_(_mm_getcsr()) {
    _mm_setcsr(saved_ | 0x8040u);
  }  // FTZ | DAZ
  ~FlushDenormals() {
    _mm_setcsr(saved_);
  }
#endif
  FlushDenormals(const FlushDenormals&) = delete;
  FlushDenormals& operator=(const FlushDenormals&) = delete;

 private:
#if defined(__SSE__)
  unsigned int saved_;
#endif
};
}  // namespace

namespace {
// A body point given relative to the centre of mass (body axes): its world position, and its
// arm from the centre of the solver slot moving it (the body's, or its weld group's).
Vec3 armOf(const World::Impl& m, const WorldState& s, std::size_t body, const Vec3& comLocal,
           Vec3* world) {
  *world = s.position[body] + s.orientation[body] * comLocal;
  return *world - m.slotPosition[static_cast<std::size_t>(m.slotOf(s, static_cast<BodyId>(body)))];
}

// One surface row, prepared for the batches (the scalar reference of prepareSurfaceRows).
void prepareSurfaceRow(World::Impl& m, const WorldState& s, const SurfaceRows& rows,
                       std::size_t i, float erp, float invH) {
  const auto body = static_cast<std::size_t>(rows.body[i]);
  assert(body < m.bodies.size() && "surface row: bad body");
  const int slot = m.slotOf(s, static_cast<BodyId>(body));
  const SolverBody& b = m.solverBodies[static_cast<std::size_t>(slot)];
  Vec3 world;
  const Vec3 r = armOf(m, s, body, rows.anchor[i] - m.bodies[body].centroid, &world);
  const Vec3& nrm = rows.normal[i];
  const Vec3 ang = r.cross(nrm);
  const Vec3 invIAng = applyInvInertia(b, ang);
  const float k = b.invMass * nrm.squaredNorm() + ang.dot(invIAng);
  const float c = nrm.dot(world - rows.target[i]);
  const Bias bias =
      rows.lower[i] >= 0.0f ? oneSidedBias(c, erp, invH) : twoSidedBias(c, erp, invH);
  m.surfaceRows[i] = {slot,       nrm,        ang,           invIAng,      k > 0.0f ? 1.0f / k : 0.0f,
                      bias.solve, bias.relax, rows.lower[i], rows.upper[i]};
}

#if defined(__SSE__)
// Four rows of one body at once, the same arithmetic operation for operation (no fused or
// reordered operations), so the same bits as prepareSurfaceRow.
struct SurfaceRowsOfBody {
  __m128 qx, qy, qz, qw, px, py, pz, cx, cy, cz, sx, sy, sz;
  __m128 invMass, ixx, iyy, izz, ixy, ixz, iyz;
  int slot;

  SurfaceRowsOfBody(const World::Impl& m, const WorldState& s, std::size_t body) {
    slot = m.slotOf(s, static_cast<BodyId>(body));
    const SolverBody& b = m.solverBodies[static_cast<std::size_t>(slot)];
    const Quat& q = s.orientation[body];
    const Vec3& p = s.position[body];
    const Vec3& c = m.bodies[body].centroid;
    const Vec3& sp = m.slotPosition[static_cast<std::size_t>(slot)];
    qx = _mm_set1_ps(q.x()), qy = _mm_set1_ps(q.y()), qz = _mm_set1_ps(q.z());
    qw = _mm_set1_ps(q.w());
    px = _mm_set1_ps(p.x()), py = _mm_set1_ps(p.y()), pz = _mm_set1_ps(p.z());
    cx = _mm_set1_ps(c.x()), cy = _mm_set1_ps(c.y()), cz = _mm_set1_ps(c.z());
    sx = _mm_set1_ps(sp.x()), sy = _mm_set1_ps(sp.y()), sz = _mm_set1_ps(sp.z());
    invMass = _mm_set1_ps(b.invMass);
    ixx = _mm_set1_ps(b.ixx), iyy = _mm_set1_ps(b.iyy), izz = _mm_set1_ps(b.izz);
    ixy = _mm_set1_ps(b.ixy), ixz = _mm_set1_ps(b.ixz), iyz = _mm_set1_ps(b.iyz);
  }

  // Rows index[0..3] (all on this body) into m.surfaceRows.
  void prepare(World::Impl& m, const SurfaceRows& rows, const int* index, float erp,
               float invH) const {
    const auto i0 = static_cast<std::size_t>(index[0]), i1 = static_cast<std::size_t>(index[1]),
               i2 = static_cast<std::size_t>(index[2]), i3 = static_cast<std::size_t>(index[3]);
    auto gather = [&](const std::vector<Vec3>& v, __m128& x, __m128& y, __m128& z) {
      __m128 a = _mm_setr_ps(v[i0].x(), v[i0].y(), v[i0].z(), 0.0f);
      __m128 b = _mm_setr_ps(v[i1].x(), v[i1].y(), v[i1].z(), 0.0f);
      __m128 c = _mm_setr_ps(v[i2].x(), v[i2].y(), v[i2].z(), 0.0f);
      __m128 d = _mm_setr_ps(v[i3].x(), v[i3].y(), v[i3].z(), 0.0f);
      _MM_TRANSPOSE4_PS(a, b, c, d);
      x = a, y = b, z = c;
    };
    const auto add = [](__m128 a, __m128 b) { return _mm_add_ps(a, b); };
    const auto sub = [](__m128 a, __m128 b) { return _mm_sub_ps(a, b); };
    const auto mul = [](__m128 a, __m128 b) { return _mm_mul_ps(a, b); };
    __m128 ax, ay, az, nx, ny, nz, tx, ty, tz;
    gather(rows.anchor, ax, ay, az);
    gather(rows.normal, nx, ny, nz);
    gather(rows.target, tx, ty, tz);
    const __m128 lower = _mm_setr_ps(rows.lower[i0], rows.lower[i1], rows.lower[i2], rows.lower[i3]);
    const __m128 upper = _mm_setr_ps(rows.upper[i0], rows.upper[i1], rows.upper[i2], rows.upper[i3]);
    // comLocal = anchor - centroid; world = position + q * comLocal (Eigen's
    // _transformVector: uv = q.vec × v, uv += uv, v + w uv + q.vec × uv).
    const __m128 lx = sub(ax, cx), ly = sub(ay, cy), lz = sub(az, cz);
    __m128 ux = sub(mul(qy, lz), mul(qz, ly)), uy = sub(mul(qz, lx), mul(qx, lz)),
           uz = sub(mul(qx, ly), mul(qy, lx));
    ux = add(ux, ux), uy = add(uy, uy), uz = add(uz, uz);
    const __m128 rx = add(add(lx, mul(qw, ux)), sub(mul(qy, uz), mul(qz, uy)));
    const __m128 ry = add(add(ly, mul(qw, uy)), sub(mul(qz, ux), mul(qx, uz)));
    const __m128 rz = add(add(lz, mul(qw, uz)), sub(mul(qx, uy), mul(qy, ux)));
    const __m128 wx = add(px, rx), wy = add(py, ry), wz = add(pz, rz);
    const __m128 armX = sub(wx, sx), armY = sub(wy, sy), armZ = sub(wz, sz);
    // ang = arm × normal; invIAng = the inverse inertia times ang.
    const __m128 gx = sub(mul(armY, nz), mul(armZ, ny));
    const __m128 gy = sub(mul(armZ, nx), mul(armX, nz));
    const __m128 gz = sub(mul(armX, ny), mul(armY, nx));
    const __m128 jx = add(add(mul(ixx, gx), mul(ixy, gy)), mul(ixz, gz));
    const __m128 jy = add(add(mul(ixy, gx), mul(iyy, gy)), mul(iyz, gz));
    const __m128 jz = add(add(mul(ixz, gx), mul(iyz, gy)), mul(izz, gz));
    // Eigen's dot and squaredNorm of 3-vectors sum as x + (y + z).
    const __m128 k = add(mul(invMass, add(mul(nx, nx), add(mul(ny, ny), mul(nz, nz)))),
                         add(mul(gx, jx), add(mul(gy, jy), mul(gz, jz))));
    const __m128 effMass =
        _mm_and_ps(_mm_cmpgt_ps(k, _mm_setzero_ps()), _mm_div_ps(_mm_set1_ps(1.0f), k));
    const __m128 c = add(mul(nx, sub(wx, tx)), add(mul(ny, sub(wy, ty)), mul(nz, sub(wz, tz))));
    // Bias (rows.h): one-sided rows (lower >= 0) ahead of the surface keep c / h in both
    // sweeps; otherwise erp c / h, and no relax bias.
    const __m128 ahead = _mm_and_ps(_mm_cmpge_ps(lower, _mm_setzero_ps()),
                                    _mm_cmpgt_ps(c, _mm_setzero_ps()));
    const __m128 speculative = mul(c, _mm_set1_ps(invH));
    const __m128 closing = mul(mul(_mm_set1_ps(erp), c), _mm_set1_ps(invH));
    const __m128 solve =
        _mm_or_ps(_mm_and_ps(ahead, speculative), _mm_andnot_ps(ahead, closing));
    const __m128 relax = _mm_and_ps(ahead, speculative);
    alignas(16) float out[14][4];
    const __m128 fields[14] = {nx, ny, nz, gx, gy, gz, jx, jy, jz, effMass, solve, relax, lower, upper};
    for (int f = 0; f < 14; ++f) _mm_store_ps(out[f], fields[f]);
    for (int lane = 0; lane < 4; ++lane) {
      PreparedSurfaceRow& row = m.surfaceRows[static_cast<std::size_t>(index[lane])];
      row.slot = slot;
      row.normal = Vec3(out[0][lane], out[1][lane], out[2][lane]);
      row.ang = Vec3(out[3][lane], out[4][lane], out[5][lane]);
      row.invIAng = Vec3(out[6][lane], out[7][lane], out[8][lane]);
      row.effMass = out[9][lane];
      row.bias = out[10][lane];
      row.relaxBias = out[11][lane];
      row.lower = out[12][lane];
      row.upper = out[13][lane];
    }
  }
};
#endif

// The tracker's thousand surface rows, prepared for the batches: body by body, four rows at a
// time with SSE (the same bits as one at a time), the rest one by one.
std::atomic<bool> wideSurfacePrepare{true};

[[gnu::noinline]] void prepareSurfaceRows(World::Impl& m, const WorldState& s,
                                          const SurfaceRows& rows, float erp, float invH) {
  const std::size_t count = rows.body.size();
  m.surfaceRows.resize(count);
#if defined(__SSE__)
  if (!wideSurfacePrepare.load(std::memory_order_relaxed)) {
    for (std::size_t i = 0; i < count; ++i) prepareSurfaceRow(m, s, rows, i, erp, invH);
    return;
  }
  // Rows grouped by body (counting sort).
  const std::size_t bodies = m.bodies.size();
  std::vector<int>& start = m.surfaceBodyStart;
  std::vector<int>& order = m.surfaceRowsByBody;
  start.assign(bodies + 1, 0);
  for (std::size_t i = 0; i < count; ++i) {
    assert(static_cast<std::size_t>(rows.body[i]) < bodies && "surface row: bad body");
    ++start[static_cast<std::size_t>(rows.body[i]) + 1];
  }
  for (std::size_t b = 0; b < bodies; ++b) start[b + 1] += start[b];
  order.resize(count);
  {
    std::vector<int>& next = m.surfaceBodyStart;
    for (std::size_t i = 0; i < count; ++i)
      order[static_cast<std::size_t>(next[static_cast<std::size_t>(rows.body[i])]++)] =
          static_cast<int>(i);
    // next[b] is now the end of body b's rows, i.e. the start of body b + 1's.
    for (std::size_t b = bodies; b > 0; --b) next[b] = next[b - 1];
    next[0] = 0;
  }
  for (std::size_t b = 0; b < bodies; ++b) {
    const auto first = static_cast<std::size_t>(start[b]);
    const auto end = static_cast<std::size_t>(start[b + 1]);
    std::size_t j = first;
    if (end - first >= 4) {
      const SurfaceRowsOfBody body(m, s, b);
      for (; j + 4 <= end; j += 4) body.prepare(m, rows, &order[j], erp, invH);
    }
    for (; j < end; ++j)
      prepareSurfaceRow(m, s, rows, static_cast<std::size_t>(order[j]), erp, invH);
  }
#else
  for (std::size_t i = 0; i < count; ++i) prepareSurfaceRow(m, s, rows, i, erp, invH);
#endif
}
}  // namespace

bool World::useWideSurfacePrepare(bool enabled) {
#if defined(__SSE__)
  wideSurfacePrepare.store(enabled);
#else
  wideSurfacePrepare.store(false);
  (void)enabled;
#endif
  return wideSurfacePrepare.load();
}

void World::step(float h) {
  assert(h > 0.0f && std::isfinite(h) && "step: dt must be positive");
  const FlushDenormals flushDenormals;
  beginStep(h);
  for (int it = 0; it < settings_.iterations; ++it) {
    impl_->surfaceBatches.solve(impl_->solverBodies, true);
    solveJointAndContactRows(true);
  }
  integrate(h);
  for (int it = 0; it < settings_.relaxIterations; ++it) {
    impl_->surfaceBatches.solve(impl_->solverBodies, false);
    solveJointAndContactRows(false);
  }
  endStep();
}

void World::stepTogether(World& a, World& b, float h) {
  assert(h > 0.0f && std::isfinite(h) && "stepTogether: dt must be positive");
  if (&a == &b || a.settings_.iterations != b.settings_.iterations ||
      a.settings_.relaxIterations != b.settings_.relaxIterations ||
      !SurfaceBatches::canSolveTogether()) {
    a.step(h);
    b.step(h);
    return;
  }
  const FlushDenormals flushDenormals;
  a.beginStep(h);
  b.beginStep(h);
  Impl& ma = *a.impl_;
  Impl& mb = *b.impl_;
  for (int it = 0; it < a.settings_.iterations; ++it) {
    SurfaceBatches::solveTogether(ma.surfaceBatches, ma.solverBodies, mb.surfaceBatches,
                                  mb.solverBodies, true);
    a.solveJointAndContactRows(true);
    b.solveJointAndContactRows(true);
  }
  a.integrate(h);
  b.integrate(h);
  for (int it = 0; it < a.settings_.relaxIterations; ++it) {
    SurfaceBatches::solveTogether(ma.surfaceBatches, ma.solverBodies, mb.surfaceBatches,
                                  mb.solverBodies, false);
    a.solveJointAndContactRows(false);
    b.solveJointAndContactRows(false);
  }
  a.endStep();
  b.endStep();
}

void World::solveJointAndContactRows(bool useBias) {
  Impl& m = *impl_;
  solveRows(m.solverBodies, m.rows, useBias);
  solvePointBlocks(m.solverBodies, m.pointBlocks, useBias);
}

void World::beginStep(float h) {
  Impl& m = *impl_;
  WorldState& s = state_;
  const float invH = 1.0f / h;
  const std::size_t n = m.bodies.size();
  const std::size_t groupCount = s.groups.size();
  const std::size_t slotCount = n + groupCount + 1;

  // --- Solver slots: free bodies, weld groups, static dummy. ---
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
    // Integrate velocities: gravity, gyroscopic term, damping.
    b.invMass = 1.0f / c.mass;
    const Mat3 r = s.orientation[i].toRotationMatrix();
    setInvInertia(b, r * c.inertiaLocal.inverse() * r.transpose());
    b.v += h * settings_.gravity;
    if (settings_.gyroscopic) b.w = gyroscopicStep(b.w, s.orientation[i], c.inertiaLocal, h);
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
    b.v = grp.linearVelocity + h * settings_.gravity;
    b.w = settings_.gyroscopic
              ? gyroscopicStep(grp.angularVelocity, grp.orientation, grp.inertiaLocal, h)
              : grp.angularVelocity;
    b.v *= 1.0f / (1.0f + h * linDamp / grp.mass);
    b.w *= 1.0f / (1.0f + h * angDamp / grp.mass);
  }
  const int dummy = static_cast<int>(slotCount - 1);

  // --- Rows. Order of the sweeps: drives, cones, contacts, limits, joint points last so the
  // skeleton is the best-satisfied constraint at the end of every sweep. ---
  m.rows.clear();
  RowBuilder rb{m};
  auto slotOf = [&](std::size_t body) { return m.slotOf(s, static_cast<BodyId>(body)); };

  // Body drives: 3 linear + 3 angular motor rows against the static dummy.
  for (std::size_t i = 0; i < n; ++i) {
    const BodyConfig& c = m.bodies[i];
    if (!c.driveEnabled || c.type != BodyType::Dynamic) continue;
    const int slot = slotOf(i);
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
  // Joint drives: 3 angular motor rows towards the target relative rotation.
  for (const JointConfig& j : m.joints) {
    if (!j.driveEnabled) continue;
    const auto pa = static_cast<std::size_t>(j.def.parent),
               pb = static_cast<std::size_t>(j.def.child);
    const int sa = slotOf(pa), sb = slotOf(pb);
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
  // Angular cones: angle(uA, uB) <= maxAngle, one-sided.
  for (const ConeConfig& c : m.cones) {
    if (!c.enabled) continue;
    const auto ia = static_cast<std::size_t>(c.a), ib = static_cast<std::size_t>(c.b);
    const int sa = slotOf(ia), sb = slotOf(ib);
    if (sa == sb) continue;
    const Vec3 u = s.orientation[ia] * c.axisA, v = s.orientation[ib] * c.axisB;
    const float angle = std::acos(std::clamp(u.dot(v), -1.0f, 1.0f));
    const float err = c.maxAngle - angle;  // >= 0 allowed; speculative while inside
    Vec3 axis = u.cross(v);
    const float len = axis.norm();
    if (len > 1e-4f) {
      axis /= len;
      rb.add(sa, sb, Vec3::Zero(), axis, -axis, oneSidedBias(err, settings_.limitErp, invH), 0.0f,
             kInf, 0.0f, true);
    } else {
      // (Anti)parallel: the opening direction is undefined, so bound the rotation rate about
      // both axes perpendicular to u (speculative; keeps the angle <= ~sqrt(2) maxAngle).
      const Vec3 p1 = u.unitOrthogonal(), p2 = u.cross(p1);
      for (const Vec3& p : {p1, p2}) {
        rb.add(sa, sb, Vec3::Zero(), p, -p, oneSidedBias(err, settings_.limitErp, invH), 0.0f, kInf,
               0.0f, true);
        rb.add(sa, sb, Vec3::Zero(), -p, p, oneSidedBias(err, settings_.limitErp, invH), 0.0f, kInf,
               0.0f, true);
      }
    }
  }
  buildContacts(h);  // contacts.cpp-free part: narrow phase + rows (below)
  // Joints: limits then points.
  for (std::size_t ji = 0; ji < m.joints.size(); ++ji) {
    const JointConfig& j = m.joints[ji];
    float* store = &s.jointImpulse[ji * kJointImpulses];
    const auto pa = static_cast<std::size_t>(j.def.parent),
               pb = static_cast<std::size_t>(j.def.child);
    const int sa = slotOf(pa), sb = slotOf(pb);
    if (sa == sb) {  // welded together: the joint is internal to the group
      std::fill(store, store + kJointImpulses, 0.0f);
      continue;
    }
    if (j.def.limitsEnabled) {
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
                 oneSidedBias(toLower, settings_.limitErp, invH), 0.0f, kInf, *lowStore, true);
          m.rows.back().store = lowStore;
        } else {
          *lowStore = 0.0f;
        }
        if (toUpper < reach) {
          rb.add(sa, sb, Vec3::Zero(), axisWorld, -axisWorld,
                 oneSidedBias(toUpper, settings_.limitErp, invH), 0.0f, kInf, *upStore, true);
          m.rows.back().store = upStore;
        } else {
          *upStore = 0.0f;
        }
      }
    } else {
      std::fill(store + 3, store + kJointImpulses, 0.0f);
    }
  }
  m.jointPositions.clear();
  m.pointBlocks.clear();
  for (std::size_t ji = 0; ji < m.joints.size(); ++ji) {
    const JointConfig& j = m.joints[ji];
    const auto pa = static_cast<std::size_t>(j.def.parent),
               pb = static_cast<std::size_t>(j.def.child);
    const int sa = slotOf(pa), sb = slotOf(pb);
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
    m.pointBlocks.push_back({sa, sb, rA, rB, invK, settings_.jointErp * invH * c,
                             Vec3(store[0], store[1], store[2]), store});
  }

  // Surface rows (one body each), packed four to a batch on different slots.
  prepareSurfaceRows(m, s, rows_, settings_.surfaceErp, invH);
  m.surfaceBatches.build(m.surfaceRows, m.solverBodies, dummy);

  // --- Warm start (then step() solves with bias, integrates positions and relaxes). ---
  for (const Row& r : m.rows) {
    if (r.impulse != 0.0f) applyRowImpulse(m.solverBodies, r, r.impulse);
  }
  for (const Impl::PointBlock& pb : m.pointBlocks)
    applyPointImpulse(m.solverBodies, pb, pb.impulse);
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
  projectJointPositions(m, settings_.positionIterations);
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
