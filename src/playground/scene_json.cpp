// Scene files (docs/formats/scene.md): JSON in metres and degrees, parsed into a SceneSpec
// in metres and radians. Every error names the file and the JSON path.
#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>

#include <nlohmann/json.hpp>

#include "core/json_util.h"
#include "dynahand/playground.h"

namespace dynahand::playground {
namespace {

using jsonread::arrayAt;
using jsonread::checkKeys;
using jsonread::childPath;
using jsonread::field;
using jsonread::FormatError;
using jsonread::number;
using jsonread::objectAt;
using jsonread::vec3;
using Json = nlohmann::json;

constexpr float kDeg = std::numbers::pi_v<float> / 180.0f;

const Json* optional(const Json& object, const char* key) {
  const auto it = object.find(key);
  return it == object.end() ? nullptr : &*it;
}

float positive(const Json& v, const std::string& path) {
  const float x = number(v, path);
  if (!(x > 0.0f)) throw FormatError{path, "must be > 0"};
  return x;
}

void readNumber(const Json& object, const std::string& path, const char* key, float& out,
                bool mustBePositive = false) {
  if (const Json* v = optional(object, key))
    out = mustBePositive ? positive(*v, childPath(path, key)) : number(*v, childPath(path, key));
}

// Object dimensions, m: far outside this range a hull degenerates in float arithmetic (and
// the physics is meaningless long before).
constexpr float kMinLength = 0.001f;
constexpr float kMaxLength = 100.0f;
constexpr const char* kLengthRange = "[0.001, 100] m";

Vec3 positiveVec3(const Json& v, const std::string& path) {
  const Vec3 x = vec3(v, path);
  if (!(x.minCoeff() > 0.0f)) throw FormatError{path, "every component must be > 0"};
  if (!(x.minCoeff() >= kMinLength && x.maxCoeff() <= kMaxLength))
    throw FormatError{path, std::string("every component must be in ") + kLengthRange};
  return x;
}

void readLength(const Json& object, const std::string& path, const char* key, float& out) {
  readNumber(object, path, key, out, true);
  if (!(out >= kMinLength && out <= kMaxLength))
    throw FormatError{childPath(path, key), std::string("must be in ") + kLengthRange};
}

ObjectKind kindFromName(const std::string& name, const std::string& path) {
  static const std::pair<const char*, ObjectKind> kKinds[] = {
      {"box", ObjectKind::Box},           {"sphere", ObjectKind::Sphere},
      {"cylinder", ObjectKind::Cylinder}, {"convex", ObjectKind::Convex},
      {"barbell", ObjectKind::Barbell},   {"lever", ObjectKind::Lever},
      {"dial", ObjectKind::Dial},         {"swing", ObjectKind::Swing}};
  for (const auto& [n, k] : kKinds)
    if (name == n) return k;
  throw FormatError{path, "unknown kind '" + name +
                              "' (box, sphere, cylinder, convex, barbell, lever, dial, swing)"};
}

// Rotation from degrees about the scene's x, then y, then z axes (extrinsic).
Quat rotationFromDegrees(const Vec3& deg) {
  return (Eigen::AngleAxisf(deg.z() * kDeg, Vec3::UnitZ()) *
          Eigen::AngleAxisf(deg.y() * kDeg, Vec3::UnitY()) *
          Eigen::AngleAxisf(deg.x() * kDeg, Vec3::UnitX()))
      .normalized();
}

ObjectSpec readObject(const Json& j, const std::string& path) {
  objectAt(j, path);
  checkKeys(
      j, path,
      {"name", "kind", "static", "position", "rotationDeg", "mass", "size", "radius", "length",
       "capRadius", "capLength", "points", "axis", "limitsDeg", "startDeg", "damping", "links"});
  ObjectSpec o;
  o.name = jsonread::string(field(j, path, "name"), childPath(path, "name"));
  if (o.name.empty() || o.name.find('/') != std::string::npos)
    throw FormatError{childPath(path, "name"), "must be non-empty and contain no '/'"};
  o.kind = kindFromName(jsonread::string(field(j, path, "kind"), childPath(path, "kind")),
                        childPath(path, "kind"));
  if (const Json* v = optional(j, "static")) {
    if (!v->is_boolean()) throw FormatError{childPath(path, "static"), "expected true or false"};
    o.isStatic = v->get<bool>();
    const bool simple = o.kind == ObjectKind::Box || o.kind == ObjectKind::Sphere ||
                        o.kind == ObjectKind::Cylinder || o.kind == ObjectKind::Convex;
    if (o.isStatic && !simple)
      throw FormatError{childPath(path, "static"), "only box, sphere, cylinder and convex"};
  }
  o.position = vec3(field(j, path, "position"), childPath(path, "position"));
  if (const Json* v = optional(j, "rotationDeg"))
    o.orientation = rotationFromDegrees(vec3(*v, childPath(path, "rotationDeg")));
  readNumber(j, path, "mass", o.mass, true);
  if (const Json* v = optional(j, "size")) o.size = positiveVec3(*v, childPath(path, "size"));
  readLength(j, path, "radius", o.radius);
  readLength(j, path, "length", o.length);
  readLength(j, path, "capRadius", o.capRadius);
  readLength(j, path, "capLength", o.capLength);
  if (const Json* v = optional(j, "points")) {
    const std::string p = childPath(path, "points");
    arrayAt(*v, p);
    for (std::size_t i = 0; i < v->size(); ++i)
      o.points.push_back(vec3((*v)[i], p + "[" + std::to_string(i) + "]"));
  }
  if (o.kind == ObjectKind::Convex && o.points.size() < 4)
    throw FormatError{childPath(path, "points"), "a convex object needs at least 4 points"};
  if (const Json* v = optional(j, "axis")) {
    o.axis = vec3(*v, childPath(path, "axis"));
    if (!(o.axis.norm() > 1e-6f)) throw FormatError{childPath(path, "axis"), "zero vector"};
    // Scaled first: normalize() alone made [3e38, 3e38, 3e38] zero (its norm overflows).
    o.axis /= o.axis.cwiseAbs().maxCoeff();
    o.axis.normalize();
  }
  if (const Json* v = optional(j, "limitsDeg")) {
    const std::string p = childPath(path, "limitsDeg");
    if (!v->is_array() || v->size() != 2) throw FormatError{p, "expected [lower, upper]"};
    o.lowerLimit = number((*v)[0], p + "[0]") * kDeg;
    o.upperLimit = number((*v)[1], p + "[1]") * kDeg;
    if (!(o.lowerLimit <= o.upperLimit) || o.upperLimit - o.lowerLimit > 340.0f * kDeg)
      throw FormatError{p, "need lower <= upper within a 340 degree range"};
  }
  if (const Json* v = optional(j, "startDeg"))
    o.startAngle = number(*v, childPath(path, "startDeg")) * kDeg;
  readNumber(j, path, "damping", o.hingeDamping);
  if (const Json* v = optional(j, "links")) {
    if (!v->is_number_integer() || v->get<int>() < 1 || v->get<int>() > 32)
      throw FormatError{childPath(path, "links"), "expected a whole number in 1..32"};
    o.links = v->get<int>();
  }
  const bool hinged = o.kind == ObjectKind::Lever || o.kind == ObjectKind::Dial;
  if (hinged && (o.startAngle < o.lowerLimit || o.startAngle > o.upperLimit))
    throw FormatError{childPath(path, "startDeg"), "outside limitsDeg"};
  return o;
}

SceneSpec readScene(const Json& root) {
  objectAt(root, "");
  checkKeys(root, "",
            {"format", "version", "name", "gravity", "camera", "stepHz", "friction", "hand",
             "navigation", "objects"});
  if (jsonread::string(field(root, "", "format"), "format") != "dynahand-scene")
    throw FormatError{"format", "expected \"dynahand-scene\""};
  const Json& version = field(root, "", "version");
  if (!version.is_number_integer() || version.get<int>() < 1)
    throw FormatError{"version", "expected a whole number >= 1"};
  if (version.get<int>() > kSceneFormatVersion)
    throw FormatError{"version", "version " + std::to_string(version.get<int>()) +
                                     " is newer than this reader (" +
                                     std::to_string(kSceneFormatVersion) + ")"};
  SceneSpec s;
  if (const Json* v = optional(root, "name")) s.name = jsonread::string(*v, "name");
  if (const Json* v = optional(root, "gravity")) s.gravity = vec3(*v, "gravity");
  {
    const Json& c = objectAt(field(root, "", "camera"), "camera");
    checkKeys(c, "camera", {"position", "pitchDeg", "yawDeg"});
    const Vec3 position = vec3(field(c, "camera", "position"), "camera.position");
    const float pitch = number(field(c, "camera", "pitchDeg"), "camera.pitchDeg");
    if (std::abs(pitch) > 90.0f) throw FormatError{"camera.pitchDeg", "must be in [-90, 90]"};
    float yaw = 0.0f;
    if (const Json* v = optional(c, "yawDeg")) yaw = number(*v, "camera.yawDeg");
    s.camera = cameraLookingDown(position, pitch * kDeg, yaw * kDeg);
  }
  if (const Json* v = optional(root, "stepHz")) {
    // Each input frame runs round(dt * stepHz) steps: bounded, so a frame ends.
    const float hz = number(*v, "stepHz");
    if (!(hz >= 1.0f && hz <= 1000.0f)) throw FormatError{"stepHz", "must be in [1, 1000]"};
    s.stepDt = 1.0f / hz;
  }
  readNumber(root, "", "friction", s.friction);
  if (s.friction < 0.0f) throw FormatError{"friction", "must be >= 0"};
  if (const Json* v = optional(root, "hand")) {
    objectAt(*v, "hand");
    checkKeys(
        *v, "hand",
        {"palmMaxForce", "palmMaxTorque", "palmTimeConstant", "palmMaxSpeed", "fingerMaxTorque",
         "thumbMaxTorque", "jointTimeConstant", "jointSpringAngle", "jointDampingRatio"});
    HandDriveSettings& h = s.hand;
    readNumber(*v, "hand", "palmMaxForce", h.palmMaxForce, true);
    readNumber(*v, "hand", "palmMaxTorque", h.palmMaxTorque, true);
    readNumber(*v, "hand", "palmTimeConstant", h.palmTimeConstant, true);
    readNumber(*v, "hand", "palmMaxSpeed", h.palmMaxSpeed, true);
    if (h.palmMaxSpeed > 0.6f)
      throw FormatError{"hand.palmMaxSpeed", "at most 0.6 m/s (the contact margin per step)"};
    readNumber(*v, "hand", "fingerMaxTorque", h.fingerMaxTorque, true);
    readNumber(*v, "hand", "thumbMaxTorque", h.thumbMaxTorque, true);
    readNumber(*v, "hand", "jointTimeConstant", h.jointTimeConstant, true);
    readNumber(*v, "hand", "jointSpringAngle", h.jointSpringAngle);
    if (h.jointSpringAngle < 0.0f) throw FormatError{"hand.jointSpringAngle", "must be >= 0"};
    readNumber(*v, "hand", "jointDampingRatio", h.jointDampingRatio, true);
  }
  if (const Json* v = optional(root, "navigation")) {
    objectAt(*v, "navigation");
    checkKeys(*v, "navigation", {"enabled", "edgeMargin", "speed"});
    if (const Json* e = optional(*v, "enabled")) {
      if (!e->is_boolean()) throw FormatError{"navigation.enabled", "expected true or false"};
      s.navigation.enabled = e->get<bool>();
    }
    readNumber(*v, "navigation", "edgeMargin", s.navigation.edgeMargin);
    if (s.navigation.edgeMargin < 0.0f || s.navigation.edgeMargin >= 1.0f)
      throw FormatError{"navigation.edgeMargin", "must be in [0, 1)"};
    readNumber(*v, "navigation", "speed", s.navigation.speed);
  }
  const Json& objects = arrayAt(field(root, "", "objects"), "objects");
  for (std::size_t i = 0; i < objects.size(); ++i) {
    s.objects.push_back(readObject(objects[i], "objects[" + std::to_string(i) + "]"));
    for (std::size_t k = 0; k + 1 < s.objects.size(); ++k)
      if (s.objects[k].name == s.objects.back().name)
        throw FormatError{"objects[" + std::to_string(i) + "].name",
                          "duplicate name '" + s.objects.back().name + "'"};
  }
  return s;
}

}  // namespace

Pose cameraLookingDown(const Vec3& position, float pitch, float yaw) {
  // Camera axes in the scene: x right, y down-ish, z forward-ish; at pitch 0 the camera looks
  // along -z with its y axis along -y (scene up is +y).
  Mat3 axes;
  axes.col(0) = Vec3::UnitX();
  axes.col(1) = Vec3(0.0f, -std::cos(pitch), std::sin(pitch));
  axes.col(2) = Vec3(0.0f, -std::sin(pitch), -std::cos(pitch));
  return {position, (Quat(Eigen::AngleAxisf(yaw, Vec3::UnitY())) * Quat(axes)).normalized()};
}

Result<SceneSpec> parseScene(const std::string& jsonText, const std::string& sourceName) {
  Json root;
  try {
    root = Json::parse(jsonText);
  } catch (const Json::exception& e) {  // parse_error, or out_of_range for overflowing numbers
    return Error{sourceName + ": not valid JSON: " + e.what()};
  }
  try {
    return readScene(root);
  } catch (const FormatError& e) {
    return Error{sourceName + ": " + (e.path.empty() ? "" : e.path + ": ") + e.problem};
  }
}

Result<SceneSpec> loadScene(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return Error{path.string() + ": cannot open"};
  std::ostringstream text;
  text << in.rdbuf();
  return parseScene(text.str(), path.string());
}

}  // namespace dynahand::playground
