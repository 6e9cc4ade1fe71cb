#include "track/simulation.h"

#include <algorithm>

#include "track/silhouette.h"

namespace dynahand::track {

namespace {
constexpr float kCutEndCos = 0.5f;  // forearm faces within 60 degrees of the elbow direction
// Fingertips within this many pixels of the mask are on the hand; farther than the search
// radius, the fit is too far off for a pull in the image plane to mean anything.
constexpr int kTipOnHandPixels = 1;
constexpr int kTipSearchPixels = 40;
}  // namespace

void Simulator::pose(const HandRig& rig, PosedBodies& bodies) {
  const auto& world = rig.world();
  const int n = world.bodyCount();
  shapes_.resize(static_cast<std::size_t>(n));
  poses_.resize(static_cast<std::size_t>(n));
  for (int b = 0; b < n; ++b) {
    shapes_[static_cast<std::size_t>(b)] = &world.bodyShape(b);
    poses_[static_cast<std::size_t>(b)] = world.pose(b);
  }
  bodies.set(shapes_, poses_);
}

void Simulator::addRows(HandRig& rig, const FrameInput& input) {
  auto& world = rig.world();
  auto& rows = world.rows();
  rows.clear();
  pose(rig, bodies_);
  const std::size_t total = input.points.size() + input.labelled.size();
  if (total == 0) return;
  const float cap = settings_.pullForce * settings_.stepDt / static_cast<float>(total);

  hints_.resize(input.points.size(), -1);
  const int forearm = rig.anatomy().forearm;
  const Vec3 forearmAxis = rig.anatomy().forearmAxis;
  auto attach = [&](const Vec3& p, BodyMask mask, float rowCap, bool anyDistance, int* hint) {
    const SurfaceHit hit = bodies_.nearestPlanar(p, mask, hint ? *hint : -1);
    if (hint) *hint = hit.body;
    if (hit.body < 0 || (!anyDistance && hit.distance > settings_.maxAttachDistance)) return;
    const Pose& pose = bodies_.pose(hit.body);
    const Vec3& localNormal =
        bodies_.shape(hit.body).faces()[static_cast<std::size_t>(hit.face)].normal;
    // The forearm's elbow-side end is where the arm was cut off, not a surface.
    if (hit.body == forearm && localNormal.dot(forearmAxis) > kCutEndCos) return;
    const Vec3 normal = pose.rotate(localNormal);
    // A face turned away from the camera cannot have produced this sample: the body
    // must instead lie behind it along the camera ray (free space in front of p).
    if (normal.dot(p) > 0.0f) {
      rows.addLineOfSight(hit.body, hit.localPoint, p.normalized(), p, rowCap);
    } else {
      rows.addSurface(hit.body, hit.localPoint, normal, p, rowCap);
    }
  };
  for (std::size_t i = 0; i < input.points.size(); ++i)
    attach(input.points[i], kAllBodies, cap, false, &hints_[i]);
  for (const LabelledPoint& l : input.labelled)
    attach(l.point, l.bodies, cap * l.capScale, true, nullptr);

  if (input.cloud != nullptr && settings_.silhouetteForce > 0.0f) {
    const float tipCap = settings_.silhouetteForce * settings_.stepDt;
    for (int f = 0; f < kFingerCount; ++f) {
      const int body = rig.anatomy().fingers[static_cast<std::size_t>(f)][2];
      const Vec3& local = rig.anatomy().tipLocal[static_cast<std::size_t>(f)];
      const auto pull = silhouettePull(*input.cloud, bodies_.pose(body).transform(local),
                                       kTipOnHandPixels, kTipSearchPixels);
      if (pull) rows.addHalfSpace(body, local, pull->inward, pull->target, tipCap);
    }
  }

  if (input.hold != nullptr) {
    const AxisHold& h = *input.hold;
    rows.addSurface(h.body, h.localPoint, h.axis, h.target, h.force * settings_.stepDt);
  }

  const float boundaryCap = settings_.boundaryForce * settings_.stepDt;
  for (const BoundaryPlane& plane : input.planes) {
    // BoundaryPlane keeps points with normal·p <= 0: the allowed side of the world
    // plane (-normal)·x >= 0.
    for (int b = 0; b < world.bodyCount(); ++b) {
      world.addBoundary(b, -plane.normal, 0.0f, boundaryCap, settings_.boundaryMargin);
    }
  }
}

void Simulator::run(HandRig& rig, const FrameInput& input, int substeps) {
  for (int s = 0; s < substeps; ++s) {
    addRows(rig, input);
    rig.world().step(settings_.stepDt);
  }
}

}  // namespace dynahand::track
