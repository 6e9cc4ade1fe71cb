// Swing-twist joint angles (convention in include/dynahand/physics_angles.h).
#include <algorithm>
#include <cmath>

#include "dynahand/physics_angles.h"

namespace dynahand::physics {

Vec3 decomposeJointRotation(const Quat& relative) {
  const Quat q = relative.normalized();
  const Vec3 d = q * Vec3::UnitX();
  const float flexion = std::atan2(d.y(), d.x());
  const float abduction = std::asin(std::clamp(-d.z(), -1.0f, 1.0f));
  // Twist: what remains after undoing the shortest swing X -> d. That swing's axis is
  // perpendicular to X, so (swing^-1 q) has the w and x of q scaled by the same positive
  // factor, and the twist angle can be read from q directly.
  float angle = 2.0f * std::atan2(q.x(), q.w());
  if (angle > static_cast<float>(M_PI)) angle -= 2.0f * static_cast<float>(M_PI);
  if (angle <= -static_cast<float>(M_PI)) angle += 2.0f * static_cast<float>(M_PI);
  return {flexion, abduction, angle};
}

Quat composeJointRotation(const Vec3& angles) {
  const float f = angles.x(), a = angles.y();
  const Vec3 d(std::cos(a) * std::cos(f), std::cos(a) * std::sin(f), -std::sin(a));
  const Quat swing = shortestRotation(Vec3::UnitX(), d);
  const Quat twist(Eigen::AngleAxisf(angles.z(), Vec3::UnitX()));
  return (swing * twist).normalized();
}

}  // namespace dynahand::physics
