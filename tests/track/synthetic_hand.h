// Test support: renders the default hand at a model pose through the synthetic
// sensor (smooth render surface, not the tracker's convex bodies) into a DepthFrame.
#pragma once

#include <numbers>

#include "dynahand/model.h"
#include "dynahand/model_pose.h"
#include "dynahand/synth_render.h"
#include "dynahand/synth_sensor.h"

namespace dynahand::test {

// Root pose putting the open hand's fingers up (-y) with the palm toward the camera
// (-z), its keypoint centre at `centre`.
inline Pose facingCamera(const model::ArticulatedModel& m, const Vec3& centre) {
  model::JointAngles open = model::zeroAngles(m);
  model::clampToLimits(m, open);
  const auto rest = model::forwardKinematics(m, open);
  const auto k = model::keypoints21(m, rest);
  const Vec3 finger = (k[9] - k[0]).normalized();
  Vec3 thumb = k[5] - k[17];
  thumb = (thumb - thumb.dot(finger) * finger).normalized();
  Mat3 from, to;
  from << finger, thumb, finger.cross(thumb);
  const Vec3 up(0, -1, 0), right(1, 0, 0);
  to << up, right, up.cross(right);
  const Quat q(to * from.transpose());
  Vec3 c = Vec3::Zero();
  for (const Vec3& p : k) c += p;
  c /= 21.0f;
  const Pose transform{centre - q * c, q};
  return transform * rest.bodies[static_cast<std::size_t>(m.root())];
}

class SyntheticCamera {
 public:
  SyntheticCamera(const std::string& profile, std::uint64_t seed = 7)
      : profile_(*synth::findSensorProfile(profile)),
        renderer_(profile_.intrinsics),
        sensor_(profile_, seed) {}

  const Intrinsics& intrinsics() const { return profile_.intrinsics; }

  DepthFrame render(const model::ArticulatedModel& m, const model::ModelPose& pose, int frameIndex,
                    double time) {
    synth::HandSkeleton skeleton;
    skeleton.keypoints = model::keypoints21(m, pose);
    const Vec3 wrist = skeleton.keypoints[0];
    skeleton.elbow = wrist + (wrist - skeleton.keypoints[9]).normalized() * 0.25f;
    primitives_.clear();
    synth::buildHandSurface(skeleton, synth::SurfaceRadii{}, primitives_);
    renderer_.clear();
    renderer_.draw(primitives_, synth::PixelLabel::Hand0);
    DepthFrame frame;
    sensor_.apply(renderer_.depth(), renderer_.labels(), frameIndex, time, frame);
    return frame;
  }

 private:
  synth::SensorProfile profile_;
  synth::DepthRenderer renderer_;
  synth::SensorSimulator sensor_;
  std::vector<synth::RoundCone> primitives_;
};

}  // namespace dynahand::test
