// Helpers shared by the model tests.
#pragma once

#include <random>

#include "dynahand/model.h"
#include "dynahand/model_pose.h"

namespace dynahand::model::fixtures {

// Uniformly random angles inside every joint's limits; root at a random pose near the camera.
inline JointAngles randomValidAngles(const ArticulatedModel& model, std::mt19937& rng) {
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  JointAngles angles = zeroAngles(model);
  for (size_t j = 0; j < angles.angles.size(); ++j) {
    const Joint& joint = model.joints()[j];
    for (int axis = 0; axis < 3; ++axis) {
      angles.angles[j][axis] =
          joint.minAngle[axis] + unit(rng) * (joint.maxAngle[axis] - joint.minAngle[axis]);
    }
  }
  const Vec3 axis = Vec3(unit(rng) - 0.5f, unit(rng) - 0.5f, unit(rng) - 0.5f).normalized();
  angles.root.q = Quat(Eigen::AngleAxisf(6.0f * unit(rng), axis));
  angles.root.p = Vec3(0.2f * unit(rng) - 0.1f, 0.2f * unit(rng) - 0.1f, 0.3f + 0.4f * unit(rng));
  return angles;
}

// Whether two bodies at these poses interpenetrate deeper than `margin` (m), judged by the
// vertices of each inside the other (enough for the rounded shapes used here).
inline bool overlaps(const physics::ConvexShape& a, const Pose& poseA,
                     const physics::ConvexShape& b, const Pose& poseB, float margin) {
  for (const Vec3& v : a.vertices()) {
    if (b.signedDistance(poseB.inverseTransform(poseA.transform(v))) < -margin) return true;
  }
  for (const Vec3& v : b.vertices()) {
    if (a.signedDistance(poseA.inverseTransform(poseB.transform(v))) < -margin) return true;
  }
  return false;
}

}  // namespace dynahand::model::fixtures
