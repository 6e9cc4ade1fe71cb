// Step time of the grasp scene (examples/scenes/grasp.json: the virtual hand + 10 objects on
// a table) at 60 Hz, with the hand holding the box: the reach-grasp-lift clip's ground truth
// drives the playground to 1.8 s (the box lifted about 11 cm in the closed hand), then each
// iteration restores that state and runs one 1/60 s step (drive targets, solver, contacts).
#include <benchmark/benchmark.h>

#include <cstdio>
#include <filesystem>

#include "dynahand/model.h"
#include "dynahand/playground.h"
#include "dynahand/synth.h"

namespace dynahand::playground {
namespace {

void BM_GraspSceneStep(benchmark::State& state) {
  auto scene = loadScene(std::filesystem::path(DYNAHAND_SOURCE_DIR) / "examples/scenes/grasp.json");
  synth::SynthOptions o;
  o.clip = "reach-grasp-lift";
  o.frameCount = 60;
  auto seq = synth::SyntheticSequence::create(o);
  if (!scene || !seq) {
    state.SkipWithError("grasp scene or clip missing");
    return;
  }
  auto pg = Playground::create(*scene, seq->model(0));
  if (!pg) {
    state.SkipWithError(pg.message().c_str());
    return;
  }
  Playground& p = **pg;
  const int frames = 54;  // 1.8 s at 30 Hz
  p.placeHand(seq->truth(0, 0).pose);
  for (int i = 0; i < frames; ++i) p.step(seq->truth(i, 0).pose, 1.0f / 30.0f);
  const model::ModelPose held = seq->truth(frames, 0).pose;
  physics::WorldState start;
  p.world().saveState(start);
  for (auto _ : state) {
    p.world().restoreState(start);
    p.step(held, 1.0f / 60.0f);
    benchmark::DoNotOptimize(p.world().state().position.data());
  }
  int dynamic = 0;
  for (const SceneBody& b : p.bodies()) dynamic += (!b.isHand && !b.isStatic) ? 1 : 0;
  state.counters["bodies"] = static_cast<double>(p.world().bodyCount());
  state.counters["objects"] = dynamic;
  state.counters["contacts"] = static_cast<double>(p.world().contacts().size());
  state.counters["box_y_cm"] = 100.0 * static_cast<double>(p.bodyPose(p.bodyIndex("box")).p.y());
}
BENCHMARK(BM_GraspSceneStep)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace dynahand::playground
