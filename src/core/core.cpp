// The out-of-line parts of dynahand/core.h: hashing, pose interpolation, the opposite-vector
// case of shortestRotation.
#include "dynahand/core.h"

namespace dynahand {

void Fnv1a::add(const void* data, std::size_t bytes) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < bytes; ++i) {
    h_ ^= p[i];
    h_ *= 1099511628211ull;
  }
}

Pose interpolate(const Pose& a, const Pose& b, float t) {
  return {a.p + (b.p - a.p) * t, a.q.slerp(t, b.q).normalized()};
}

Quat shortestRotationOpposite(const Vec3& from, const Vec3& to) {
  return Quat::FromTwoVectors(from, to);
}

}  // namespace dynahand
