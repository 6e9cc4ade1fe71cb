// Paper "Searching Nearby States": from the previous best pose, joint drives raise or
// lower one finger (sometimes with its neighbour) into the opposite of its current
// state, then the drives let go and the data decides; the error metric keeps the
// result only if it fits better. Which finger(s) cycles every flipPeriod seconds of
// sequence time, since settling can take a few frames.
#include <algorithm>
#include <array>
#include <vector>

#include "track/strategies/strategy.h"

namespace dynahand::track {
namespace {

// Finger sets tried in turn: each finger alone, then neighbouring pairs.
constexpr std::array<std::array<int, 2>, 8> kFlipSets = {
    {{1, -1}, {2, -1}, {3, -1}, {4, -1}, {0, -1}, {1, 2}, {2, 3}, {3, 4}}};

constexpr float kCurledFlexion =
    1.6f;  // sum of a finger's three flexions above which it is curled, rad
constexpr float kCurlFraction =
    0.85f;                            // curled target: this fraction of each joint's flexion range
constexpr float kDriveTorque = 3.0f;  // N m, per joint
constexpr float kDriveTime = 2.0f / 60;  // s to close the angle error

class FingerFlipStrategy final : public Strategy {
 public:
  StrategyKind kind() const override { return StrategyKind::FingerFlip; }

  int steps(int substeps) const override { return 2 * substeps; }

  bool begin(StrategyContext& c) override {
    if (c.startAngles == nullptr || c.detectorInUse) return false;
    const auto& model = c.rig.model();
    const auto& anatomy = c.rig.anatomy();
    auto& world = c.rig.world();
    const auto setIndex =
        static_cast<std::size_t>(c.sequenceTime / static_cast<double>(c.flipPeriod)) %
        kFlipSets.size();
    joints_.clear();
    for (int finger : kFlipSets[setIndex]) {
      if (finger < 0) continue;
      const auto& bodies = anatomy.fingers[static_cast<std::size_t>(finger)];
      float flexion = 0.0f;
      for (int body : bodies) {
        flexion += c.startAngles
                       ->angles[static_cast<std::size_t>(
                           anatomy.jointOfBody[static_cast<std::size_t>(body)])]
                       .x();
      }
      const bool curled = flexion > (finger == 0 ? 0.6f * kCurledFlexion : kCurledFlexion);
      for (int body : bodies) {
        const int j = anatomy.jointOfBody[static_cast<std::size_t>(body)];
        const auto& joint = model.joints()[static_cast<std::size_t>(j)];
        Vec3 target = c.startAngles->angles[static_cast<std::size_t>(j)];
        const float lo = std::max(joint.minAngle.x(), 0.0f);
        target.x() = curled ? lo : lo + kCurlFraction * (joint.maxAngle.x() - lo);
        target = target.cwiseMax(joint.minAngle).cwiseMin(joint.maxAngle);
        world.setJointDrive(j, c.rig.physicsJointRotation(j, target), kDriveTorque, kDriveTime);
        joints_.push_back(j);
      }
    }
    return true;
  }

  const FrameInput* beforeStep(StrategyContext& c, int step) override {
    if (step == c.substeps)
      for (int j : joints_) c.rig.world().clearJointDrive(j);
    return step < 2 * c.substeps ? &c.input : nullptr;
  }

 private:
  std::vector<int> joints_;
};

}  // namespace

std::unique_ptr<Strategy> makeFingerFlipStrategy() {
  return std::make_unique<FingerFlipStrategy>();
}

}  // namespace dynahand::track
