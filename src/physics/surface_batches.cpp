#include "physics/surface_batches.h"

#include "physics/world_impl.h"

#include <algorithm>
#include <cstddef>
#include <numeric>

#if defined(__SSE__)
#include <xmmintrin.h>
#endif

namespace dynahand::physics {
namespace {
constexpr int kWays = 4;
}  // namespace

void SurfaceBatches::reserve(int rows) {
  const auto n = static_cast<std::size_t>(rows);
  batches_.reserve(n / 4 + 1);
  order_.reserve(n);
}

void SurfaceBatches::build(const std::vector<PreparedSurfaceRow>& rows, int slotCount,
                           int dummySlot) {
  const int n = static_cast<int>(rows.size());
  const auto slots = static_cast<std::size_t>(slotCount);
  // Rows grouped by slot (counting sort, stable), slots by decreasing row count.
  count_.assign(slots, 0);
  for (const PreparedSurfaceRow& r : rows) ++count_[static_cast<std::size_t>(r.slot)];
  start_.assign(slots + 1, 0);
  for (std::size_t s = 0; s < slots; ++s) start_[s + 1] = start_[s] + count_[s];
  order_.resize(static_cast<std::size_t>(n));
  {
    std::vector<int>& next = count_;  // reused as the fill cursor
    for (std::size_t s = 0; s < slots; ++s) next[s] = start_[s];
    for (int i = 0; i < n; ++i)
      order_[static_cast<std::size_t>(
          next[static_cast<std::size_t>(rows[static_cast<std::size_t>(i)].slot)]++)] = i;
  }
  slotsByCount_.resize(slots);
  std::iota(slotsByCount_.begin(), slotsByCount_.end(), 0);
  // Insertion sort (a handful of slots; std::stable_sort would allocate every step).
  auto rowsOf = [&](int slot) {
    return start_[static_cast<std::size_t>(slot) + 1] - start_[static_cast<std::size_t>(slot)];
  };
  for (std::size_t i = 1; i < slots; ++i) {
    const int slot = slotsByCount_[i];
    std::size_t j = i;
    for (; j > 0 && rowsOf(slotsByCount_[j - 1]) < rowsOf(slot); --j)
      slotsByCount_[j] = slotsByCount_[j - 1];
    slotsByCount_[j] = slot;
  }
  const int largest = slots == 0 ? 0
                                 : start_[static_cast<std::size_t>(slotsByCount_[0]) + 1] -
                                       start_[static_cast<std::size_t>(slotsByCount_[0])];
  // Deal the rows, slot after slot, down the columns of a (batches x 4) table: a slot's run
  // is at most `batchCount` long, so its rows land in different batches.
  // Consecutive dealt batches hold the same slots (one long dependency chain through the
  // bodies' velocities), so they are stored kWays apart: batches next to each other in the
  // sweep then touch different bodies and the CPU overlaps them.
  const int dealt = std::max((n + 3) / 4, largest);
  const int batchCount = (dealt + kWays - 1) / kWays * kWays;
  const int stride = batchCount / kWays;
  auto storedAt = [&](int j) { return (j % stride) * kWays + j / stride; };
  batches_.resize(static_cast<std::size_t>(batchCount));
  for (Batch& b : batches_) {
    for (int k = 0; k < 4; ++k) {
      b.slot[k] = dummySlot;
      b.row[k] = -1;
      b.nx[k] = b.ny[k] = b.nz[k] = b.ax[k] = b.ay[k] = b.az[k] = 0.0f;
      b.ix[k] = b.iy[k] = b.iz[k] = 0.0f;
      b.effMass[k] = b.bias[k] = b.relaxBias[k] = b.lower[k] = b.upper[k] = b.impulse[k] = 0.0f;
    }
  }
  int position = 0;
  for (const int slot : slotsByCount_) {
    for (int o = start_[static_cast<std::size_t>(slot)];
         o < start_[static_cast<std::size_t>(slot) + 1]; ++o, ++position) {
      const int i = order_[static_cast<std::size_t>(o)];
      const PreparedSurfaceRow& r = rows[static_cast<std::size_t>(i)];
      Batch& b = batches_[static_cast<std::size_t>(storedAt(position % batchCount))];
      const int k = position / batchCount;
      b.slot[k] = r.slot;
      b.row[k] = i;
      b.nx[k] = r.normal.x();
      b.ny[k] = r.normal.y();
      b.nz[k] = r.normal.z();
      b.ax[k] = r.ang.x();
      b.ay[k] = r.ang.y();
      b.az[k] = r.ang.z();
      b.ix[k] = r.invIAng.x();
      b.iy[k] = r.invIAng.y();
      b.iz[k] = r.invIAng.z();
      b.effMass[k] = r.effMass;
      b.bias[k] = r.bias;
      b.relaxBias[k] = r.relaxBias;
      b.lower[k] = r.lower;
      b.upper[k] = r.upper;
    }
  }
}

void SurfaceBatches::writeImpulses(float* impulses) const {
  for (const Batch& b : batches_)
    for (int k = 0; k < 4; ++k)
      if (b.row[k] >= 0) impulses[b.row[k]] = b.impulse[k];
}

#if defined(__SSE__)
// SolverBody starts with (v, invMass) and (w, pad): one unaligned load each per lane, and a
// 4x4 transpose turns four bodies into x, y, z (and invMass) registers.
void SurfaceBatches::solve(std::vector<SolverBody>& bodies, bool useBias) {
  static_assert(offsetof(SolverBody, invMass) == 12 && offsetof(SolverBody, w) == 16);
  for (Batch& b : batches_) {
    float* p[4];
    for (int k = 0; k < 4; ++k) p[k] = bodies[static_cast<std::size_t>(b.slot[k])].v.data();
    __m128 vx = _mm_loadu_ps(p[0]), vy = _mm_loadu_ps(p[1]), vz = _mm_loadu_ps(p[2]),
           invMass = _mm_loadu_ps(p[3]);
    _MM_TRANSPOSE4_PS(vx, vy, vz, invMass);
    __m128 wx = _mm_loadu_ps(p[0] + 4), wy = _mm_loadu_ps(p[1] + 4), wz = _mm_loadu_ps(p[2] + 4),
           pad = _mm_loadu_ps(p[3] + 4);
    _MM_TRANSPOSE4_PS(wx, wy, wz, pad);

    const __m128 nx = _mm_load_ps(b.nx), ny = _mm_load_ps(b.ny), nz = _mm_load_ps(b.nz);
    const __m128 jv = _mm_add_ps(
        _mm_add_ps(_mm_add_ps(_mm_mul_ps(nx, vx), _mm_mul_ps(ny, vy)), _mm_mul_ps(nz, vz)),
        _mm_add_ps(_mm_add_ps(_mm_mul_ps(_mm_load_ps(b.ax), wx), _mm_mul_ps(_mm_load_ps(b.ay), wy)),
                   _mm_mul_ps(_mm_load_ps(b.az), wz)));
    const __m128 old = _mm_load_ps(b.impulse);
    const __m128 bias = _mm_load_ps(useBias ? b.bias : b.relaxBias);
    const __m128 target = _mm_sub_ps(old, _mm_mul_ps(_mm_load_ps(b.effMass), _mm_add_ps(jv, bias)));
    const __m128 clamped =
        _mm_min_ps(_mm_max_ps(target, _mm_load_ps(b.lower)), _mm_load_ps(b.upper));
    _mm_store_ps(b.impulse, clamped);
    const __m128 d = _mm_sub_ps(clamped, old);
    const __m128 dm = _mm_mul_ps(d, invMass);
    vx = _mm_add_ps(vx, _mm_mul_ps(dm, nx));
    vy = _mm_add_ps(vy, _mm_mul_ps(dm, ny));
    vz = _mm_add_ps(vz, _mm_mul_ps(dm, nz));
    wx = _mm_add_ps(wx, _mm_mul_ps(d, _mm_load_ps(b.ix)));
    wy = _mm_add_ps(wy, _mm_mul_ps(d, _mm_load_ps(b.iy)));
    wz = _mm_add_ps(wz, _mm_mul_ps(d, _mm_load_ps(b.iz)));

    _MM_TRANSPOSE4_PS(vx, vy, vz, invMass);
    _MM_TRANSPOSE4_PS(wx, wy, wz, pad);
    // Padding lanes share the dummy slot; their values are unchanged, so any store order works.
    _mm_storeu_ps(p[0], vx);
    _mm_storeu_ps(p[1], vy);
    _mm_storeu_ps(p[2], vz);
    _mm_storeu_ps(p[3], invMass);
    _mm_storeu_ps(p[0] + 4, wx);
    _mm_storeu_ps(p[1] + 4, wy);
    _mm_storeu_ps(p[2] + 4, wz);
    _mm_storeu_ps(p[3] + 4, pad);
  }
}
#else
void SurfaceBatches::solve(std::vector<SolverBody>& bodies, bool useBias) {
  for (Batch& b : batches_) {
    for (int k = 0; k < 4; ++k) {
      SolverBody& body = bodies[static_cast<std::size_t>(b.slot[k])];
      const Vec3 n(b.nx[k], b.ny[k], b.nz[k]);
      const float jv = n.dot(body.v) + Vec3(b.ax[k], b.ay[k], b.az[k]).dot(body.w);
      const float old = b.impulse[k];
      const float clamped = std::min(
          std::max(old - b.effMass[k] * (jv + (useBias ? b.bias[k] : b.relaxBias[k])), b.lower[k]),
          b.upper[k]);
      const float d = clamped - old;
      b.impulse[k] = clamped;
      body.v += (body.invMass * d) * n;
      body.w += d * Vec3(b.ix[k], b.iy[k], b.iz[k]);
    }
  }
}
#endif

}  // namespace dynahand::physics
