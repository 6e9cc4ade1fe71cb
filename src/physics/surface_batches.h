// Surface rows (one body each, the tracker's thousands of point-on-plane constraints) packed
// eight to a batch, the eight on different solver slots, and solved a batch at a time (the SIMD
// layer's kernel surface_sweeps.inl; row by row on its scalar level). Within a batch the rows touch
// different bodies, so solving them together is the same as solving them one after another: still
// projected Gauss-Seidel. Since every row moves one body only, a sweep's result depends on nothing
// but each slot's order of its rows; the batches only schedule the slots' chains side by side. A
// slot holding more than a quarter of the rows, and at least 32 (a welded hand: all of them), would
// be one long chain; its rows are instead spread over several copies of the slot, each with that
// share of its mass, whose velocities are averaged after every sweep (mass splitting, Tonge et al.
// 2012).
#pragma once

#include <span>
#include <vector>

#include "dynahand/core.h"

namespace dynahand::physics {

struct SolverBody;  // world_impl.h

// One prepared surface row (see World::step): impulse increment d = -effMass (Jv + bias),
// Jv = normal·v + ang·w, clamped to [lower, upper]; applies invMass d normal and d invIAng.
struct PreparedSurfaceRow {
  int slot;
  Vec3 normal, ang, invIAng;
  float effMass, bias, relaxBias, lower, upper;
};

class SurfaceBatches {
 public:
  // Packs the rows; `dummySlot` is a slot that never moves (padding lanes point at it).
  // bodies: the solver slots (their count: copies of split slots are numbered after them).
  void build(const std::vector<PreparedSurfaceRow>& rows, const std::vector<SolverBody>& bodies,
             int dummySlot);
  // One sweep over every row, with the position bias (solve) or the relax bias.
  void solve(std::vector<SolverBody>& bodies, bool useBias);
  // sweeps[i]->solve(*bodies[i], useBias) for each i (of different worlds), side by side,
  // batch by batch, up to four at a time on the AVX-512 level (two on AVX2, whose sixteen
  // registers hold two worlds' lanes; one on SSE2): each lane does exactly what solve() does,
  // so the same bits, but the sweeps' latency chains overlap.
  static void solveSideBySide(std::span<SurfaceBatches* const> sweeps,
                              std::span<std::vector<SolverBody>* const> bodies, bool useBias);
  // Whether solveSideBySide overlaps the sweeps here (the SIMD level is above scalar and the
  // vector sweeps are on); otherwise it solves one after the other, row by row.
  static bool canSolveSideBySide();
  // Switches the vector sweeps (useVectorSweeps, kernel_paths.h); returns whether they are now on.
  static bool useVectorSweeps(bool enabled);
  // The accumulated impulse of every row, in the order given to build().
  void writeImpulses(float* impulses) const;
  void reserve(int rows);

 private:
  // build's stages: each row's solving slot (its own, or for a slot with many rows one of its
  // copies in turn) and the copies' mass scales, returning the solving slots' count; the rows
  // grouped by solving slot and the slots by decreasing row count, returning the largest
  // count; the rows dealt into the (batches x 8) table, returning the batch count; the
  // batches filled from the table.
  int assignSolvingSlots(const std::vector<PreparedSurfaceRow>& rows);
  int groupRowsBySlot(int n, std::size_t slots);
  int dealIntoTable(int n, int largest);
  void fillBatches(const std::vector<PreparedSurfaceRow>& rows, int batchCount, int dummySlot);
  friend struct SurfaceSweeps;  // the sweeps' kernels' access (surface_batches.cpp)
  static constexpr int kLanes = 8;
  // A batch: what the sweeps read, two fields to a cache line (relaxBias last: only the relax
  // sweeps read it). The sweeps are bound by how fast these stream in from the second-level
  // cache, so a batch holds nothing that can be formed on the way: the pull along the normal
  // per unit impulse is normal x (the lane's inverse mass x massScale_), formed per batch with
  // the same rounding as storing it would have had.
  struct alignas(64) Batch {
    float nx[kLanes], ny[kLanes], nz[kLanes], ax[kLanes], ay[kLanes], az[kLanes];
    float ix[kLanes], iy[kLanes], iz[kLanes];  // the body's inverse inertia x ang
    float effMass[kLanes], lower[kLanes], upper[kLanes], impulse[kLanes], bias[kLanes];
    float relaxBias[kLanes];
  };
  // Where a batch's lanes point, read only when lanes change slot.
  struct BatchLanes {
    int slot[kLanes];
    int row[kLanes];  // index in build()'s input; -1 for padding
  };
  // A slot whose rows are spread over `copies` copies, solver slots `first`... of copies_.
  struct Split {
    int slot, first, copies;
  };
  SolverBody* laneBody(std::vector<SolverBody>& bodies, int slot);
  void beginCopies(const std::vector<SolverBody>& bodies);  // every copy = its slot
  void endCopies(std::vector<SolverBody>& bodies) const;    // each split slot = its copies' mean

  void solveFallback(std::vector<SolverBody>& bodies, bool useBias);

  std::vector<Batch> batches_;
  std::vector<BatchLanes> lanes_;  // (batches)
  // (batches) the lanes whose slot differs from the batch before (a bit mask; the first: 0),
  // where the sweep writes those lanes' bodies back and loads the next ones
  std::vector<unsigned char> changed_;
  std::vector<int> spread_;   // scratch: one slot's rows in dealing order
  std::vector<int> cellRow_;  // scratch: the row in each cell, counted down the columns
  std::vector<int> order_, count_, start_, slotsByCount_;
  std::vector<int> virtualSlot_;  // (rows) the slot or copy a row is solved on
  std::vector<Split> splits_;
  std::vector<int> splitOfSlot_;  // (slots) index into splits_, -1 when not split
  std::vector<int> rowsSeen_;     // (slots) scratch while dealing rows to copies
  // (slots, then copies) the factor on a lane body's inverse mass: a copy holds 1/copies of
  // its slot's mass; 1 for a slot
  std::vector<float> massScale_;
  std::vector<SolverBody> copies_;
  int slotCount_ = 0;  // real solver slots; copies are numbered after them
};

}  // namespace dynahand::physics
