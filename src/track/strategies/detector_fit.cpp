// The detector-fit simulation (beyond the paper, whose feature simulation binds detected
// points to a model that starts where the last frame left it): the hand is placed in the
// pose fitted to the learned detector's keypoints, then fitted to the cloud like the normal
// simulation. A hand the temporal prior has turned the wrong way (flipped palm, fingers
// swapped) is replaced within a frame when this fits the data better: the error metric
// decides, as for every simulation.
#include "track/strategies/strategy.h"

namespace dynahand::track {
namespace {

class DetectorFitStrategy final : public Strategy {
 public:
  StrategyKind kind() const override { return StrategyKind::DetectorFit; }
  // From a start up to ~2 cm off: twice the normal run.
  int steps(int substeps) const override { return 2 * substeps; }

  bool begin(StrategyContext& c) override {
    if (c.detectorPose == nullptr) return false;
    c.rig.setPose(*c.detectorPose);
    // No forearm hold: it holds the last frame's forearm, which this start replaces.
    input_ = c.input;
    input_.hold = nullptr;
    return true;
  }

  const FrameInput* beforeStep(StrategyContext& c, int step) override {
    return step < 2 * c.substeps ? &input_ : nullptr;
  }

 private:
  FrameInput input_;
};

}  // namespace

std::unique_ptr<Strategy> makeDetectorFitStrategy() {
  return std::make_unique<DetectorFitStrategy>();
}

}  // namespace dynahand::track
