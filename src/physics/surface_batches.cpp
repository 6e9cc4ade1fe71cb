#include "physics/surface_batches.h"

#include "core/cpu_features.h"
#include "physics/world_impl.h"

#include <algorithm>
#include <cstddef>
#include <numeric>

#if defined(__SSE__)
#include <xmmintrin.h>
#endif
#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#define DYNAHAND_SWEEP_AVX 1
#endif

namespace dynahand::physics {
namespace {
constexpr int kSpread = 4;
constexpr int kMinRowsToSplit = 32;  // fewer rows on one slot are never split
}  // namespace

void SurfaceBatches::reserve(int rows) {
  const auto n = static_cast<std::size_t>(rows);
  batches_.reserve(n / 4 + 1);
  order_.reserve(n);
}

void SurfaceBatches::build(const std::vector<PreparedSurfaceRow>& rows,
                           const std::vector<SolverBody>& bodies, int dummySlot) {
  slotCount_ = static_cast<int>(bodies.size());
  dummySlot_ = dummySlot;
  const int n = static_cast<int>(rows.size());
  // Slots with more rows than a four-wide sweep has batches are split (see the header), but
  // not small sets: a few rows solve as well in sequence, and Gauss-Seidel converges faster.
  const int target = std::max(1, (n + 3) / 4);
  count_.assign(static_cast<std::size_t>(slotCount_), 0);
  for (const PreparedSurfaceRow& r : rows) ++count_[static_cast<std::size_t>(r.slot)];
  splits_.clear();
  int copyCount = 0;
  for (int s = 0; s < slotCount_; ++s) {
    const int c = count_[static_cast<std::size_t>(s)];
    if (c <= target || c < kMinRowsToSplit) continue;
    const int copies = (c + target - 1) / target;
    splits_.push_back({s, copyCount, copies});
    copyCount += copies;
  }
  copies_.resize(static_cast<std::size_t>(copyCount));
  slotCopies_.assign(static_cast<std::size_t>(slotCount_), 1.0f);
  for (const Split& sp : splits_)
    slotCopies_[static_cast<std::size_t>(sp.slot)] = static_cast<float>(sp.copies);
  // Each row's solving slot: its own, or for a split slot the copies in turn (so that every
  // copy sees rows from all over the body).
  virtualSlot_.resize(static_cast<std::size_t>(n));
  {
    std::vector<int>& turn = rowsSeen_;
    turn.assign(static_cast<std::size_t>(slotCount_), 0);
    std::vector<int>& splitOf = splitOfSlot_;
    splitOf.assign(static_cast<std::size_t>(slotCount_), -1);
    for (std::size_t k = 0; k < splits_.size(); ++k)
      splitOf[static_cast<std::size_t>(splits_[k].slot)] = static_cast<int>(k);
    for (int i = 0; i < n; ++i) {
      const int slot = rows[static_cast<std::size_t>(i)].slot;
      const int k = splitOf[static_cast<std::size_t>(slot)];
      if (k < 0) {
        virtualSlot_[static_cast<std::size_t>(i)] = slot;
        continue;
      }
      const Split& sp = splits_[static_cast<std::size_t>(k)];
      const int j = turn[static_cast<std::size_t>(slot)]++ % sp.copies;
      virtualSlot_[static_cast<std::size_t>(i)] = slotCount_ + sp.first + j;
    }
  }
  const int slotCountAll = slotCount_ + copyCount;
  const auto slots = static_cast<std::size_t>(slotCountAll);
  // Rows grouped by solving slot (counting sort, stable), slots by decreasing row count.
  count_.assign(slots, 0);
  for (int i = 0; i < n; ++i)
    ++count_[static_cast<std::size_t>(virtualSlot_[static_cast<std::size_t>(i)])];
  start_.assign(slots + 1, 0);
  for (std::size_t s = 0; s < slots; ++s) start_[s + 1] = start_[s] + count_[s];
  order_.resize(static_cast<std::size_t>(n));
  {
    std::vector<int>& next = count_;  // reused as the fill cursor
    for (std::size_t s = 0; s < slots; ++s) next[s] = start_[s];
    for (int i = 0; i < n; ++i)
      order_[static_cast<std::size_t>(
          next[static_cast<std::size_t>(virtualSlot_[static_cast<std::size_t>(i)])]++)] = i;
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
  // is at most `batchCount` long, so its rows land in different batches, and each lane of
  // the sweep stays on one slot for a long run of batches (solve() keeps that slot's
  // velocities in registers until the lane moves on).
  const int batchCount = std::max((n + 3) / 4, largest);
  batches_.resize(static_cast<std::size_t>(batchCount));
  // The next free cell of the table: batch `column`, lane `lane` (dealt down the columns).
  int column = 0, lane = 0;
  auto deal = [&](int o) {
    const int i = order_[static_cast<std::size_t>(o)];
    const PreparedSurfaceRow& r = rows[static_cast<std::size_t>(i)];
    Batch& b = batches_[static_cast<std::size_t>(column)];
    const int k = lane;
    if (++column == batchCount) column = 0, ++lane;
    b.slot[k] = virtualSlot_[static_cast<std::size_t>(i)];
    b.row[k] = i;
    b.nx[k] = r.normal.x();
    b.ny[k] = r.normal.y();
    b.nz[k] = r.normal.z();
    b.ax[k] = r.ang.x();
    b.ay[k] = r.ang.y();
    b.az[k] = r.ang.z();
    // A copy holds 1/copies of its slot's mass: inverse mass and inertia times copies (exactly
    // the slot's own values for an unsplit slot, copies = 1).
    const float copies = slotCopies_[static_cast<std::size_t>(r.slot)];
    const float invMass = bodies[static_cast<std::size_t>(r.slot)].invMass * copies;
    b.ix[k] = r.invIAng.x() * copies;
    b.iy[k] = r.invIAng.y() * copies;
    b.iz[k] = r.invIAng.z() * copies;
    b.effMass[k] = r.effMass / copies;
    b.ux[k] = r.normal.x() * invMass;
    b.uy[k] = r.normal.y() * invMass;
    b.uz[k] = r.normal.z() * invMass;
    b.bias[k] = r.bias;
    b.relaxBias[k] = r.relaxBias;
    b.lower[k] = r.lower;
    b.upper[k] = r.upper;
    b.impulse[k] = 0.0f;
  };
  // A slot's rows (in input order, i.e. scanline order of the points) taken every kSpread-th:
  // Gauss-Seidel then alternates between parts of the body instead of sweeping it from one
  // side to the other.
  for (const int slot : slotsByCount_) {
    const int first = start_[static_cast<std::size_t>(slot)];
    const int end = start_[static_cast<std::size_t>(slot) + 1];
    for (int residue = 0; residue < kSpread; ++residue)
      for (int o = first + residue; o < end; o += kSpread) deal(o);
  }
  // The cells left over: padding on the dummy slot, all zero (they never act).
  while (batchCount > 0 && lane < 4) {
    Batch& b = batches_[static_cast<std::size_t>(column)];
    const int k = lane;
    if (++column == batchCount) column = 0, ++lane;
    b.slot[k] = dummySlot;
    b.row[k] = -1;
    b.nx[k] = b.ny[k] = b.nz[k] = b.ax[k] = b.ay[k] = b.az[k] = 0.0f;
    b.ix[k] = b.iy[k] = b.iz[k] = 0.0f;
    b.ux[k] = b.uy[k] = b.uz[k] = 0.0f;
    b.effMass[k] = b.bias[k] = b.relaxBias[k] = b.lower[k] = b.upper[k] = b.impulse[k] = 0.0f;
  }
}

float* SurfaceBatches::laneBody(std::vector<SolverBody>& bodies, int slot) {
  return slot < slotCount_ ? bodies[static_cast<std::size_t>(slot)].v.data()
                           : copies_[static_cast<std::size_t>(slot - slotCount_)].v.data();
}

void SurfaceBatches::beginCopies(const std::vector<SolverBody>& bodies) {
  for (const Split& sp : splits_)
    for (int j = 0; j < sp.copies; ++j)
      copies_[static_cast<std::size_t>(sp.first + j)] = bodies[static_cast<std::size_t>(sp.slot)];
}

void SurfaceBatches::endCopies(std::vector<SolverBody>& bodies) const {
  // The copies' average: each row moved its copy by copies x its share, so the average moved
  // by exactly what that row's impulse does to the whole body.
  for (const Split& sp : splits_) {
    Vec3 v = Vec3::Zero(), w = Vec3::Zero();
    for (int j = 0; j < sp.copies; ++j) {
      v += copies_[static_cast<std::size_t>(sp.first + j)].v;
      w += copies_[static_cast<std::size_t>(sp.first + j)].w;
    }
    const float share = 1.0f / static_cast<float>(sp.copies);
    bodies[static_cast<std::size_t>(sp.slot)].v = v * share;
    bodies[static_cast<std::size_t>(sp.slot)].w = w * share;
  }
}

void SurfaceBatches::writeImpulses(float* impulses) const {
  for (const Batch& b : batches_)
    for (int k = 0; k < 4; ++k)
      if (b.row[k] >= 0) impulses[b.row[k]] = b.impulse[k];
}

#if defined(__SSE__)
namespace {
// SolverBody starts with (v, invMass) and (w, pad): one unaligned load each per lane, and a
// 4x4 transpose turns four bodies into x, y, z (and invMass) registers.
struct LaneBodies {
  __m128 vx, vy, vz, invMass, wx, wy, wz, pad;
  void load(float* const p[4]) {
    vx = _mm_loadu_ps(p[0]);
    vy = _mm_loadu_ps(p[1]);
    vz = _mm_loadu_ps(p[2]);
    invMass = _mm_loadu_ps(p[3]);
    _MM_TRANSPOSE4_PS(vx, vy, vz, invMass);
    wx = _mm_loadu_ps(p[0] + 4);
    wy = _mm_loadu_ps(p[1] + 4);
    wz = _mm_loadu_ps(p[2] + 4);
    pad = _mm_loadu_ps(p[3] + 4);
    _MM_TRANSPOSE4_PS(wx, wy, wz, pad);
  }
  // Padding lanes share the dummy slot; their values never change, so any store order works.
  void store(float* const p[4]) const {
    __m128 a = vx, b = vy, c = vz, d = invMass;
    _MM_TRANSPOSE4_PS(a, b, c, d);
    _mm_storeu_ps(p[0], a);
    _mm_storeu_ps(p[1], b);
    _mm_storeu_ps(p[2], c);
    _mm_storeu_ps(p[3], d);
    a = wx, b = wy, c = wz, d = pad;
    _MM_TRANSPOSE4_PS(a, b, c, d);
    _mm_storeu_ps(p[0] + 4, a);
    _mm_storeu_ps(p[1] + 4, b);
    _mm_storeu_ps(p[2] + 4, c);
    _mm_storeu_ps(p[3] + 4, d);
  }
};
}  // namespace

// Each lane of the sweep runs down its column, mostly on one slot for many batches in a
// row: the four bodies stay in registers and are written back (and the next four read)
// only when some lane moves to another slot. The chain through a body's velocity is then
// the row arithmetic alone; the impulse's clamp target is formed off that chain.
void SurfaceBatches::solve(std::vector<SolverBody>& bodies, bool useBias) {
  static_assert(offsetof(SolverBody, invMass) == 12 && offsetof(SolverBody, w) == 16);
  if (batches_.empty()) return;
  beginCopies(bodies);
  float* p[4];
  __m128i slots = _mm_load_si128(reinterpret_cast<const __m128i*>(batches_[0].slot));
  for (int k = 0; k < 4; ++k) p[k] = laneBody(bodies, batches_[0].slot[k]);
  LaneBodies lane;
  lane.load(p);
  for (Batch& b : batches_) {
    const __m128i next = _mm_load_si128(reinterpret_cast<const __m128i*>(b.slot));
    if (_mm_movemask_epi8(_mm_cmpeq_epi32(next, slots)) != 0xFFFF) {
      lane.store(p);
      for (int k = 0; k < 4; ++k) p[k] = laneBody(bodies, b.slot[k]);
      lane.load(p);
      slots = next;
    }
    const __m128 effMass = _mm_load_ps(b.effMass);
    const __m128 old = _mm_load_ps(b.impulse);
    // old - effMass bias: independent of the velocities, so not on the chain.
    const __m128 base =
        _mm_sub_ps(old, _mm_mul_ps(effMass, _mm_load_ps(useBias ? b.bias : b.relaxBias)));
    const __m128 jv = _mm_add_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(_mm_load_ps(b.nx), lane.vx),
                                                       _mm_mul_ps(_mm_load_ps(b.ny), lane.vy)),
                                            _mm_mul_ps(_mm_load_ps(b.nz), lane.vz)),
                                 _mm_add_ps(_mm_add_ps(_mm_mul_ps(_mm_load_ps(b.ax), lane.wx),
                                                       _mm_mul_ps(_mm_load_ps(b.ay), lane.wy)),
                                            _mm_mul_ps(_mm_load_ps(b.az), lane.wz)));
    const __m128 clamped =
        _mm_min_ps(_mm_max_ps(_mm_sub_ps(base, _mm_mul_ps(effMass, jv)), _mm_load_ps(b.lower)),
                   _mm_load_ps(b.upper));
    _mm_store_ps(b.impulse, clamped);
    const __m128 d = _mm_sub_ps(clamped, old);
    lane.vx = _mm_add_ps(lane.vx, _mm_mul_ps(d, _mm_load_ps(b.ux)));
    lane.vy = _mm_add_ps(lane.vy, _mm_mul_ps(d, _mm_load_ps(b.uy)));
    lane.vz = _mm_add_ps(lane.vz, _mm_mul_ps(d, _mm_load_ps(b.uz)));
    lane.wx = _mm_add_ps(lane.wx, _mm_mul_ps(d, _mm_load_ps(b.ix)));
    lane.wy = _mm_add_ps(lane.wy, _mm_mul_ps(d, _mm_load_ps(b.iy)));
    lane.wz = _mm_add_ps(lane.wz, _mm_mul_ps(d, _mm_load_ps(b.iz)));
  }
  lane.store(p);
  endCopies(bodies);
}
#else
void SurfaceBatches::solve(std::vector<SolverBody>& bodies, bool useBias) {
  beginCopies(bodies);
  for (Batch& b : batches_) {
    for (int k = 0; k < 4; ++k) {
      SolverBody& body = *reinterpret_cast<SolverBody*>(laneBody(bodies, b.slot[k]));
      const Vec3 n(b.nx[k], b.ny[k], b.nz[k]);
      const float jv = n.dot(body.v) + Vec3(b.ax[k], b.ay[k], b.az[k]).dot(body.w);
      const float old = b.impulse[k];
      const float base = old - b.effMass[k] * (useBias ? b.bias[k] : b.relaxBias[k]);
      const float clamped = std::min(std::max(base - b.effMass[k] * jv, b.lower[k]), b.upper[k]);
      const float d = clamped - old;
      b.impulse[k] = clamped;
      body.v += d * Vec3(b.ux[k], b.uy[k], b.uz[k]);
      body.w += d * Vec3(b.ix[k], b.iy[k], b.iz[k]);
    }
  }
  endCopies(bodies);
}
#endif

#if defined(DYNAHAND_SWEEP_AVX)
namespace {
const bool kHasAvx = cpuHasAvx();

// A field of two batches as one register: a's four lanes low, b's high.
__attribute__((target("avx"))) inline __m256 load(const float (&fa)[4], const float (&fb)[4]) {
  return _mm256_set_m128(_mm_load_ps(fb), _mm_load_ps(fa));
}

// Four bodies of each sweep (loaded and stored through LaneBodies): lanes 0-3 are sweep a's,
// 4-7 sweep b's.
struct alignas(32) PairedLaneBodies {
  __m256 vx, vy, vz, wx, wy, wz;
  __m128 invMass[2], pad[2];  // kept only to be written back

  __attribute__((target("avx"))) void loadHalf(int half, float* const p[4]) {
    LaneBodies four;
    four.load(p);
    invMass[half] = four.invMass;
    pad[half] = four.pad;
    if (half == 0) {
      vx = _mm256_insertf128_ps(vx, four.vx, 0), vy = _mm256_insertf128_ps(vy, four.vy, 0);
      vz = _mm256_insertf128_ps(vz, four.vz, 0), wx = _mm256_insertf128_ps(wx, four.wx, 0);
      wy = _mm256_insertf128_ps(wy, four.wy, 0), wz = _mm256_insertf128_ps(wz, four.wz, 0);
    } else {
      vx = _mm256_insertf128_ps(vx, four.vx, 1), vy = _mm256_insertf128_ps(vy, four.vy, 1);
      vz = _mm256_insertf128_ps(vz, four.vz, 1), wx = _mm256_insertf128_ps(wx, four.wx, 1);
      wy = _mm256_insertf128_ps(wy, four.wy, 1), wz = _mm256_insertf128_ps(wz, four.wz, 1);
    }
  }
  __attribute__((target("avx"))) void storeHalf(int half, float* const p[4]) const {
    LaneBodies four;
    if (half == 0) {
      four.vx = _mm256_castps256_ps128(vx), four.vy = _mm256_castps256_ps128(vy);
      four.vz = _mm256_castps256_ps128(vz), four.wx = _mm256_castps256_ps128(wx);
      four.wy = _mm256_castps256_ps128(wy), four.wz = _mm256_castps256_ps128(wz);
    } else {
      four.vx = _mm256_extractf128_ps(vx, 1), four.vy = _mm256_extractf128_ps(vy, 1);
      four.vz = _mm256_extractf128_ps(vz, 1), four.wx = _mm256_extractf128_ps(wx, 1);
      four.wy = _mm256_extractf128_ps(wy, 1), four.wz = _mm256_extractf128_ps(wz, 1);
    }
    four.invMass = invMass[half];
    four.pad = pad[half];
    four.store(p);
  }
};
}  // namespace

bool SurfaceBatches::canSolveTogether() {
  return kHasAvx;
}

__attribute__((target("avx"))) void SurfaceBatches::solveTogether(SurfaceBatches& a,
                                                                  std::vector<SolverBody>& bodiesA,
                                                                  SurfaceBatches& b,
                                                                  std::vector<SolverBody>& bodiesB,
                                                                  bool useBias) {
  if (!kHasAvx || a.batches_.empty() || b.batches_.empty()) {
    a.solve(bodiesA, useBias);
    b.solve(bodiesB, useBias);
    return;
  }
  a.beginCopies(bodiesA);
  b.beginCopies(bodiesB);
  SurfaceBatches* sweep[2] = {&a, &b};
  std::vector<SolverBody>* bodies[2] = {&bodiesA, &bodiesB};
  // The shorter sweep runs out first: its lanes then solve a padding batch (every lane on its
  // dummy slot, all zero), which changes nothing.
  Batch padding[2]{};
  for (int h = 0; h < 2; ++h) {
    for (int k = 0; k < 4; ++k) {
      padding[h].slot[k] = sweep[h]->dummySlot_;
      padding[h].row[k] = -1;
    }
  }
  const std::size_t count[2] = {a.batches_.size(), b.batches_.size()};
  const std::size_t total = std::max(count[0], count[1]);
  auto batchOf = [&](int h, std::size_t i) -> Batch& {
    return i < count[h] ? sweep[h]->batches_[i] : padding[h];
  };
  float* p[2][4];
  __m128i slots[2];
  PairedLaneBodies lane;
  lane.vx = lane.vy = lane.vz = lane.wx = lane.wy = lane.wz = _mm256_setzero_ps();
  for (int h = 0; h < 2; ++h) {
    const Batch& first = batchOf(h, 0);
    slots[h] = _mm_load_si128(reinterpret_cast<const __m128i*>(first.slot));
    for (int k = 0; k < 4; ++k) p[h][k] = sweep[h]->laneBody(*bodies[h], first.slot[k]);
    lane.loadHalf(h, p[h]);
  }
  for (std::size_t i = 0; i < total; ++i) {
    Batch& ba = batchOf(0, i);
    Batch& bb = batchOf(1, i);
    Batch* batch[2] = {&ba, &bb};
    for (int h = 0; h < 2; ++h) {
      const __m128i next = _mm_load_si128(reinterpret_cast<const __m128i*>(batch[h]->slot));
      if (_mm_movemask_epi8(_mm_cmpeq_epi32(next, slots[h])) != 0xFFFF) {
        lane.storeHalf(h, p[h]);
        for (int k = 0; k < 4; ++k) p[h][k] = sweep[h]->laneBody(*bodies[h], batch[h]->slot[k]);
        lane.loadHalf(h, p[h]);
        slots[h] = next;
      }
    }
    // solve()'s arithmetic, lane for lane.
    const __m256 effMass = load(ba.effMass, bb.effMass);
    const __m256 old = load(ba.impulse, bb.impulse);
    const __m256 base =
        _mm256_sub_ps(old, _mm256_mul_ps(effMass, useBias ? load(ba.bias, bb.bias)
                                                          : load(ba.relaxBias, bb.relaxBias)));
    const __m256 jv =
        _mm256_add_ps(_mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(load(ba.nx, bb.nx), lane.vx),
                                                  _mm256_mul_ps(load(ba.ny, bb.ny), lane.vy)),
                                    _mm256_mul_ps(load(ba.nz, bb.nz), lane.vz)),
                      _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(load(ba.ax, bb.ax), lane.wx),
                                                  _mm256_mul_ps(load(ba.ay, bb.ay), lane.wy)),
                                    _mm256_mul_ps(load(ba.az, bb.az), lane.wz)));
    const __m256 clamped = _mm256_min_ps(
        _mm256_max_ps(_mm256_sub_ps(base, _mm256_mul_ps(effMass, jv)), load(ba.lower, bb.lower)),
        load(ba.upper, bb.upper));
    _mm_store_ps(ba.impulse, _mm256_castps256_ps128(clamped));
    _mm_store_ps(bb.impulse, _mm256_extractf128_ps(clamped, 1));
    const __m256 d = _mm256_sub_ps(clamped, old);
    lane.vx = _mm256_add_ps(lane.vx, _mm256_mul_ps(d, load(ba.ux, bb.ux)));
    lane.vy = _mm256_add_ps(lane.vy, _mm256_mul_ps(d, load(ba.uy, bb.uy)));
    lane.vz = _mm256_add_ps(lane.vz, _mm256_mul_ps(d, load(ba.uz, bb.uz)));
    lane.wx = _mm256_add_ps(lane.wx, _mm256_mul_ps(d, load(ba.ix, bb.ix)));
    lane.wy = _mm256_add_ps(lane.wy, _mm256_mul_ps(d, load(ba.iy, bb.iy)));
    lane.wz = _mm256_add_ps(lane.wz, _mm256_mul_ps(d, load(ba.iz, bb.iz)));
  }
  lane.storeHalf(0, p[0]);
  lane.storeHalf(1, p[1]);
  a.endCopies(bodiesA);
  b.endCopies(bodiesB);
}
#else
bool SurfaceBatches::canSolveTogether() {
  return false;
}

void SurfaceBatches::solveTogether(SurfaceBatches& a, std::vector<SolverBody>& bodiesA,
                                   SurfaceBatches& b, std::vector<SolverBody>& bodiesB,
                                   bool useBias) {
  a.solve(bodiesA, useBias);
  b.solve(bodiesB, useBias);
}
#endif

}  // namespace dynahand::physics
