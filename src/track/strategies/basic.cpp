// The normal, gross-motion and grasp-bias simulations.
#include "track/strategies/strategy.h"

#include <numeric>
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
  if (!strategy.begin(c)) return false;
  for (int step = 0;; ++step) {
    const FrameInput* input = strategy.beforeStep(c, step);
    if (input == nullptr) return true;
    c.simulator.prepareStep(c.rig, *input);
    c.rig.world().step(c.simulator.settings().stepDt);
  }
}

void runStrategiesTogether(Strategy& a, StrategyContext& contextA, Strategy& b,
                           StrategyContext& contextB, bool ran[2]) {
  Strategy* strategy[2] = {&a, &b};
  StrategyContext* context[2] = {&contextA, &contextB};
  bool active[2];
  for (int k = 0; k < 2; ++k) ran[k] = active[k] = strategy[k]->begin(*context[k]);
  const float dt[2] = {contextA.simulator.settings().stepDt, contextB.simulator.settings().stepDt};
  for (int step = 0; active[0] || active[1]; ++step) {
    bool stepping[2] = {false, false};
    for (int k = 0; k < 2; ++k) {
      if (!active[k]) continue;
      const FrameInput* input = strategy[k]->beforeStep(*context[k], step);
      active[k] = stepping[k] = input != nullptr;
      if (input != nullptr) context[k]->simulator.prepareStep(context[k]->rig, *input);
    }
    auto& worldA = contextA.rig.world();
    auto& worldB = contextB.rig.world();
    if (stepping[0] && stepping[1] && dt[0] == dt[1]) {
      physics::World::stepTogether(worldA, worldB, dt[0]);
    } else {
      if (stepping[0]) worldA.step(dt[0]);
      if (stepping[1]) worldB.step(dt[1]);
    }
  }
}

std::unique_ptr<Strategy> makeFingerFlipStrategy();
std::unique_ptr<Strategy> makeFeatureDetectionStrategy();

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
  }
  return nullptr;
}

}  // namespace dynahand::track
