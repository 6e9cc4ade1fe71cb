// Paper "Feature Detection": when the five-finger detector fires, its fingertips are
// bound to the fingertip bodies (labelled points, stronger than ordinary samples) in
// a simulation of their own, so a false detection costs nothing: the error metric
// simply does not pick it.
#include <vector>

#include "track/strategies/strategy.h"

namespace dynahand::track {
namespace {

constexpr float kLabelCapScale = 20.0f;  // a labelled tip pulls like this many samples

class FeatureDetectionStrategy final : public Strategy {
 public:
  StrategyKind kind() const override { return StrategyKind::FeatureDetection; }

  bool run(StrategyContext& c) override {
    if (c.detection == nullptr || !c.detection->fired) return false;
    const auto& anatomy = c.rig.anatomy();
    labelled_.clear();
    for (int f = 0; f < kFingerCount; ++f) {
      const int tipBody = anatomy.fingers[static_cast<std::size_t>(f)][2];
      labelled_.push_back(
          {c.detection->tips[static_cast<std::size_t>(f)], BodyMask{1} << tipBody, kLabelCapScale});
    }
    FrameInput input = c.input;
    input.labelled = labelled_;
    c.simulator.run(c.rig, input, c.substeps);
    // Then let go of the labels so the result also fits the rest of the data.
    c.simulator.run(c.rig, c.input, 1);
    return true;
  }

 private:
  std::vector<LabelledPoint> labelled_;
};

}  // namespace

std::unique_ptr<Strategy> makeFeatureDetectionStrategy() {
  return std::make_unique<FeatureDetectionStrategy>();
}

}  // namespace dynahand::track
