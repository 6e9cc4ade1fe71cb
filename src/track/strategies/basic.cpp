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
  bool run(StrategyContext& c) override {
    c.simulator.run(c.rig, c.input, c.substeps);
    return true;
  }
};

// Paper "Gross Motion Bias": the whole hand frozen into one rigid body so the palm,
// wrist and boundary planes overpower points mapped to the wrong finger; then
// unfrozen, re-mapped (every substep re-maps) and simulated normally.
class GrossMotionStrategy final : public Strategy {
 public:
  StrategyKind kind() const override { return StrategyKind::GrossMotion; }
  bool run(StrategyContext& c) override {
    auto& world = c.rig.world();
    if (all_.size() != static_cast<std::size_t>(world.bodyCount())) {
      all_.resize(static_cast<std::size_t>(world.bodyCount()));
      std::iota(all_.begin(), all_.end(), 0);
    }
    world.weld(all_);
    c.simulator.run(c.rig, c.input, c.substeps);
    world.unweldAll();
    c.simulator.run(c.rig, c.input, c.substeps);
    return true;
  }

 private:
  std::vector<physics::BodyId> all_;
};

// Paper "Grasping Bias": neighbouring fingertip bones, and middle bones, kept within
// 10 degrees of parallel, so the fingers move together as in most grasps.
class GraspBiasStrategy final : public Strategy {
 public:
  StrategyKind kind() const override { return StrategyKind::GraspBias; }
  bool run(StrategyContext& c) override {
    auto& world = c.rig.world();
    for (auto cone : c.rig.graspCones()) world.setConeEnabled(cone, true);
    c.simulator.run(c.rig, c.input, c.substeps);
    for (auto cone : c.rig.graspCones()) world.setConeEnabled(cone, false);
    return true;
  }
};

}  // namespace

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
