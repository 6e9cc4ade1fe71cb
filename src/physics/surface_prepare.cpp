// The tracker's surface rows prepared for the solver's batches (World::step): body by body,
// eight at a time (the SIMD layer's kernel surface_prepare.inl), or one at a time (the
// reference), with the same bits.
#include <algorithm>
#include <atomic>
#include <cassert>
#include <vector>

#include "core/simd/lanes.h"
#include "physics/kernel_paths.h"
#include "physics/rows.h"
#include "physics/world_impl.h"

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

// What the rows of one body share (prepareRowsOfBody).
struct SurfaceBodyConstants {
  Quat q;
  Vec3 position, centroid, slotPosition;
  float invMass, ixx, iyy, izz, ixy, ixz, iyz;
  int slot;

  SurfaceBodyConstants(const World::Impl& m, const WorldState& s, std::size_t body)
      : q(s.orientation[body]), position(s.position[body]), centroid(m.bodies[body].centroid) {
    slot = m.slotOf(s, static_cast<BodyId>(body));
    slotPosition = m.slotPosition[static_cast<std::size_t>(slot)];
    const SolverBody& b = m.solverBodies[static_cast<std::size_t>(slot)];
    invMass = b.invMass;
    ixx = b.ixx, iyy = b.iyy, izz = b.izz, ixy = b.ixy, ixz = b.ixz, iyz = b.iyz;
  }
};

#define DYNAHAND_SIMD_KERNELS "physics/surface_prepare.inl"
#include "core/simd/for_each_level.inl"

// The tracker's thousand surface rows, prepared for the batches: body by body, eight rows at a
// time (the same bits as one at a time); false: one at a time (tests comparing the two).
std::atomic<bool> wideSurfacePrepare{true};

}  // namespace

[[gnu::noinline]] void prepareSurfaceRows(World::Impl& m, const WorldState& s,
                                          const SurfaceRows& rows, float erp, float invH) {
  const std::size_t count = rows.body.size();
  m.surfaceRows.resize(count);
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
    if (first == end) continue;
    const SurfaceBodyConstants body(m, s, b);
    for (std::size_t j = first; j < end; j += simd::kLanes) {
      const int lanes = static_cast<int>(std::min<std::size_t>(simd::kLanes, end - j));
      DYNAHAND_SIMD_DISPATCH(prepareRowsOfBody, m, rows, body, &order[j], lanes, erp, invH);
    }
  }
}

bool useWideSurfacePrepare(bool enabled) {
  wideSurfacePrepare.store(enabled);
  return wideSurfacePrepare.load();
}

}  // namespace dynahand::physics
