#include "track/simulation.h"

#include <algorithm>
#include <cassert>
#include <cmath>

#include "track/silhouette.h"

namespace dynahand::track {

namespace {
constexpr float kCutEndCos = 0.5f;  // forearm faces within 60 degrees of the elbow direction
// Fingertips within this many pixels of the mask are on the hand; farther than the search
// radius, the fit is too far off for a pull in the image plane to mean anything.
constexpr int kTipOnHandPixels = 1;
constexpr int kTipSearchPixels = 40;
bool samePose(const Pose& a, const Pose& b) {
  return a.p == b.p && a.q.coeffs() == b.q.coeffs();
}

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

void Simulator::beginFrame(const Simulator* shared) {
  frameStartRowsInput_ = nullptr;
  frameStart_.clear();
  frameStartPoses_.clear();
  frameStartPoints_ = nullptr;
  shared_ = shared;
  pass_ = 0;
  // The sample points are new every frame: last frame's bodies are no guide, the shared
  // mapping's (at this frame's start poses) are.
  if (shared != nullptr) hints_ = shared->hints_;
}

int Simulator::labelCell(const Intrinsics& k, const Vec3& p) const {
  if (!(p.z() > 0.0f)) return -1;
  const Vec2 pixel = k.project(p);
  const float u = pixel.x() * labelScale_, v = pixel.y() * labelScale_;
  if (!(u >= 0.0f && v >= 0.0f && u < static_cast<float>(kLabelColumns) &&
        v < static_cast<float>(labelRows_)))
    return -1;
  return static_cast<int>(v) * kLabelColumns + static_cast<int>(u);
}

void Simulator::mapFrameStart(const HandRig& rig, const FrameInput& input) {
  beginFrame();
  pose(rig, bodies_);
  // Last frame's nearest bodies, looked up by pixel: a good first guess for this frame's new
  // points (the answers do not depend on it; the bulk query only culls more).
  const CloudFrame* cloud = input.cloud;
  if (cloud != nullptr) {
    const Intrinsics& k = cloud->intrinsics;
    labelScale_ = kLabelColumns / static_cast<float>(std::max(k.width, 1));
    const int rows = static_cast<int>(std::ceil(static_cast<float>(k.height) * labelScale_));
    if (labelRows_ != rows) {
      labelRows_ = rows;
      labels_.assign(static_cast<std::size_t>(kLabelColumns * labelRows_), -1);
    }
    hints_.resize(input.points.size());
    pointCells_.resize(input.points.size());
    for (std::size_t i = 0; i < input.points.size(); ++i) {
      const int cell = pointCells_[i] = labelCell(k, input.points[i]);
      if (cell >= 0 && labels_[static_cast<std::size_t>(cell)] >= 0)
        hints_[i] = labels_[static_cast<std::size_t>(cell)];
    }
  }
  // The other subsets first, only for their nearest bodies: the simulations sharing this
  // mapping start their own from there (a body found at the start poses is close to the
  // answer a substep later, which makes the bulk query cull more).
  for (int subset = 1; subset < settings_.pointSubsets; ++subset) mapPoints(rig, input, subset);
  mapPoints(rig, input, 0);  // every simulation's first substep uses subset 0
  frameStart_ = attachments_;
  frameStartSubset_ = 0;
  frameStartPoses_ = poses_;
  frameStartPoints_ = input.points.data();
  if (cloud != nullptr) {
    std::fill(labels_.begin(), labels_.end(), -1);
    for (std::size_t i = 0; i < input.points.size(); ++i) {
      const int cell = pointCells_[i];
      if (cell >= 0) labels_[static_cast<std::size_t>(cell)] = static_cast<std::int8_t>(hints_[i]);
    }
  }
}

void Simulator::keepPoints(std::span<const int> kept, std::span<const Vec3> keptPoints) {
  assert(kept.size() == keptPoints.size() && kept.size() <= frameStart_.size());
  for (std::size_t k = 0; k < kept.size(); ++k) {
    const auto i = static_cast<std::size_t>(kept[k]);  // i >= k: gathered in place
    frameStart_[k] = frameStart_[i];
    hints_[k] = hints_[i];
  }
  frameStart_.resize(kept.size());
  hints_.resize(kept.size());
  frameStartPoints_ = keptPoints.data();
}

void Simulator::prepareFrameStartRows(HandRig& rig, const FrameInput& input) {
  const int pass = pass_;
  addRows(rig, input);
  pass_ = pass;
  frameStartRows_ = rig.world().rows();
  frameStartRowsInput_ = &input;
  frameStartRowsPositions_ = rig.world().state().position;
  frameStartRowsOrientations_ = rig.world().state().orientation;
}

Simulator::Attachment Simulator::map(const HandRig& rig, const Vec3& p, BodyMask mask,
                                     bool anyDistance, int* hint) const {
  const SurfaceHit hit = bodies_.nearestPlanar(p, mask, hint ? *hint : -1);
  if (hint) *hint = hit.body;
  return attachment(rig, hit, anyDistance);
}

Simulator::Attachment Simulator::attachment(const HandRig& rig, const SurfaceHit& hit,
                                            bool anyDistance) const {
  Attachment a;
  if (hit.body < 0 || (!anyDistance && hit.distance > settings_.maxAttachDistance)) return a;
  const Pose& pose = bodies_.pose(hit.body);
  const Vec3& localNormal =
      bodies_.shape(hit.body).faces()[static_cast<std::size_t>(hit.face)].normal;
  // The forearm's elbow-side end is where the arm was cut off, not a surface.
  if (hit.body == rig.anatomy().forearm && localNormal.dot(rig.anatomy().forearmAxis) > kCutEndCos)
    return a;
  a.body = hit.body;
  a.localPoint = hit.localPoint;
  a.normal = pose.rotate(localNormal);
  return a;
}

void Simulator::mapPoints(const HandRig& rig, const FrameInput& input, int subset) {
  // Points outside the subset keep their last attachment and hint (unused this substep).
  hints_.resize(input.points.size(), -1);
  attachments_.resize(input.points.size());
  const auto stride = static_cast<std::size_t>(settings_.pointSubsets);
  subsetPoints_.clear();
  subsetHints_.clear();
  for (auto i = static_cast<std::size_t>(subset); i < input.points.size(); i += stride) {
    subsetPoints_.push_back(input.points[i]);
    subsetHints_.push_back(hints_[i]);
  }
  subsetHits_.resize(subsetPoints_.size());
  bodies_.nearestPlanarMany(subsetPoints_, subsetHints_, subsetHits_);
  std::size_t k = 0;
  for (auto i = static_cast<std::size_t>(subset); i < input.points.size(); i += stride, ++k) {
    hints_[i] = subsetHints_[k];
    attachments_[i] = attachment(rig, subsetHits_[k], false);
  }
}

void Simulator::addRows(HandRig& rig, const FrameInput& input) {
  auto& world = rig.world();
  auto& rows = world.rows();
  if (pass_ == 0 && shared_ != nullptr && shared_->frameStartRowsInput_ == &input) {
    const physics::WorldState& state = world.state();
    const auto sameOrientation = [](const Quat& a, const Quat& b) {
      return a.coeffs() == b.coeffs();
    };
    if (state.position == shared_->frameStartRowsPositions_ &&
        std::equal(state.orientation.begin(), state.orientation.end(),
                   shared_->frameStartRowsOrientations_.begin(),
                   shared_->frameStartRowsOrientations_.end(), sameOrientation)) {
      rows = shared_->frameStartRows_;  // the same rows, bit for bit: built from the same data
      ++pass_;
      return;
    }
  }
  rows.clear();
  pose(rig, bodies_);
  const int subset = pass_++ % settings_.pointSubsets;
  const auto stride = static_cast<std::size_t>(settings_.pointSubsets);
  const auto first = static_cast<std::size_t>(subset);
  const std::size_t used =
      input.points.size() > first ? (input.points.size() - first - 1) / stride + 1 : 0;
  float total = static_cast<float>(used + input.labelled.size());
  const bool weighted = input.weights.size() == input.points.size() && !input.weights.empty();
  if (weighted) {
    total = static_cast<float>(input.labelled.size());
    for (std::size_t i = first; i < input.points.size(); i += stride) total += input.weights[i];
  }
  if (!(total > 0.0f)) return;
  const float cap = settings_.pullForce * settings_.stepDt / total;
  auto capOf = [&](std::size_t i) { return weighted ? cap * input.weights[i] : cap; };

  auto attach = [&](const Attachment& a, const Vec3& p, float rowCap) {
    if (a.body < 0) return;
    // A face turned away from the camera cannot have produced this sample: the body
    // must instead lie behind it along the camera ray (free space in front of p).
    if (a.normal.dot(p) > 0.0f) {
      rows.addLineOfSight(a.body, a.localPoint, p.normalized(), p, rowCap);
    } else {
      rows.addSurface(a.body, a.localPoint, a.normal, p, rowCap);
    }
  };
  // Every simulation of a frame starts from the same state, so the first substep's mapping
  // is the same for all of them: computed once (poses compared bit for bit), here or by
  // the simulator this one shares it with.
  const Simulator& start = shared_ != nullptr ? *shared_ : *this;
  const bool sameAsFrameStart =
      !start.frameStart_.empty() && start.frameStartSubset_ == subset &&
      start.frameStartPoints_ == input.points.data() &&
      start.frameStart_.size() == input.points.size() &&
      std::equal(poses_.begin(), poses_.end(), start.frameStartPoses_.begin(),
                 start.frameStartPoses_.end(), samePose);
  if (sameAsFrameStart) {
    for (std::size_t i = first; i < input.points.size(); i += stride)
      attach(start.frameStart_[i], input.points[i], capOf(i));
  } else {
    const bool keep = shared_ == nullptr && frameStart_.empty() && frameStartPoints_ == nullptr;
    mapPoints(rig, input, subset);
    for (std::size_t i = first; i < input.points.size(); i += stride)
      attach(attachments_[i], input.points[i], capOf(i));
    if (keep) {
      frameStart_ = attachments_;
      frameStartSubset_ = subset;
      frameStartPoses_ = poses_;
      frameStartPoints_ = input.points.data();
    }
  }
  for (const LabelledPoint& l : input.labelled)
    attach(map(rig, l.point, l.bodies, true, nullptr), l.point, cap * l.capScale);

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
      // The forearm leaves the segmented region: its unobserved part lies outside the
      // planes, which would turn it to point along the view ray (70 degrees off).
      if (b == rig.anatomy().forearm) continue;
      world.addBoundary(b, -plane.normal, 0.0f, boundaryCap, settings_.boundaryMargin,
                        settings_.boundaryBand);
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
