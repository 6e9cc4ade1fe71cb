// buildModel: validation (errors carry the JSON path of the first problem) and compilation
// of a ModelSpec into an ArticulatedModel; uniform scaling and mirroring.
#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdint>
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

namespace {

// Index of the body named `name` in `bodies`, -1 when none.
int bodyIndexIn(const std::vector<Body>& bodies, const std::string& name) {
  for (std::size_t i = 0; i < bodies.size(); ++i)
    if (bodies[i].name == name) return static_cast<int>(i);
  return -1;
}

// Body i of the spec: its name (unique), hull and mass; parent and joint are set later.
Result<Body> compileBody(const ModelSpec& spec, int i) {
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
  return Body{b.name, b.vertices, std::move(shape).value(), mass, -1, -1};
}

// Joints: references, anchors, frames, limits; each body the child of at most one joint
// (its parent and joint set in `bodies`).
Result<std::vector<Joint>> compileJoints(const ModelSpec& spec, std::vector<Body>& bodies) {
  std::vector<Joint> joints;
  for (size_t j = 0; j < spec.joints.size(); ++j) {
    const JointSpec& js = spec.joints[j];
    const std::string path = fmt::format("joints[{}]", j);
    const int parent = bodyIndexIn(bodies, js.parent);
    const int child = bodyIndexIn(bodies, js.child);
    if (parent < 0) return pathError(path + ".parent", fmt::format("unknown body '{}'", js.parent));
    if (child < 0) return pathError(path + ".child", fmt::format("unknown body '{}'", js.child));
    if (parent == child)
      return pathError(path, fmt::format("parent and child are the same body '{}'", js.child));
    Body& childBody = bodies[static_cast<size_t>(child)];
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
    joints.push_back(
        Joint{parent, child, js.anchorParent, js.anchorChild, frame, js.minAngle, js.maxAngle});
  }
  return joints;
}

// The root: the parent graph must be a tree (no cycles, exactly one body without a parent).
Result<int> findRoot(const std::vector<Body>& bodies) {
  const int bodyCount = static_cast<int>(bodies.size());
  const auto body = [&](int b) -> const Body& { return bodies[static_cast<size_t>(b)]; };
  for (int i = 0; i < bodyCount; ++i) {
    int b = i;
    for (int steps = 0; b >= 0; ++steps) {
      if (steps > bodyCount) {
        std::string cycle = body(i).name;
        int c = body(i).parent;
        for (int k = 0; k < bodyCount && c != i; ++k, c = body(c).parent)
          cycle += " -> " + body(c).name;
        return pathError("joints",
                         fmt::format("cycle in the parent graph: {} -> {}", cycle, body(i).name));
      }
      b = body(b).parent;
    }
  }
  std::vector<int> roots;
  for (int i = 0; i < bodyCount; ++i) {
    if (body(i).parent < 0) roots.push_back(i);
  }
  if (roots.size() != 1) {
    std::string names;
    for (int r : roots) names += (names.empty() ? "'" : ", '") + body(r).name + "'";
    return pathError("joints",
                     fmt::format("{} bodies have no parent joint ({}); exactly one root is allowed",
                                 roots.size(), names));
  }
  return roots[0];
}

// Kinematic order: by depth, then by index (stable, deterministic).
std::vector<int> kinematicOrder(const std::vector<Body>& bodies) {
  const std::size_t n = bodies.size();
  std::vector<int> depth(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    for (int b = bodies[i].parent; b >= 0; b = bodies[static_cast<size_t>(b)].parent) ++depth[i];
  }
  std::vector<int> order(n);
  for (std::size_t i = 0; i < n; ++i) order[i] = static_cast<int>(i);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    return depth[static_cast<size_t>(a)] < depth[static_cast<size_t>(b)];
  });
  return order;
}

// (n x n) 1 where body j is body i or one of its ancestors.
std::vector<std::uint8_t> ancestorMatrix(const std::vector<Body>& bodies) {
  const std::size_t n = bodies.size();
  std::vector<std::uint8_t> ancestorOrSelf(n * n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    for (int b = static_cast<int>(i); b >= 0; b = bodies[static_cast<size_t>(b)].parent)
      ancestorOrSelf[i * n + static_cast<size_t>(b)] = 1;
  }
  return ancestorOrSelf;
}

// (n x n) collision filter: 1 where a pair may collide.
Result<std::vector<std::uint8_t>> collisionMatrix(const ModelSpec& spec,
                                                  const std::vector<Body>& bodies,
                                                  const std::vector<Joint>& joints) {
  const std::size_t n = bodies.size();
  std::vector<std::uint8_t> collides(n * n, 1);
  for (size_t i = 0; i < n; ++i) collides[i * n + i] = 0;
  if (spec.collision.ignoreJointNeighbours) {
    for (const Joint& j : joints) {
      collides[static_cast<size_t>(j.parent) * n + static_cast<size_t>(j.child)] = 0;
      collides[static_cast<size_t>(j.child) * n + static_cast<size_t>(j.parent)] = 0;
    }
  }
  for (size_t p = 0; p < spec.collision.ignoredPairs.size(); ++p) {
    const auto& [nameA, nameB] = spec.collision.ignoredPairs[p];
    const int a = bodyIndexIn(bodies, nameA);
    const int b = bodyIndexIn(bodies, nameB);
    if (a < 0)
      return pathError(fmt::format("collision.ignorePairs[{}][0]", p),
                       fmt::format("unknown body '{}'", nameA));
    if (b < 0)
      return pathError(fmt::format("collision.ignorePairs[{}][1]", p),
                       fmt::format("unknown body '{}'", nameB));
    collides[static_cast<size_t>(a) * n + static_cast<size_t>(b)] = 0;
    collides[static_cast<size_t>(b) * n + static_cast<size_t>(a)] = 0;
  }
  return collides;
}

// Keypoints: unique names, known bodies, finite points, radii >= 0.
Result<std::vector<Keypoint>> compileKeypoints(const ModelSpec& spec,
                                               const std::vector<Body>& bodies) {
  std::vector<Keypoint> keypoints;
  for (size_t k = 0; k < spec.keypoints.size(); ++k) {
    const KeypointSpec& ks = spec.keypoints[k];
    const std::string path = fmt::format("keypoints[{}]", k);
    if (ks.name.empty()) return pathError(path + ".name", "empty");
    for (const Keypoint& earlier : keypoints)
      if (earlier.name == ks.name)
        return pathError(path + ".name", fmt::format("duplicate name '{}'", ks.name));
    const int body = bodyIndexIn(bodies, ks.body);
    if (body < 0) return pathError(path + ".body", fmt::format("unknown body '{}'", ks.body));
    if (!finite(ks.point)) return pathError(path + ".point", "not finite");
    if (!std::isfinite(ks.radius) || ks.radius < 0.0f)
      return pathError(path + ".radius", "must be a number >= 0");
    keypoints.push_back(Keypoint{ks.name, body, ks.point, ks.radius});
  }
  return keypoints;
}

}  // namespace

Result<ArticulatedModel> buildModel(const ModelSpec& spec) {
  ArticulatedModel model;
  model.metadata_ = spec.metadata;
  if (!std::isfinite(spec.metadata.referenceLength) || spec.metadata.referenceLength < 0.0f) {
    return pathError("metadata.referenceLength", "must be a finite number >= 0");
  }
  if (spec.bodies.empty()) return pathError("bodies", "no bodies");
  for (int i = 0; i < static_cast<int>(spec.bodies.size()); ++i) {
    Result<Body> body = compileBody(spec, i);
    if (!body) return body.error();
    model.bodies_.push_back(std::move(body).value());
  }
  Result<std::vector<Joint>> joints = compileJoints(spec, model.bodies_);
  if (!joints) return joints.error();
  model.joints_ = std::move(joints).value();
  Result<int> root = findRoot(model.bodies_);
  if (!root) return root.error();
  model.root_ = *root;
  model.order_ = kinematicOrder(model.bodies_);
  model.ancestorOrSelf_ = ancestorMatrix(model.bodies_);
  model.collision_ = spec.collision;
  Result<std::vector<std::uint8_t>> collides = collisionMatrix(spec, model.bodies_, model.joints_);
  if (!collides) return collides.error();
  model.collides_ = std::move(collides).value();
  Result<std::vector<Keypoint>> keypoints = compileKeypoints(spec, model.bodies_);
  if (!keypoints) return keypoints.error();
  model.keypoints_ = std::move(keypoints).value();
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
