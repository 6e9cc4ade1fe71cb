// Paper "Feature Detection": detected features bound to the bodies they name (labelled
// points, stronger than ordinary samples) in a simulation of their own, so a false
// detection costs nothing: the error metric simply does not pick it. The features are the
// learned detector's confident keypoints when it has them, else the five-finger
// detector's fingertips when it fires.
#include <vector>

#include "track/strategies/strategy.h"

namespace dynahand::track {
namespace {

constexpr float kLabelCapScale = 20.0f;  // a labelled tip pulls like this many samples

class FeatureDetectionStrategy final : public Strategy {
 public:
  StrategyKind kind() const override { return StrategyKind::FeatureDetection; }

  int steps(int substeps) const override { return substeps + 1; }

  bool begin(StrategyContext& c) override {
    if (!c.detectorLabels.empty()) {
      labelledInput_ = c.input;
      labelledInput_.labelled = c.detectorLabels;
      return true;
    }
    if (c.detection == nullptr || !c.detection->fired) return false;
    const auto& anatomy = c.rig.anatomy();
    labelled_.clear();
    for (int f = 0; f < kFingerCount; ++f) {
      const int tipBody = anatomy.fingers[static_cast<std::size_t>(f)][2];
      labelled_.push_back(
          {c.detection->tips[static_cast<std::size_t>(f)], BodyMask{1} << tipBody, kLabelCapScale});
    }
    labelledInput_ = c.input;
    labelledInput_.labelled = labelled_;
    return true;
  }

  const FrameInput* beforeStep(StrategyContext& c, int step) override {
    if (step < c.substeps) return &labelledInput_;
    // Then one step without the labels, so the result also fits the rest of the data.
    return step == c.substeps ? &c.input : nullptr;
  }

 private:
  std::vector<LabelledPoint> labelled_;
  FrameInput labelledInput_;
};

}  // namespace

std::unique_ptr<Strategy> makeFeatureDetectionStrategy() {
  return std::make_unique<FeatureDetectionStrategy>();
}

}  // namespace dynahand::track
