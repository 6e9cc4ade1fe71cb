// What every model a reader returns must be (model.h): a tree of bodies with valid hulls
// and positive finite masses, joints and keypoints that refer to bodies, and a model that
// saves as a model file that loads again and saves byte-identically.
#pragma once

#include <cmath>
#include <vector>

#include "dynahand/model.h"
#include "fuzz_util.h"

namespace dynahand::fuzz {

inline void checkModel(const model::ArticulatedModel& m) {
  const int n = m.bodyCount();
  FUZZ_CHECK(n > 0);
  FUZZ_CHECK(m.root() >= 0 && m.root() < n);
  FUZZ_CHECK(m.bodies()[static_cast<std::size_t>(m.root())].parent == -1);
  FUZZ_CHECK(m.jointCount() == n - 1);  // a tree: every body but the root is one joint's child
  FUZZ_CHECK(std::isfinite(m.metadata().referenceLength) && m.metadata().referenceLength >= 0.0f);
  for (const model::Body& b : m.bodies()) {
    FUZZ_CHECK(!b.name.empty());
    FUZZ_CHECK(std::isfinite(b.mass) && b.mass > 0.0f);
    FUZZ_CHECK(b.shape.vertices().size() >= 4 && b.shape.faces().size() >= 4);
    FUZZ_CHECK(b.parent >= -1 && b.parent < n);
    FUZZ_CHECK(b.joint >= -1 && b.joint < m.jointCount());
  }
  for (const model::Joint& j : m.joints()) {
    FUZZ_CHECK(j.parent >= 0 && j.parent < n && j.child >= 0 && j.child < n);
    FUZZ_CHECK(j.parent != j.child);
    FUZZ_CHECK(std::abs(j.frame.norm() - 1.0f) < 1e-3f);
    FUZZ_CHECK(j.anchorParent.allFinite() && j.anchorChild.allFinite());
    for (int axis = 0; axis < 3; ++axis) FUZZ_CHECK(j.minAngle[axis] <= j.maxAngle[axis]);
  }
  // Kinematic order: a permutation with every parent before its children.
  const std::vector<int>& order = m.kinematicOrder();
  FUZZ_CHECK(static_cast<int>(order.size()) == n);
  std::vector<int> position(static_cast<std::size_t>(n), -1);
  for (int i = 0; i < n; ++i) {
    const int b = order[static_cast<std::size_t>(i)];
    FUZZ_CHECK(b >= 0 && b < n && position[static_cast<std::size_t>(b)] == -1);
    position[static_cast<std::size_t>(b)] = i;
  }
  for (int b = 0; b < n; ++b) {
    const int parent = m.bodies()[static_cast<std::size_t>(b)].parent;
    if (parent >= 0)
      FUZZ_CHECK(position[static_cast<std::size_t>(parent)] <
                 position[static_cast<std::size_t>(b)]);
  }
  for (const model::Keypoint& k : m.keypoints()) {
    FUZZ_CHECK(k.body >= 0 && k.body < n);
    FUZZ_CHECK(k.point.allFinite() && std::isfinite(k.radius) && k.radius >= 0.0f);
  }
  if (m.hasKeypoints21()) {
    for (const int k : m.keypoints21Indices())
      FUZZ_CHECK(k >= 0 && k < static_cast<int>(m.keypoints().size()));
  }
  if (m.hasOpenXrJoints()) {
    for (const model::BodyFrame& f : m.openXrFrames()) {
      FUZZ_CHECK(f.body >= 0 && f.body < n);
      FUZZ_CHECK(f.local.p.allFinite() && std::abs(f.local.q.norm() - 1.0f) < 1e-3f);
    }
  }
  // Saved, it loads again and saves the same bytes (model_json.cpp: canonical writing).
  const std::string saved = model::modelToJson(m);
  const Result<model::ArticulatedModel> again = model::parseModel(saved, "saved.json");
  if (!again) {
    std::fprintf(stderr, "a returned model does not load once saved: %s\n",
                 again.message().c_str());
    FUZZ_CHECK(again.ok());
  }
  FUZZ_CHECK(model::modelToJson(*again) == saved);
}

}  // namespace dynahand::fuzz
