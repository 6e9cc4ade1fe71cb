#include "track/posed_bodies.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <limits>

namespace dynahand::track {

void PosedBodies::set(std::span<const physics::ConvexShape* const> shapes, std::span<const Pose> poses) {
  assert(shapes.size() == poses.size() && shapes.size() <= 32);
  shapes_.assign(shapes.begin(), shapes.end());
  poses_.assign(poses.begin(), poses.end());
  centroids_.resize(shapes.size());
  radii_.resize(shapes.size());
  for (std::size_t i = 0; i < shapes.size(); ++i) {
    radii_[i] = shapes_[i]->boundingRadius();
    centroids_[i] = poses_[i].transform(shapes_[i]->centroid());
  }
}

void PosedBodies::setPose(int body, const Pose& pose) {
  const auto i = static_cast<std::size_t>(body);
  poses_[i] = pose;
  centroids_[i] = pose.transform(shapes_[i]->centroid());
}

SurfaceHit PosedBodies::nearest(const Vec3& p, BodyMask mask) const {
  // Lower bounds on the distance to each allowed body, sorted ascending (insertion
  // sort: at most 32 entries, stable so ties keep body order).
  std::array<std::pair<float, int>, 32> order;
  int count = 0;
  for (int i = 0; i < size(); ++i) {
    if (!(mask >> i & 1u)) continue;
    const float bound = std::max(0.0f, (p - centroids_[static_cast<std::size_t>(i)]).norm() -
                                           radii_[static_cast<std::size_t>(i)]);
    int k = count++;
    while (k > 0 && order[static_cast<std::size_t>(k - 1)].first > bound) {
      order[static_cast<std::size_t>(k)] = order[static_cast<std::size_t>(k - 1)];
      --k;
    }
    order[static_cast<std::size_t>(k)] = {bound, i};
  }
  SurfaceHit best;
  best.distance = std::numeric_limits<float>::infinity();
  for (int k = 0; k < count; ++k) {
    const auto [bound, i] = order[static_cast<std::size_t>(k)];
    if (bound > best.distance) break;
    const Pose& pose = poses_[static_cast<std::size_t>(i)];
    const Vec3 local = pose.inverseTransform(p);
    Vec3 closest;
    int face = -1;
    const float sd = shapes_[static_cast<std::size_t>(i)]->query(local, &closest, &face);
    const float d = std::abs(sd);
    if (d < best.distance || (d == best.distance && i < best.body)) {
      best = {i, face, d, sd, closest};
    }
  }
  return best;
}

}  // namespace dynahand::track
