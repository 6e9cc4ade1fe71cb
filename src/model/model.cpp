// buildModel: validation (errors carry the JSON path of the first problem) and compilation
// of a ModelSpec into an ArticulatedModel; uniform scaling and mirroring.
#include <algorithm>
#include <cassert>
#include <cmath>
#include <numbers>

#include <fmt/format.h>

#include "dynahand/model.h"
#include "dynahand/model_pose.h"
#include "model/hand_layout.h"

namespace dynahand::model {
namespace {

bool finite(const Vec3& v) {
  return v.allFinite();
}

Error pathError(const std::string& path, const std::string& problem) {
  return Error{path + ": " + problem};
}

std::string vecPath(const std::string& base, int axis) {
  return fmt::format("{}[{}]", base, axis);
}

// The file names limits in degrees; messages use the file's names.
std::optional<Error> checkLimits(const JointSpec& joint, const std::string& path) {
  constexpr float kHalfPi = std::numbers::pi_v<float> / 2.0f;
  constexpr float kPi = std::numbers::pi_v<float>;
  for (int axis = 0; axis < 3; ++axis) {
    const float lo = joint.minAngle[axis];
    const float hi = joint.maxAngle[axis];
    if (!std::isfinite(lo))
      return pathError(vecPath(path + ".minDeg", axis), "not a finite number");
    if (!std::isfinite(hi))
      return pathError(vecPath(path + ".maxDeg", axis), "not a finite number");
    if (lo > hi) return pathError(vecPath(path + ".minDeg", axis), "greater than maxDeg");
    // The swing is singular at |abduction| = 90 and at flexion = 180 degrees.
    const float bound = axis == 0 ? kPi * (179.0f / 180.0f) : axis == 1 ? kHalfPi - 1e-3f : kPi;
    if (lo < -bound || hi > bound) {
      const char* problem = axis == 0   ? "flexion limits must lie within [-179, 179] degrees"
                            : axis == 1 ? "abduction limits must lie inside (-90, 90) degrees"
                                        : "twist limits must lie within [-180, 180] degrees";
      return pathError(vecPath(path + (lo < -bound ? ".minDeg" : ".maxDeg"), axis), problem);
    }
  }
  return std::nullopt;
}

}  // namespace

int ArticulatedModel::bodyIndex(const std::string& name) const {
  for (size_t i = 0; i < bodies_.size(); ++i) {
    if (bodies_[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

int ArticulatedModel::keypointIndex(const std::string& name) const {
  for (size_t i = 0; i < keypoints_.size(); ++i) {
    if (keypoints_[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

ModelSpec ArticulatedModel::spec() const {
  ModelSpec spec;
  spec.metadata = metadata_;
  for (const Body& body : bodies_)
    spec.bodies.push_back({body.name, body.vertices, body.mass, std::nullopt});
  for (const Joint& joint : joints_) {
    spec.joints.push_back({bodies_[static_cast<size_t>(joint.parent)].name,
                           bodies_[static_cast<size_t>(joint.child)].name, joint.anchorParent,
                           joint.anchorChild, joint.frame, joint.minAngle, joint.maxAngle});
  }
  spec.collision = collision_;
  for (const Keypoint& kp : keypoints_) {
    spec.keypoints.push_back(
        {kp.name, bodies_[static_cast<size_t>(kp.body)].name, kp.point, kp.radius});
  }
  return spec;
}

Result<ArticulatedModel> buildModel(const ModelSpec& spec) {
  ArticulatedModel model;
  model.metadata_ = spec.metadata;
  if (!std::isfinite(spec.metadata.referenceLength) || spec.metadata.referenceLength < 0.0f) {
    return pathError("metadata.referenceLength", "must be a finite number >= 0");
  }
  if (spec.bodies.empty()) return pathError("bodies", "no bodies");
  const int bodyCount = static_cast<int>(spec.bodies.size());

  // Bodies: names, hulls, masses.
  for (int i = 0; i < bodyCount; ++i) {
    const BodySpec& b = spec.bodies[static_cast<size_t>(i)];
    const std::string path = fmt::format("bodies[{}]", i);
    if (b.name.empty()) return pathError(path + ".name", "empty");
    for (int k = 0; k < i; ++k) {
      if (spec.bodies[static_cast<size_t>(k)].name == b.name) {
        return pathError(path + ".name",
                         fmt::format("duplicate name '{}' (also bodies[{}])", b.name, k));
      }
    }
    for (size_t v = 0; v < b.vertices.size(); ++v) {
      if (!finite(b.vertices[v]))
        return pathError(fmt::format("{}.vertices[{}]", path, v), "not finite");
    }
    Result<physics::ConvexShape> shape = physics::ConvexShape::fromPoints(b.vertices);
    // Non-finite points were caught above: what remains is a flat or too small point set.
    if (!shape)
      return pathError(path + ".vertices",
                       "fewer than 4 non-coplanar points (" + shape.message() + ")");
    if (b.mass && b.density) return pathError(path, "give mass or density, not both");
    float mass = 0.0f;
    if (b.mass) {
      if (!std::isfinite(*b.mass) || *b.mass <= 0.0f)
        return pathError(path + ".mass", "must be a positive number (kg)");
      mass = *b.mass;
    } else {
      const float density = b.density.value_or(kDefaultDensity);
      if (!std::isfinite(density) || density <= 0.0f) {
        return pathError(path + ".density", "must be a positive number (kg/m^3)");
      }
      mass = density * shape->volume();
      if (!std::isfinite(mass) || mass <= 0.0f) {
        return pathError(path + ".density",
                         fmt::format("gives a mass of {} kg (hull volume {} m^3); the mass must "
                                     "be a positive finite number",
                                     mass, shape->volume()));
      }
    }
    model.bodies_.push_back(Body{b.name, b.vertices, std::move(shape).value(), mass, -1, -1});
  }

  auto findBody = [&](const std::string& name) { return model.bodyIndex(name); };

  // Joints: references, anchors, frames, limits; each body the child of at most one joint.
  for (size_t j = 0; j < spec.joints.size(); ++j) {
    const JointSpec& js = spec.joints[j];
    const std::string path = fmt::format("joints[{}]", j);
    const int parent = findBody(js.parent);
    const int child = findBody(js.child);
    if (parent < 0) return pathError(path + ".parent", fmt::format("unknown body '{}'", js.parent));
    if (child < 0) return pathError(path + ".child", fmt::format("unknown body '{}'", js.child));
    if (parent == child)
      return pathError(path, fmt::format("parent and child are the same body '{}'", js.child));
    Body& childBody = model.bodies_[static_cast<size_t>(child)];
    if (childBody.joint >= 0) {
      return pathError(path + ".child", fmt::format("body '{}' is already the child of joints[{}]",
                                                    js.child, childBody.joint));
    }
    if (!finite(js.anchorParent)) return pathError(path + ".anchorParent", "not finite");
    if (!finite(js.anchorChild)) return pathError(path + ".anchorChild", "not finite");
    const float norm = js.frame.coeffs().norm();
    if (!js.frame.coeffs().allFinite() || std::abs(norm - 1.0f) > 1e-3f) {
      return pathError(path + ".frame", "not a unit quaternion [w, x, y, z]");
    }
    if (std::optional<Error> e = checkLimits(js, path)) return *e;
    childBody.parent = parent;
    childBody.joint = static_cast<int>(j);
    // A frame that is unit to float precision is kept bit-exact (file round trips).
    const Quat frame = std::abs(norm - 1.0f) < 1e-5f ? js.frame : js.frame.normalized();
    model.joints_.push_back(
        Joint{parent, child, js.anchorParent, js.anchorChild, frame, js.minAngle, js.maxAngle});
  }

  // The parent graph must be a tree: no cycles, exactly one root.
  for (int i = 0; i < bodyCount; ++i) {
    int b = i;
    for (int steps = 0; b >= 0; ++steps) {
      if (steps > bodyCount) {
        std::string cycle = model.bodies_[static_cast<size_t>(i)].name;
        int c = model.bodies_[static_cast<size_t>(i)].parent;
        for (int k = 0; k < bodyCount && c != i;
             ++k, c = model.bodies_[static_cast<size_t>(c)].parent) {
          cycle += " -> " + model.bodies_[static_cast<size_t>(c)].name;
        }
        return pathError("joints", fmt::format("cycle in the parent graph: {} -> {}", cycle,
                                               model.bodies_[static_cast<size_t>(i)].name));
      }
      b = model.bodies_[static_cast<size_t>(b)].parent;
    }
  }
  std::vector<int> roots;
  for (int i = 0; i < bodyCount; ++i) {
    if (model.bodies_[static_cast<size_t>(i)].parent < 0) roots.push_back(i);
  }
  if (roots.size() != 1) {
    std::string names;
    for (int r : roots)
      names += (names.empty() ? "'" : ", '") + model.bodies_[static_cast<size_t>(r)].name + "'";
    return pathError("joints",
                     fmt::format("{} bodies have no parent joint ({}); exactly one root is allowed",
                                 roots.size(), names));
  }
  model.root_ = roots[0];

  // Kinematic order: by depth, then by index (stable, deterministic).
  std::vector<int> depth(static_cast<size_t>(bodyCount), 0);
  for (int i = 0; i < bodyCount; ++i) {
    for (int b = model.bodies_[static_cast<size_t>(i)].parent; b >= 0;
         b = model.bodies_[static_cast<size_t>(b)].parent) {
      ++depth[static_cast<size_t>(i)];
    }
  }
  model.order_.resize(static_cast<size_t>(bodyCount));
  for (int i = 0; i < bodyCount; ++i) model.order_[static_cast<size_t>(i)] = i;
  std::stable_sort(model.order_.begin(), model.order_.end(), [&](int a, int b) {
    return depth[static_cast<size_t>(a)] < depth[static_cast<size_t>(b)];
  });

  const size_t n = static_cast<size_t>(bodyCount);
  model.ancestorOrSelf_.assign(n * n, 0);
  for (int i = 0; i < bodyCount; ++i) {
    for (int b = i; b >= 0; b = model.bodies_[static_cast<size_t>(b)].parent) {
      model.ancestorOrSelf_[static_cast<size_t>(i) * n + static_cast<size_t>(b)] = 1;
    }
  }

  // Collision filter.
  model.collision_ = spec.collision;
  model.collides_.assign(n * n, 1);
  for (size_t i = 0; i < n; ++i) model.collides_[i * n + i] = 0;
  if (spec.collision.ignoreJointNeighbours) {
    for (const Joint& j : model.joints_) {
      model.collides_[static_cast<size_t>(j.parent) * n + static_cast<size_t>(j.child)] = 0;
      model.collides_[static_cast<size_t>(j.child) * n + static_cast<size_t>(j.parent)] = 0;
    }
  }
  for (size_t p = 0; p < spec.collision.ignoredPairs.size(); ++p) {
    const auto& [nameA, nameB] = spec.collision.ignoredPairs[p];
    const int a = findBody(nameA);
    const int b = findBody(nameB);
    if (a < 0)
      return pathError(fmt::format("collision.ignorePairs[{}][0]", p),
                       fmt::format("unknown body '{}'", nameA));
    if (b < 0)
      return pathError(fmt::format("collision.ignorePairs[{}][1]", p),
                       fmt::format("unknown body '{}'", nameB));
    model.collides_[static_cast<size_t>(a) * n + static_cast<size_t>(b)] = 0;
    model.collides_[static_cast<size_t>(b) * n + static_cast<size_t>(a)] = 0;
  }

  // Keypoints.
  for (size_t k = 0; k < spec.keypoints.size(); ++k) {
    const KeypointSpec& ks = spec.keypoints[k];
    const std::string path = fmt::format("keypoints[{}]", k);
    if (ks.name.empty()) return pathError(path + ".name", "empty");
    if (model.keypointIndex(ks.name) >= 0)
      return pathError(path + ".name", fmt::format("duplicate name '{}'", ks.name));
    const int body = findBody(ks.body);
    if (body < 0) return pathError(path + ".body", fmt::format("unknown body '{}'", ks.body));
    if (!finite(ks.point)) return pathError(path + ".point", "not finite");
    if (!std::isfinite(ks.radius) || ks.radius < 0.0f)
      return pathError(path + ".radius", "must be a number >= 0");
    model.keypoints_.push_back(Keypoint{ks.name, body, ks.point, ks.radius});
  }

  detail::resolveHandLayout(model.keypoints_, model.hasKeypoints21_, model.keypoints21_);
  if (model.hasKeypoints21_) model.hasOpenXr_ = detail::computeOpenXrFrames(model, model.openXr_);
  return model;
}

ArticulatedModel scaleModel(const ArticulatedModel& model, float factor) {
  assert(factor > 0.0f && std::isfinite(factor) && "scaleModel: factor must be positive");
  ModelSpec spec = model.spec();
  spec.metadata.referenceLength *= factor;
  for (BodySpec& b : spec.bodies) {
    for (Vec3& v : b.vertices) v *= factor;
    if (b.mass) *b.mass *= factor * factor * factor;
  }
  for (JointSpec& j : spec.joints) {
    j.anchorParent *= factor;
    j.anchorChild *= factor;
  }
  for (KeypointSpec& k : spec.keypoints) {
    k.point *= factor;
    k.radius *= factor;
  }
  Result<ArticulatedModel> scaled = buildModel(spec);
  assert(scaled.ok() && "scaling a valid model keeps it valid");
  return std::move(scaled).value();
}

ArticulatedModel mirrorModel(const ArticulatedModel& model) {
  ModelSpec spec = model.spec();
  const auto mirror = [](Vec3 v) { return Vec3(-v.x(), v.y(), v.z()); };
  if (spec.metadata.handedness == Handedness::Right) {
    spec.metadata.handedness = Handedness::Left;
  } else if (spec.metadata.handedness == Handedness::Left) {
    spec.metadata.handedness = Handedness::Right;
  }
  for (BodySpec& b : spec.bodies) {
    for (Vec3& v : b.vertices) v = mirror(v);
  }
  for (JointSpec& j : spec.joints) {
    j.anchorParent = mirror(j.anchorParent);
    j.anchorChild = mirror(j.anchorChild);
    // M R M with M = diag(-1, 1, 1): rotations about x keep their angle, about y and z flip.
    j.frame = Quat(j.frame.w(), j.frame.x(), -j.frame.y(), -j.frame.z());
    const Vec3 lo = j.minAngle;
    const Vec3 hi = j.maxAngle;
    j.minAngle = Vec3(lo.x(), -hi.y(), -hi.z());
    j.maxAngle = Vec3(hi.x(), -lo.y(), -lo.z());
  }
  for (KeypointSpec& k : spec.keypoints) k.point = mirror(k.point);
  Result<ArticulatedModel> mirrored = buildModel(spec);
  assert(mirrored.ok() && "mirroring a valid model keeps it valid");
  return std::move(mirrored).value();
}

}  // namespace dynahand::model
