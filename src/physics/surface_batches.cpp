#include "physics/surface_batches.h"

#include "core/cpu_features.h"
#include "physics/world_impl.h"

#include <algorithm>
#include <atomic>
#include <cassert>
#include <cstddef>
#include <numeric>

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#define DYNAHAND_SWEEP_AVX 1
#endif

namespace dynahand::physics {
namespace {
constexpr int kSpread = 4;
// The width of the table that fixes each slot's row order and the mass splitting: four, the
// width the tracker's tuning was done with (the sweeps themselves are eight wide).
constexpr int kOrderLanes = 4;
constexpr int kMinRowsToSplit = 32;  // fewer rows on one slot are never split
}  // namespace

void SurfaceBatches::reserve(int rows) {
  const auto n = static_cast<std::size_t>(rows);
  // A batch per eight rows, or per row of the largest slot (at most a quarter of them).
  const std::size_t batches = n / 4 + 1;
  batches_.reserve(batches);
  lanes_.reserve(batches);
  changed_.reserve(batches);
  cellRow_.reserve(batches * kLanes);
  order_.reserve(n);
  spread_.reserve(n);
}

namespace {
#if defined(DYNAHAND_SWEEP_AVX)
const bool kHasAvx = cpuHasAvx();
#else
constexpr bool kHasAvx = false;
#endif

// A batch's fields from its eight rows (padding lanes: an all-zero row) and the lanes'
// copies (1 for an unsplit slot): a copy holds 1/copies of its slot's mass, so inverse
// inertia times copies and effective mass over copies (exactly the row's own values for
// copies = 1); the inverse mass is applied in the sweep (massScale_). A template only so that
// it need not name the private batch type.
template <class Batch>
void fillBatch(Batch& b, const PreparedSurfaceRow* const* rows, const float* copies) {
  for (int k = 0; k < 8; ++k) {
    const PreparedSurfaceRow& r = *rows[k];
    b.nx[k] = r.normal.x();
    b.ny[k] = r.normal.y();
    b.nz[k] = r.normal.z();
    b.ax[k] = r.ang.x();
    b.ay[k] = r.ang.y();
    b.az[k] = r.ang.z();
    b.ix[k] = r.invIAng.x() * copies[k];
    b.iy[k] = r.invIAng.y() * copies[k];
    b.iz[k] = r.invIAng.z() * copies[k];
    b.effMass[k] = r.effMass / copies[k];
    b.bias[k] = r.bias;
    b.relaxBias[k] = r.relaxBias;
    b.lower[k] = r.lower;
    b.upper[k] = r.upper;
    b.impulse[k] = 0.0f;
  }
}

#if defined(DYNAHAND_SWEEP_AVX)
// r[k] = eight floats of row k -> r[f] = float f of the eight rows.
__attribute__((target("avx"), always_inline)) inline void transpose8(__m256 (&r)[8]) {
  const __m256 t0 = _mm256_unpacklo_ps(r[0], r[1]), t1 = _mm256_unpackhi_ps(r[0], r[1]);
  const __m256 t2 = _mm256_unpacklo_ps(r[2], r[3]), t3 = _mm256_unpackhi_ps(r[2], r[3]);
  const __m256 t4 = _mm256_unpacklo_ps(r[4], r[5]), t5 = _mm256_unpackhi_ps(r[4], r[5]);
  const __m256 t6 = _mm256_unpacklo_ps(r[6], r[7]), t7 = _mm256_unpackhi_ps(r[6], r[7]);
  const __m256 s0 = _mm256_shuffle_ps(t0, t2, 0x44), s1 = _mm256_shuffle_ps(t0, t2, 0xEE);
  const __m256 s2 = _mm256_shuffle_ps(t1, t3, 0x44), s3 = _mm256_shuffle_ps(t1, t3, 0xEE);
  const __m256 s4 = _mm256_shuffle_ps(t4, t6, 0x44), s5 = _mm256_shuffle_ps(t4, t6, 0xEE);
  const __m256 s6 = _mm256_shuffle_ps(t5, t7, 0x44), s7 = _mm256_shuffle_ps(t5, t7, 0xEE);
  r[0] = _mm256_permute2f128_ps(s0, s4, 0x20);
  r[1] = _mm256_permute2f128_ps(s1, s5, 0x20);
  r[2] = _mm256_permute2f128_ps(s2, s6, 0x20);
  r[3] = _mm256_permute2f128_ps(s3, s7, 0x20);
  r[4] = _mm256_permute2f128_ps(s0, s4, 0x31);
  r[5] = _mm256_permute2f128_ps(s1, s5, 0x31);
  r[6] = _mm256_permute2f128_ps(s2, s6, 0x31);
  r[7] = _mm256_permute2f128_ps(s3, s7, 0x31);
}

// fillBatch with two 8x8 transposes: a row's fourteen floats (normal ... upper, bytes 4-60)
// are read as floats 0-7 and 6-13. The same operations per value, so the same bits.
template <class Batch>
__attribute__((target("avx"))) void fillBatchAvx(Batch& b, const PreparedSurfaceRow* const* rows,
                                                 const float* copies) {
  static_assert(sizeof(PreparedSurfaceRow) == 60, "slot, then fourteen floats");
  __m256 first[8], second[8];
  for (int k = 0; k < 8; ++k) {
    const float* f = reinterpret_cast<const float*>(rows[k]) + 1;
    first[k] = _mm256_loadu_ps(f);
    second[k] = _mm256_loadu_ps(f + 6);
  }
  transpose8(first);
  transpose8(second);
  const __m256 c = _mm256_loadu_ps(copies);
  _mm256_store_ps(b.nx, first[0]);
  _mm256_store_ps(b.ny, first[1]);
  _mm256_store_ps(b.nz, first[2]);
  _mm256_store_ps(b.ax, first[3]);
  _mm256_store_ps(b.ay, first[4]);
  _mm256_store_ps(b.az, first[5]);
  _mm256_store_ps(b.ix, _mm256_mul_ps(second[0], c));
  _mm256_store_ps(b.iy, _mm256_mul_ps(second[1], c));
  _mm256_store_ps(b.iz, _mm256_mul_ps(second[2], c));
  _mm256_store_ps(b.effMass, _mm256_div_ps(second[3], c));
  _mm256_store_ps(b.bias, second[4]);
  _mm256_store_ps(b.relaxBias, second[5]);
  _mm256_store_ps(b.lower, second[6]);
  _mm256_store_ps(b.upper, second[7]);
  _mm256_store_ps(b.impulse, _mm256_setzero_ps());
}
#endif
}  // namespace

void SurfaceBatches::build(const std::vector<PreparedSurfaceRow>& rows,
                           const std::vector<SolverBody>& bodies, int dummySlot) {
  slotCount_ = static_cast<int>(bodies.size());
  const int n = static_cast<int>(rows.size());
  const auto slots = static_cast<std::size_t>(assignSolvingSlots(rows));
  const int largest = groupRowsBySlot(n, slots);
  const int batchCount = dealIntoTable(n, largest);
  fillBatches(rows, batchCount, dummySlot);
}

int SurfaceBatches::assignSolvingSlots(const std::vector<PreparedSurfaceRow>& rows) {
  const int n = static_cast<int>(rows.size());
  // Slots with more than a quarter of the rows are split (see the header), but not small
  // sets: a few rows solve as well in sequence, and Gauss-Seidel converges faster. (A quarter:
  // kOrderLanes, and the split decides the results.)
  const int target = std::max(1, (n + kOrderLanes - 1) / kOrderLanes);
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
  massScale_.assign(static_cast<std::size_t>(slotCountAll), 1.0f);
  for (const Split& sp : splits_)
    for (int j = 0; j < sp.copies; ++j)
      massScale_[static_cast<std::size_t>(slotCount_ + sp.first + j)] =
          static_cast<float>(sp.copies);
  return slotCountAll;
}

int SurfaceBatches::groupRowsBySlot(int n, std::size_t slots) {
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
  return largest;
}

int SurfaceBatches::dealIntoTable(int n, int largest) {
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
  // kOrderLanes wide wraps: the order the tracker was tuned with (the rotation itself means
  // nothing).
  const int orderBatches = std::max((n + kOrderLanes - 1) / kOrderLanes, largest);
  const int batchCount = std::max((n + kLanes - 1) / kLanes, largest);
  batches_.resize(static_cast<std::size_t>(batchCount));
  lanes_.resize(static_cast<std::size_t>(batchCount));
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
  return batchCount;
}

void SurfaceBatches::fillBatches(const std::vector<PreparedSurfaceRow>& rows, int batchCount,
                                 int dummySlot) {
  // Filled batch after batch (row after row would write each batch's eight cache lines
  // once per row). Cells left over are padding on the dummy slot, all zero: they never act.
  static const PreparedSurfaceRow kPaddingRow{};
  const PreparedSurfaceRow* source[kLanes];
  alignas(32) float copies[kLanes];
  for (int batch = 0; batch < batchCount; ++batch) {
    BatchLanes& l = lanes_[static_cast<std::size_t>(batch)];
    for (int lane = 0; lane < kLanes; ++lane) {
      const int i = cellRow_[static_cast<std::size_t>(lane * batchCount + batch)];
      const PreparedSurfaceRow* r = i >= 0 ? &rows[static_cast<std::size_t>(i)] : &kPaddingRow;
      l.slot[lane] = i >= 0 ? virtualSlot_[static_cast<std::size_t>(i)] : dummySlot;
      l.row[lane] = i;
      source[lane] = r;
      copies[lane] = i >= 0 ? massScale_[static_cast<std::size_t>(l.slot[lane])] : 1.0f;
    }
#if defined(DYNAHAND_SWEEP_AVX)
    // Filled with AVX only when the sweep runs with it: the tests' switch turns off both.
    if (canSolveSideBySide()) {
      fillBatchAvx(batches_[static_cast<std::size_t>(batch)], source, copies);
      continue;
    }
#endif
    fillBatch(batches_[static_cast<std::size_t>(batch)], source, copies);
  }
  changed_.assign(static_cast<std::size_t>(batchCount), 0);
  for (std::size_t i = 1; i < batches_.size(); ++i)
    for (int k = 0; k < kLanes; ++k)
      if (lanes_[i].slot[k] != lanes_[i - 1].slot[k]) changed_[i] |= 1u << k;
}

SolverBody* SurfaceBatches::laneBody(std::vector<SolverBody>& bodies, int slot) {
  return slot < slotCount_ ? &bodies[static_cast<std::size_t>(slot)]
                           : &copies_[static_cast<std::size_t>(slot - slotCount_)];
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
  for (std::size_t i = 0; i < batches_.size(); ++i)
    for (int k = 0; k < kLanes; ++k)
      if (lanes_[i].row[k] >= 0) impulses[lanes_[i].row[k]] = batches_[i].impulse[k];
}

void SurfaceBatches::solveFallback(std::vector<SolverBody>& bodies, bool useBias) {
  beginCopies(bodies);
  for (std::size_t i = 0; i < batches_.size(); ++i) {
    Batch& b = batches_[i];
    for (int k = 0; k < kLanes; ++k) {
      const int slot = lanes_[i].slot[k];
      SolverBody& body = *laneBody(bodies, slot);
      // Summed as the vector paths sum: (x + y) + z.
      const float jv = ((b.nx[k] * body.v.x() + b.ny[k] * body.v.y()) + b.nz[k] * body.v.z()) +
                       ((b.ax[k] * body.w.x() + b.ay[k] * body.w.y()) + b.az[k] * body.w.z());
      const float old = b.impulse[k];
      const float base = old - b.effMass[k] * (useBias ? b.bias[k] : b.relaxBias[k]);
      // Clamped as the vector max and min do: equal values (+0 and -0) give the bound.
      const float target = base - b.effMass[k] * jv;
      const float raised = target > b.lower[k] ? target : b.lower[k];
      const float clamped = raised < b.upper[k] ? raised : b.upper[k];
      const float d = clamped - old;
      b.impulse[k] = clamped;
      const float invMass = body.invMass * massScale_[static_cast<std::size_t>(slot)];
      body.v += d * Vec3(b.nx[k] * invMass, b.ny[k] * invMass, b.nz[k] * invMass);
      body.w += d * Vec3(b.ix[k], b.iy[k], b.iz[k]);
    }
  }
  endCopies(bodies);
}

#if defined(DYNAHAND_SWEEP_AVX)
namespace {

// The bodies of a sweep's eight lanes, their velocities in registers. A lane changes body
// only where its column moves to the next slot (about one lane every sixth batch, rarely
// several at once), so lanes are written back and loaded one by one.
struct alignas(32) EightBodies {
  __m256 vx, vy, vz, wx, wy, wz;
  __m256 pull;  // the body's inverse mass x the lane's massScale_ (the normal's factor)

  // Lanes in `lanes` (a bit mask) write their velocities back to their bodies p[k].
  __attribute__((target("avx"), always_inline)) inline void writeBack(
      unsigned lanes, SolverBody* const p[8]) const {
    alignas(32) float t[6][8];
    _mm256_store_ps(t[0], vx);
    _mm256_store_ps(t[1], vy);
    _mm256_store_ps(t[2], vz);
    _mm256_store_ps(t[3], wx);
    _mm256_store_ps(t[4], wy);
    _mm256_store_ps(t[5], wz);
    for (; lanes != 0; lanes &= lanes - 1) {
      const int k = __builtin_ctz(lanes);
      SolverBody& body = *p[k];
      body.v = Vec3(t[0][k], t[1][k], t[2][k]);
      body.w = Vec3(t[3][k], t[4][k], t[5][k]);
    }
  }
  // Lane k takes `body`, whose rows pull with `scale` times its inverse mass.
  __attribute__((target("avx"), always_inline)) inline void loadLane(int k, const SolverBody& body,
                                                                     float scale) {
    alignas(32) static constexpr int kLaneMask[8][8] = {
        {-1, 0, 0, 0, 0, 0, 0, 0}, {0, -1, 0, 0, 0, 0, 0, 0}, {0, 0, -1, 0, 0, 0, 0, 0},
        {0, 0, 0, -1, 0, 0, 0, 0}, {0, 0, 0, 0, -1, 0, 0, 0}, {0, 0, 0, 0, 0, -1, 0, 0},
        {0, 0, 0, 0, 0, 0, -1, 0}, {0, 0, 0, 0, 0, 0, 0, -1}};
    const __m256 m = _mm256_load_ps(reinterpret_cast<const float*>(kLaneMask[k]));
    vx = _mm256_blendv_ps(vx, _mm256_broadcast_ss(&body.v.x()), m);
    vy = _mm256_blendv_ps(vy, _mm256_broadcast_ss(&body.v.y()), m);
    vz = _mm256_blendv_ps(vz, _mm256_broadcast_ss(&body.v.z()), m);
    wx = _mm256_blendv_ps(wx, _mm256_broadcast_ss(&body.w.x()), m);
    wy = _mm256_blendv_ps(wy, _mm256_broadcast_ss(&body.w.y()), m);
    wz = _mm256_blendv_ps(wz, _mm256_broadcast_ss(&body.w.z()), m);
    pull = _mm256_blendv_ps(pull, _mm256_set1_ps(body.invMass * scale), m);
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
  lane.vx =
      _mm256_add_ps(lane.vx, _mm256_mul_ps(d, _mm256_mul_ps(_mm256_load_ps(b.nx), lane.pull)));
  lane.vy =
      _mm256_add_ps(lane.vy, _mm256_mul_ps(d, _mm256_mul_ps(_mm256_load_ps(b.ny), lane.pull)));
  lane.vz =
      _mm256_add_ps(lane.vz, _mm256_mul_ps(d, _mm256_mul_ps(_mm256_load_ps(b.nz), lane.pull)));
  lane.wx = _mm256_add_ps(lane.wx, _mm256_mul_ps(d, _mm256_load_ps(b.ix)));
  lane.wy = _mm256_add_ps(lane.wy, _mm256_mul_ps(d, _mm256_load_ps(b.iy)));
  lane.wz = _mm256_add_ps(lane.wz, _mm256_mul_ps(d, _mm256_load_ps(b.iz)));
}
}  // namespace

// The sweeps of up to four worlds side by side. Each world's lanes take six vector registers:
// four worlds need twenty-four, which AVX-512VL has (thirty-two; the loop is compiled for it
// too: the same operations, so the same bits, and contraction into FMA is off in every
// build). AVX's sixteen hold two worlds' lanes, though not without spills that land on the
// velocity chains, so without AVX-512VL the worlds go two by two.
struct SurfaceSweeps {
  using Batch = SurfaceBatches::Batch;
  static constexpr int kLanes = SurfaceBatches::kLanes;

  // Lanes `lanes` (a bit mask) of batch i take their bodies (p: where they are).
  __attribute__((target("avx"), always_inline)) static inline void load(
      SurfaceBatches& sweep, std::vector<SolverBody>& bodies, std::size_t i, unsigned lanes,
      SolverBody* p[kLanes], EightBodies& lane) {
    for (; lanes != 0; lanes &= lanes - 1) {
      const int k = __builtin_ctz(lanes);
      const int slot = sweep.lanes_[i].slot[k];
      p[k] = sweep.laneBody(bodies, slot);
      lane.loadLane(k, *p[k], sweep.massScale_[static_cast<std::size_t>(slot)]);
    }
  }

  // Batches [from, to) of the first M sweeps (each has them). Each lane runs down its
  // column, mostly on one slot for many batches in a row: its body stays in registers until
  // the lane moves to another slot, and until `to`.
  template <int M>
  __attribute__((target("avx"), always_inline)) static inline void phase(
      SurfaceBatches* const* sweeps, std::vector<SolverBody>* const* bodies, std::size_t from,
      std::size_t to, bool useBias) {
    constexpr unsigned kAll = (1u << kLanes) - 1;
    SolverBody* p[M][kLanes];
    EightBodies lane[M];
#pragma GCC unroll 4
    for (int w = 0; w < M; ++w) {
      lane[w].vx = lane[w].vy = lane[w].vz = lane[w].wx = lane[w].wy = lane[w].wz = lane[w].pull =
          _mm256_setzero_ps();
      load(*sweeps[w], *bodies[w], from, kAll, p[w], lane[w]);
    }
    for (std::size_t i = from; i < to; ++i) {
#pragma GCC unroll 4
      for (int w = 0; w < M; ++w) {
        const unsigned changed = sweeps[w]->changed_[i];
        if (i == from || changed == 0) continue;
        // Every leaving body is written back before any arriving one is read: a slot can
        // leave one lane and enter another at the same batch.
        lane[w].writeBack(changed, p[w]);
        load(*sweeps[w], *bodies[w], i, changed, p[w], lane[w]);
      }
#pragma GCC unroll 4
      for (int w = 0; w < M; ++w) solveBatch(sweeps[w]->batches_[i], lane[w], useBias);
    }
#pragma GCC unroll 4
    for (int w = 0; w < M; ++w) lane[w].writeBack(kAll, p[w]);
  }

  // Every batch of the given sweeps (at most four, none empty): all of them side by side
  // while each has batches left, then the longer ones on.
  __attribute__((target("avx"), always_inline)) static inline void run(
      std::span<SurfaceBatches* const> given, std::span<std::vector<SolverBody>* const> givenBodies,
      bool useBias) {
    const std::size_t n = given.size();
    SurfaceBatches* sweeps[4];
    std::vector<SolverBody>* bodies[4];
    for (std::size_t w = 0; w < n; ++w) {  // by decreasing batch count (insertion sort)
      std::size_t j = w;
      for (; j > 0 && sweeps[j - 1]->batches_.size() < given[w]->batches_.size(); --j) {
        sweeps[j] = sweeps[j - 1];
        bodies[j] = bodies[j - 1];
      }
      sweeps[j] = given[w];
      bodies[j] = givenBodies[w];
    }
    for (std::size_t w = 0; w < n; ++w) sweeps[w]->beginCopies(*bodies[w]);
    std::size_t from = 0;
    for (std::size_t m = n; m > 0; --m) {  // the m longest sweeps still have batches
      const std::size_t to = sweeps[m - 1]->batches_.size();
      if (from < to) {
        switch (m) {
          case 4:
            phase<4>(sweeps, bodies, from, to, useBias);
            break;
          case 3:
            phase<3>(sweeps, bodies, from, to, useBias);
            break;
          case 2:
            phase<2>(sweeps, bodies, from, to, useBias);
            break;
          default:
            phase<1>(sweeps, bodies, from, to, useBias);
            break;
        }
        from = to;
      }
    }
    for (std::size_t w = 0; w < n; ++w) sweeps[w]->endCopies(*bodies[w]);
  }
};

namespace {
const bool kHasAvx512vl = cpuHasAvx512vl();

__attribute__((target("avx"))) void runAvx(std::span<SurfaceBatches* const> sweeps,
                                           std::span<std::vector<SolverBody>* const> bodies,
                                           bool useBias) {
  SurfaceSweeps::run(sweeps, bodies, useBias);
}

__attribute__((target("avx512f,avx512vl"))) void runAvx512(
    std::span<SurfaceBatches* const> sweeps, std::span<std::vector<SolverBody>* const> bodies,
    bool useBias) {
  SurfaceSweeps::run(sweeps, bodies, useBias);
}
std::atomic<bool> vectorSweeps{true};  // useVectorSweeps (kernel_paths.h)
}  // namespace

bool SurfaceBatches::canSolveSideBySide() {
  return kHasAvx && vectorSweeps.load(std::memory_order_relaxed);
}

bool SurfaceBatches::useVectorSweeps(bool enabled) {
  vectorSweeps.store(enabled && kHasAvx);
  return vectorSweeps.load();
}

void SurfaceBatches::solve(std::vector<SolverBody>& bodies, bool useBias) {
  SurfaceBatches* const self[1] = {this};
  std::vector<SolverBody>* const selfBodies[1] = {&bodies};
  solveSideBySide(self, selfBodies, useBias);
}

void SurfaceBatches::solveSideBySide(std::span<SurfaceBatches* const> sweeps,
                                     std::span<std::vector<SolverBody>* const> bodies,
                                     bool useBias) {
  assert(sweeps.size() == bodies.size());
  if (!canSolveSideBySide()) {
    for (std::size_t w = 0; w < sweeps.size(); ++w) sweeps[w]->solveFallback(*bodies[w], useBias);
    return;
  }
  // The sweeps with batches, `group` at a time.
  const std::size_t group = kHasAvx512vl ? 4 : 2;
  SurfaceBatches* chosen[4];
  std::vector<SolverBody>* chosenBodies[4];
  std::size_t count = 0;
  auto flush = [&] {
    if (count == 0) return;
    if (kHasAvx512vl)
      runAvx512({chosen, count}, {chosenBodies, count}, useBias);
    else
      runAvx({chosen, count}, {chosenBodies, count}, useBias);
    count = 0;
  };
  for (std::size_t w = 0; w < sweeps.size(); ++w) {
    if (sweeps[w]->batches_.empty()) continue;
    chosen[count] = sweeps[w];
    chosenBodies[count] = bodies[w];
    if (++count == group) flush();
  }
  flush();
}
#else
bool SurfaceBatches::canSolveSideBySide() {
  return false;
}

bool SurfaceBatches::useVectorSweeps(bool) {
  return false;
}

void SurfaceBatches::solve(std::vector<SolverBody>& bodies, bool useBias) {
  solveFallback(bodies, useBias);
}

void SurfaceBatches::solveSideBySide(std::span<SurfaceBatches* const> sweeps,
                                     std::span<std::vector<SolverBody>* const> bodies,
                                     bool useBias) {
  for (std::size_t w = 0; w < sweeps.size(); ++w) sweeps[w]->solve(*bodies[w], useBias);
}
#endif

}  // namespace dynahand::physics
