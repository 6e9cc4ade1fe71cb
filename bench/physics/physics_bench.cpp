// Solver step on a 17-body hand-like model (16 joints with limits, contacts between every
// unjoined pair) with N random surface rows, 16 sweeps + 4 relax sweeps: the tracker's inner
// loop. Each iteration restores the same state and steps once (the rows stay filled).
#include <benchmark/benchmark.h>

#include "dynahand/physics_world.h"
#include "physics/physics_scenes.h"

namespace dynahand::physics {
namespace {

constexpr float kDt = 1.0f / 60.0f;

void BM_SolverStep(benchmark::State& state) {
  const int rows = static_cast<int>(state.range(0));
  scenes::HandLike hand = scenes::makeHandLike();
  World& w = hand.world;
  w.reserveRows(rows);
  scenes::addRandomSurfaceRows(w, rows, 42, 0.01f);
  for (int i = 0; i < 5; ++i) w.step(kDt);  // warm up (caches, contact list, warm starts)
  WorldState start;
  w.saveState(start);
  for (auto _ : state) {
    w.restoreState(start);
    w.step(kDt);
    benchmark::DoNotOptimize(w.state().position.data());
  }
  state.counters["rows"] = rows;
  state.counters["contacts"] = static_cast<double>(w.contacts().size());
}
BENCHMARK(BM_SolverStep)->Arg(300)->Arg(1000)->Arg(3000)->Unit(benchmark::kMicrosecond);

// The same without surface rows: the fixed cost (joints, limits, narrow phase).
void BM_SolverStepNoRows(benchmark::State& state) {
  scenes::HandLike hand = scenes::makeHandLike();
  World& w = hand.world;
  for (int i = 0; i < 5; ++i) w.step(kDt);
  WorldState start;
  w.saveState(start);
  for (auto _ : state) {
    w.restoreState(start);
    w.step(kDt);
    benchmark::DoNotOptimize(w.state().position.data());
  }
}
BENCHMARK(BM_SolverStepNoRows)->Unit(benchmark::kMicrosecond);

// Snapshot + restore alone (several simulations per frame start from one state).
void BM_SnapshotRestore(benchmark::State& state) {
  scenes::HandLike hand = scenes::makeHandLike();
  World& w = hand.world;
  w.step(kDt);
  WorldState a, b;
  w.saveState(a);
  for (auto _ : state) {
    w.restoreState(a);
    w.saveState(b);
    benchmark::DoNotOptimize(b.position.data());
  }
}
BENCHMARK(BM_SnapshotRestore)->Unit(benchmark::kMicrosecond);

// Refilling the transient surface-row buffer (the tracker does this every substep).
void BM_FillSurfaceRows(benchmark::State& state) {
  const int rows = static_cast<int>(state.range(0));
  scenes::HandLike hand = scenes::makeHandLike();
  World& w = hand.world;
  w.reserveRows(rows);
  for (auto _ : state) {
    w.rows().clear();
    scenes::addRandomSurfaceRows(w, rows, 42, 0.01f);
    benchmark::DoNotOptimize(w.rows().body.data());
  }
}
BENCHMARK(BM_FillSurfaceRows)->Arg(1000)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace dynahand::physics
