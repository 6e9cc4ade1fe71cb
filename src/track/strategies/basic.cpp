// The normal, gross-motion and grasp-bias simulations.
#include "track/strategies/strategy.h"

#include <array>
#include <cassert>
#include <numeric>
#include <span>
#include <vector>

namespace dynahand::track {
namespace {

// Plain fit: surface rows, joints, limits, collisions, boundary planes, momentum.
class NormalStrategy final : public Strategy {
 public:
  StrategyKind kind() const override { return StrategyKind::Normal; }
  int steps(int substeps) const override { return substeps; }
  bool begin(StrategyContext&) override { return true; }
  const FrameInput* beforeStep(StrategyContext& c, int step) override {
    return step < c.substeps ? &c.input : nullptr;
  }
};

// Paper "Gross Motion Bias": the whole hand frozen into one rigid body so the palm,
// wrist and boundary planes overpower points mapped to the wrong finger; then
// unfrozen, re-mapped (every substep re-maps) and simulated normally.
class GrossMotionStrategy final : public Strategy {
 public:
  StrategyKind kind() const override { return StrategyKind::GrossMotion; }
  int steps(int substeps) const override { return 2 * substeps; }
  bool begin(StrategyContext& c) override {
    auto& world = c.rig.world();
    if (all_.size() != static_cast<std::size_t>(world.bodyCount())) {
      all_.resize(static_cast<std::size_t>(world.bodyCount()));
      std::iota(all_.begin(), all_.end(), 0);
    }
    world.weld(all_);
    return true;
  }
  const FrameInput* beforeStep(StrategyContext& c, int step) override {
    if (step == c.substeps) c.rig.world().unweldAll();
    return step < 2 * c.substeps ? &c.input : nullptr;
  }

 private:
  std::vector<physics::BodyId> all_;
};

// Paper "Grasping Bias": neighbouring fingertip bones, and middle bones, kept within
// 10 degrees of parallel, so the fingers move together as in most grasps.
class GraspBiasStrategy final : public Strategy {
 public:
  StrategyKind kind() const override { return StrategyKind::GraspBias; }
  int steps(int substeps) const override { return substeps; }
  bool begin(StrategyContext& c) override {
    for (auto cone : c.rig.graspCones()) c.rig.world().setConeEnabled(cone, true);
    return true;
  }
  const FrameInput* beforeStep(StrategyContext& c, int step) override {
    if (step < c.substeps) return &c.input;
    for (auto cone : c.rig.graspCones()) c.rig.world().setConeEnabled(cone, false);
    return nullptr;
  }
};

}  // namespace

bool runStrategy(Strategy& strategy, StrategyContext& c) {
  Strategy* const one[1] = {&strategy};
  StrategyContext* const context[1] = {&c};
  bool ran[1] = {false};
  runStrategiesSideBySide(one, context, ran);
  return ran[0];
}

void runStrategiesSideBySide(std::span<Strategy* const> strategies,
                             std::span<StrategyContext* const> contexts, std::span<bool> ran) {
  assert(strategies.size() == contexts.size() && ran.size() == strategies.size());
  constexpr std::size_t kSlots = physics::World::kMaxSideBySide;
  std::size_t next = 0;  // the next strategy to start
  std::array<int, kSlots> running, step;
  // Slot k takes the next strategy with something to do (-1 when none is left).
  auto startNext = [&](std::size_t k) {
    running[k] = -1;
    while (next < strategies.size()) {
      const std::size_t i = next++;
      ran[i] = strategies[i]->begin(*contexts[i]);
      if (ran[i]) {
        running[k] = static_cast<int>(i);
        step[k] = 0;
        return;
      }
    }
  };
  for (std::size_t k = 0; k < kSlots; ++k) startNext(k);
  std::array<physics::World*, kSlots> worlds;
  for (;;) {
    // The worlds with a step to take now; those whose step length differs from the first's
    // are stepped alone.
    std::size_t count = 0;
    float dt = 0.0f;
    for (std::size_t k = 0; k < kSlots; ++k) {
      while (running[k] >= 0) {
        StrategyContext& c = *contexts[static_cast<std::size_t>(running[k])];
        const FrameInput* input =
            strategies[static_cast<std::size_t>(running[k])]->beforeStep(c, step[k]);
        if (input != nullptr) {
          ++step[k];
          c.simulator.prepareStep(c.rig, *input);
          const float h = c.simulator.settings().stepDt;
          if (count == 0) dt = h;
          if (h == dt) {
            worlds[count++] = &c.rig.world();
          } else {
            c.rig.world().step(h);
          }
          break;
        }
        startNext(k);  // this run is over
      }
    }
    if (count == 0) break;
    physics::World::stepSideBySide(std::span(worlds.data(), count), dt);
  }
}

std::unique_ptr<Strategy> makeFingerFlipStrategy();
std::unique_ptr<Strategy> makeFeatureDetectionStrategy();
std::unique_ptr<Strategy> makeDetectorFitStrategy();

std::unique_ptr<Strategy> makeStrategy(StrategyKind kind) {
  switch (kind) {
    case StrategyKind::Normal:
      return std::make_unique<NormalStrategy>();
    case StrategyKind::GrossMotion:
      return std::make_unique<GrossMotionStrategy>();
    case StrategyKind::GraspBias:
      return std::make_unique<GraspBiasStrategy>();
    case StrategyKind::FingerFlip:
      return makeFingerFlipStrategy();
    case StrategyKind::FeatureDetection:
      return makeFeatureDetectionStrategy();
    case StrategyKind::DetectorFit:
      return makeDetectorFitStrategy();
  }
  return nullptr;
}

}  // namespace dynahand::track
