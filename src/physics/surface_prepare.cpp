// The tracker's surface rows prepared for the solver's batches (World::step): one at a time,
// or body by body four at a time with SSE, with the same bits.
#include <atomic>
#include <cassert>
#include <vector>

#include "physics/kernel_paths.h"
#include "physics/rows.h"
#include "physics/world_impl.h"

#if defined(__SSE__)
#include <xmmintrin.h>
#endif

namespace dynahand::physics {
namespace {

// One surface row, prepared for the batches (the scalar reference of prepareSurfaceRows).
void prepareSurfaceRow(World::Impl& m, const WorldState& s, const SurfaceRows& rows, std::size_t i,
                       float erp, float invH) {
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
  const Bias bias = rows.lower[i] >= 0.0f ? oneSidedBias(c, erp, invH) : twoSidedBias(c, erp, invH);
  m.surfaceRows[i] = {
      slot,       nrm,        ang,           invIAng,      k > 0.0f ? 1.0f / k : 0.0f,
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
    const __m128 lower =
        _mm_setr_ps(rows.lower[i0], rows.lower[i1], rows.lower[i2], rows.lower[i3]);
    const __m128 upper =
        _mm_setr_ps(rows.upper[i0], rows.upper[i1], rows.upper[i2], rows.upper[i3]);
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
    const __m128 ahead =
        _mm_and_ps(_mm_cmpge_ps(lower, _mm_setzero_ps()), _mm_cmpgt_ps(c, _mm_setzero_ps()));
    const __m128 speculative = mul(c, _mm_set1_ps(invH));
    const __m128 closing = mul(mul(_mm_set1_ps(erp), c), _mm_set1_ps(invH));
    const __m128 solve = _mm_or_ps(_mm_and_ps(ahead, speculative), _mm_andnot_ps(ahead, closing));
    const __m128 relax = _mm_and_ps(ahead, speculative);
    alignas(16) float out[14][4];
    const __m128 fields[14] = {nx, ny, nz,      gx,    gy,    gz,    jx,
                               jy, jz, effMass, solve, relax, lower, upper};
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

}  // namespace

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

bool useWideSurfacePrepare(bool enabled) {
#if defined(__SSE__)
  wideSurfacePrepare.store(enabled);
#else
  wideSurfacePrepare.store(false);
  (void)enabled;
#endif
  return wideSurfacePrepare.load();
}

}  // namespace dynahand::physics
