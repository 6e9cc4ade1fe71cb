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

inline void SurfaceBatches::place(Batch& b, int k, const PreparedSurfaceRow& r, int row,
                                  const std::vector<SolverBody>& bodies) {
  b.slot[k] = virtualSlot_[static_cast<std::size_t>(row)];
  b.row[k] = row;
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
  // The rows are dealt, slot after slot, down the columns of a (batches x 8) table: a slot's
  // run is at most `batchCount` long, so its rows land in different batches, and each lane of
  // the sweep stays on one slot for a long run of batches (the sweep keeps that slot's
  // velocities in registers until the lane moves on). A run that reaches a column's end wraps
  // to the next column's top, and is solved from there: rows are placed so that each slot
  // still sees its rows in the order below.
  //
  // Each slot's order: its rows (in input order, i.e. scanline order of the points) taken
  // every kSpread-th, so that Gauss-Seidel alternates between parts of the body instead of
  // sweeping it from one side to the other; then rotated where the same dealing into a table
  // four wide wraps. Four was the sweep's width before session 14; keeping its order keeps
  // the results bit for bit (the rotation itself means nothing).
  constexpr int kOrderLanes = 4;
  const int orderBatches = std::max((n + kOrderLanes - 1) / kOrderLanes, largest);
  const int batchCount = std::max((n + kLanes - 1) / kLanes, largest);
  batches_.resize(static_cast<std::size_t>(batchCount));
  cellRow_.assign(static_cast<std::size_t>(batchCount) * kLanes, -1);
  // Rows from `position` on, `length` of them, wrap in a table `height` batches high after
  // the returned count (length when they do not wrap).
  auto wrapAfter = [](int position, int length, int height) {
    const int room = height - position % height;
    return room < length ? room : length;
  };
  int position = 0;  // cell in the table, counted down the columns
  for (const int slot : slotsByCount_) {
    const int first = start_[static_cast<std::size_t>(slot)];
    const int end = start_[static_cast<std::size_t>(slot) + 1];
    const int length = end - first;
    if (length == 0) continue;
    spread_.clear();
    for (int residue = 0; residue < kSpread; ++residue)
      for (int o = first + residue; o < end; o += kSpread)
        spread_.push_back(order_[static_cast<std::size_t>(o)]);
    // The slot's k-th row is spread_[(k + turn) % length]; cell `position + j` is solved
    // k-th with k = j - split for j >= split (the wrapped part, at the next column's top,
    // comes first), else k = j - split + length.
    const int wrap4 = wrapAfter(position, length, orderBatches);
    const int turn = wrap4 < length ? wrap4 : 0;
    const int split = wrapAfter(position, length, batchCount);
    const int rank = split < length ? length - split : 0;  // of cell `position`
    int at = rank + turn >= length ? rank + turn - length : rank + turn;
    for (int j = 0; j < length; ++j) {
      cellRow_[static_cast<std::size_t>(position + j)] = spread_[static_cast<std::size_t>(at)];
      if (++at == length) at = 0;
    }
    position += length;
  }
  // Filled batch after batch (row after row would write each batch's eight cache lines
  // once per row). Cells left over are padding on the dummy slot, all zero: they never act.
  for (int column = 0; column < batchCount; ++column) {
    Batch& b = batches_[static_cast<std::size_t>(column)];
    for (int lane = 0; lane < kLanes; ++lane) {
      const int i = cellRow_[static_cast<std::size_t>(lane * batchCount + column)];
      if (i >= 0) {
        place(b, lane, rows[static_cast<std::size_t>(i)], i, bodies);
        continue;
      }
      b.slot[lane] = dummySlot;
      b.row[lane] = -1;
      b.nx[lane] = b.ny[lane] = b.nz[lane] = b.ax[lane] = b.ay[lane] = b.az[lane] = 0.0f;
      b.ix[lane] = b.iy[lane] = b.iz[lane] = 0.0f;
      b.ux[lane] = b.uy[lane] = b.uz[lane] = 0.0f;
      b.effMass[lane] = b.bias[lane] = b.relaxBias[lane] = b.lower[lane] = b.upper[lane] = 0.0f;
      b.impulse[lane] = 0.0f;
    }
  }
  reload_.assign(static_cast<std::size_t>(batchCount), 0);
  for (std::size_t i = 1; i < batches_.size(); ++i)
    reload_[i] = !std::equal(batches_[i].slot, batches_[i].slot + kLanes, batches_[i - 1].slot);
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
    for (int k = 0; k < kLanes; ++k)
      if (b.row[k] >= 0) impulses[b.row[k]] = b.impulse[k];
}

void SurfaceBatches::solveFallback(std::vector<SolverBody>& bodies, bool useBias) {
  beginCopies(bodies);
  for (Batch& b : batches_) {
    for (int k = 0; k < kLanes; ++k) {
      SolverBody& body = *reinterpret_cast<SolverBody*>(laneBody(bodies, b.slot[k]));
      // Summed as the vector paths sum: (x + y) + z.
      const float jv = ((b.nx[k] * body.v.x() + b.ny[k] * body.v.y()) + b.nz[k] * body.v.z()) +
                       ((b.ax[k] * body.w.x() + b.ay[k] * body.w.y()) + b.az[k] * body.w.z());
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

#if defined(DYNAHAND_SWEEP_AVX)
namespace {
const bool kHasAvx = cpuHasAvx();

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

// The eight bodies of a batch's lanes, velocities in registers (lanes 0-3 low, 4-7 high).
struct alignas(32) EightBodies {
  __m256 vx, vy, vz, wx, wy, wz;
  __m128 invMass[2], pad[2];  // kept only to be written back

  __attribute__((target("avx"))) void load(float* const p[8]) {
    LaneBodies low, high;
    low.load(p);
    high.load(p + 4);
    vx = _mm256_set_m128(high.vx, low.vx), vy = _mm256_set_m128(high.vy, low.vy);
    vz = _mm256_set_m128(high.vz, low.vz), wx = _mm256_set_m128(high.wx, low.wx);
    wy = _mm256_set_m128(high.wy, low.wy), wz = _mm256_set_m128(high.wz, low.wz);
    invMass[0] = low.invMass, invMass[1] = high.invMass;
    pad[0] = low.pad, pad[1] = high.pad;
  }
  __attribute__((target("avx"))) void store(float* const p[8]) const {
    LaneBodies low, high;
    low.vx = _mm256_castps256_ps128(vx), low.vy = _mm256_castps256_ps128(vy);
    low.vz = _mm256_castps256_ps128(vz), low.wx = _mm256_castps256_ps128(wx);
    low.wy = _mm256_castps256_ps128(wy), low.wz = _mm256_castps256_ps128(wz);
    high.vx = _mm256_extractf128_ps(vx, 1), high.vy = _mm256_extractf128_ps(vy, 1);
    high.vz = _mm256_extractf128_ps(vz, 1), high.wx = _mm256_extractf128_ps(wx, 1);
    high.wy = _mm256_extractf128_ps(wy, 1), high.wz = _mm256_extractf128_ps(wz, 1);
    low.invMass = invMass[0], high.invMass = invMass[1];
    low.pad = pad[0], high.pad = pad[1];
    low.store(p);
    high.store(p + 4);
  }
};

// One batch's rows, lane for lane the fallback's arithmetic (a template only so that it
// need not name the private batch type). The chain through a body's velocity is the row
// arithmetic alone; the clamp's target is formed off that chain.
template <class Batch>
__attribute__((target("avx"), always_inline)) inline void solveBatch(Batch& b, EightBodies& lane,
                                                                     bool useBias) {
  const __m256 effMass = _mm256_load_ps(b.effMass);
  const __m256 old = _mm256_load_ps(b.impulse);
  const __m256 base =
      _mm256_sub_ps(old, _mm256_mul_ps(effMass, _mm256_load_ps(useBias ? b.bias : b.relaxBias)));
  const __m256 jv =
      _mm256_add_ps(_mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(_mm256_load_ps(b.nx), lane.vx),
                                                _mm256_mul_ps(_mm256_load_ps(b.ny), lane.vy)),
                                  _mm256_mul_ps(_mm256_load_ps(b.nz), lane.vz)),
                    _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(_mm256_load_ps(b.ax), lane.wx),
                                                _mm256_mul_ps(_mm256_load_ps(b.ay), lane.wy)),
                                  _mm256_mul_ps(_mm256_load_ps(b.az), lane.wz)));
  const __m256 clamped = _mm256_min_ps(
      _mm256_max_ps(_mm256_sub_ps(base, _mm256_mul_ps(effMass, jv)), _mm256_load_ps(b.lower)),
      _mm256_load_ps(b.upper));
  _mm256_store_ps(b.impulse, clamped);
  const __m256 d = _mm256_sub_ps(clamped, old);
  lane.vx = _mm256_add_ps(lane.vx, _mm256_mul_ps(d, _mm256_load_ps(b.ux)));
  lane.vy = _mm256_add_ps(lane.vy, _mm256_mul_ps(d, _mm256_load_ps(b.uy)));
  lane.vz = _mm256_add_ps(lane.vz, _mm256_mul_ps(d, _mm256_load_ps(b.uz)));
  lane.wx = _mm256_add_ps(lane.wx, _mm256_mul_ps(d, _mm256_load_ps(b.ix)));
  lane.wy = _mm256_add_ps(lane.wy, _mm256_mul_ps(d, _mm256_load_ps(b.iy)));
  lane.wz = _mm256_add_ps(lane.wz, _mm256_mul_ps(d, _mm256_load_ps(b.iz)));
}
}  // namespace

bool SurfaceBatches::canSolveTogether() {
  return kHasAvx;
}

// Each lane runs down its column, mostly on one slot for many batches in a row: the eight
// bodies stay in registers and are written back (and the next eight read) only when some
// lane moves to another slot.
__attribute__((target("avx"))) void SurfaceBatches::solve(std::vector<SolverBody>& bodies,
                                                          bool useBias) {
  static_assert(offsetof(SolverBody, invMass) == 12 && offsetof(SolverBody, w) == 16);
  if (!kHasAvx) {
    solveFallback(bodies, useBias);
    return;
  }
  if (batches_.empty()) return;
  beginCopies(bodies);
  float* p[kLanes];
  for (int k = 0; k < kLanes; ++k) p[k] = laneBody(bodies, batches_[0].slot[k]);
  EightBodies lane;
  lane.load(p);
  for (std::size_t i = 0; i < batches_.size(); ++i) {
    Batch& b = batches_[i];
    if (reload_[i]) {
      lane.store(p);
      for (int k = 0; k < kLanes; ++k) p[k] = laneBody(bodies, b.slot[k]);
      lane.load(p);
    }
    solveBatch(b, lane, useBias);
  }
  lane.store(p);
  endCopies(bodies);
}

// solveTogether's loop. Two sweeps' lanes take twelve vector registers: AVX's sixteen leave
// too few for the rest, and the spills land on the velocity chains, so where the CPU has
// AVX-512VL (thirty-two) the loop is compiled for that too (the same operations, so the same
// bits; contraction into FMA is off in every build).
struct SurfaceSweeps {
  __attribute__((target("avx"), always_inline)) static inline void sideBySide(
      SurfaceBatches& a, std::vector<SolverBody>& bodiesA, SurfaceBatches& b,
      std::vector<SolverBody>& bodiesB, bool useBias) {
    using Batch = SurfaceBatches::Batch;
    constexpr int kLanes = SurfaceBatches::kLanes;
    // The longer sweep first: once the shorter one ends, the longer goes on alone.
    const bool swap = b.batches_.size() > a.batches_.size();
    SurfaceBatches& longer = swap ? b : a;
    SurfaceBatches& shorter = swap ? a : b;
    std::vector<SolverBody>& bodiesL = swap ? bodiesB : bodiesA;
    std::vector<SolverBody>& bodiesS = swap ? bodiesA : bodiesB;
    longer.beginCopies(bodiesL);
    shorter.beginCopies(bodiesS);
    float* pl[kLanes];
    float* ps[kLanes];
    for (int k = 0; k < kLanes; ++k) {
      pl[k] = longer.laneBody(bodiesL, longer.batches_[0].slot[k]);
      ps[k] = shorter.laneBody(bodiesS, shorter.batches_[0].slot[k]);
    }
    EightBodies laneL, laneS;
    laneL.load(pl);
    laneS.load(ps);
    const std::size_t common = shorter.batches_.size();
    for (std::size_t i = 0; i < common; ++i) {
      Batch& bl = longer.batches_[i];
      Batch& bs = shorter.batches_[i];
      if (longer.reload_[i]) {
        laneL.store(pl);
        for (int k = 0; k < kLanes; ++k) pl[k] = longer.laneBody(bodiesL, bl.slot[k]);
        laneL.load(pl);
      }
      if (shorter.reload_[i]) {
        laneS.store(ps);
        for (int k = 0; k < kLanes; ++k) ps[k] = shorter.laneBody(bodiesS, bs.slot[k]);
        laneS.load(ps);
      }
      solveBatch(bl, laneL, useBias);
      solveBatch(bs, laneS, useBias);
    }
    laneS.store(ps);
    shorter.endCopies(bodiesS);
    for (std::size_t i = common; i < longer.batches_.size(); ++i) {
      Batch& bl = longer.batches_[i];
      if (longer.reload_[i]) {
        laneL.store(pl);
        for (int k = 0; k < kLanes; ++k) pl[k] = longer.laneBody(bodiesL, bl.slot[k]);
        laneL.load(pl);
      }
      solveBatch(bl, laneL, useBias);
    }
    laneL.store(pl);
    longer.endCopies(bodiesL);
  }
};

namespace {
const bool kHasAvx512vl = cpuHasAvx512vl();

__attribute__((target("avx"))) void sideBySideAvx(SurfaceBatches& a,
                                                  std::vector<SolverBody>& bodiesA,
                                                  SurfaceBatches& b,
                                                  std::vector<SolverBody>& bodiesB, bool useBias) {
  SurfaceSweeps::sideBySide(a, bodiesA, b, bodiesB, useBias);
}

__attribute__((target("avx512f,avx512vl"))) void sideBySideAvx512(SurfaceBatches& a,
                                                                  std::vector<SolverBody>& bodiesA,
                                                                  SurfaceBatches& b,
                                                                  std::vector<SolverBody>& bodiesB,
                                                                  bool useBias) {
  SurfaceSweeps::sideBySide(a, bodiesA, b, bodiesB, useBias);
}
}  // namespace

void SurfaceBatches::solveTogether(SurfaceBatches& a, std::vector<SolverBody>& bodiesA,
                                   SurfaceBatches& b, std::vector<SolverBody>& bodiesB,
                                   bool useBias) {
  if (!kHasAvx || a.batches_.empty() || b.batches_.empty()) {
    a.solve(bodiesA, useBias);
    b.solve(bodiesB, useBias);
    return;
  }
  if (kHasAvx512vl)
    sideBySideAvx512(a, bodiesA, b, bodiesB, useBias);
  else
    sideBySideAvx(a, bodiesA, b, bodiesB, useBias);
}
#else
bool SurfaceBatches::canSolveTogether() {
  return false;
}

void SurfaceBatches::solve(std::vector<SolverBody>& bodies, bool useBias) {
  solveFallback(bodies, useBias);
}

void SurfaceBatches::solveTogether(SurfaceBatches& a, std::vector<SolverBody>& bodiesA,
                                   SurfaceBatches& b, std::vector<SolverBody>& bodiesB,
                                   bool useBias) {
  a.solve(bodiesA, useBias);
  b.solve(bodiesB, useBias);
}
#endif

}  // namespace dynahand::physics
