#include "physics/surface_batches.h"

#include <algorithm>
#include <atomic>
#include <cassert>
#include <cstddef>
#include <numeric>

#include "core/simd/lanes.h"
#include "physics/world_impl.h"

namespace dynahand::physics {
namespace {
constexpr int kSpread = 4;
// A slot with more than 1/kSplitShare of the rows is split into copies (mass splitting).
constexpr int kSplitShare = 4;
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

}  // namespace

// The sweeps' access to SurfaceBatches (a friend), for the kernels of surface_sweeps.inl.
struct SurfaceSweeps {
  using Batch = SurfaceBatches::Batch;
  static std::vector<Batch>& batches(SurfaceBatches& s) { return s.batches_; }
  static const std::vector<SurfaceBatches::BatchLanes>& lanes(const SurfaceBatches& s) {
    return s.lanes_;
  }
  static const std::vector<unsigned char>& changed(const SurfaceBatches& s) { return s.changed_; }
  static const std::vector<float>& massScale(const SurfaceBatches& s) { return s.massScale_; }
  static SolverBody* laneBody(SurfaceBatches& s, std::vector<SolverBody>& bodies, int slot) {
    return s.laneBody(bodies, slot);
  }
  static void beginCopies(SurfaceBatches& s, const std::vector<SolverBody>& bodies) {
    s.beginCopies(bodies);
  }
  static void endCopies(const SurfaceBatches& s, std::vector<SolverBody>& bodies) {
    s.endCopies(bodies);
  }
};

namespace {
#define DYNAHAND_SIMD_KERNELS "physics/surface_sweeps.inl"
#include "core/simd/for_each_level.inl"

std::atomic<bool> vectorSweeps{true};  // useVectorSweeps (kernel_paths.h)

// The sweeps run one batch (eight rows) at a time on the SIMD layer's widest level but the
// scalar one, where they run row by row (solveFallback).
bool sweepsInLanes() {
  return simd::level() != simd::Level::Scalar && vectorSweeps.load(std::memory_order_relaxed);
}
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
  // sets: a few rows solve as well in sequence, and Gauss-Seidel converges faster.
  const int target = std::max(1, (n + kSplitShare - 1) / kSplitShare);
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
  // sweeping it from one side to the other.
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
    // The slot's k-th row is spread_[k]; cell `position + j` is solved k-th with
    // k = j - split for j >= split (the wrapped part, at the next column's top, comes first),
    // else k = j - split + length.
    const int split = wrapAfter(position, length, batchCount);
    int at = split < length ? length - split : 0;  // rank of cell `position`
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
    // Filled in lanes only when the sweeps run in them: the tests' switch turns off both.
    if (sweepsInLanes())
      DYNAHAND_SIMD_DISPATCH(fillBatchLanes, batches_[static_cast<std::size_t>(batch)], source,
                             copies);
    else
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

bool SurfaceBatches::canSolveSideBySide() {
  return sweepsInLanes();
}

bool SurfaceBatches::useVectorSweeps(bool enabled) {
  vectorSweeps.store(enabled);
  return sweepsInLanes();
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
  if (!sweepsInLanes()) {
    for (std::size_t w = 0; w < sweeps.size(); ++w) sweeps[w]->solveFallback(*bodies[w], useBias);
    return;
  }
  // The sweeps with batches, `group` at a time: each world's lanes take seven vector
  // registers, so four worlds fit AVX-512's thirty-two, two AVX2's sixteen (not without
  // spills that land on the velocity chains), one SSE2's sixteen half-width ones.
  const simd::Level level = simd::level();
  const std::size_t group = level == simd::Level::Avx512 ? 4 : level == simd::Level::Avx2 ? 2 : 1;
  SurfaceBatches* chosen[4];
  std::vector<SolverBody>* chosenBodies[4];
  std::size_t count = 0;
  auto flush = [&] {
    if (count == 0) return;
    DYNAHAND_SIMD_DISPATCH(sweepSideBySide, chosen, chosenBodies, count, useBias);
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

}  // namespace dynahand::physics
