// Model files: JSON text <-> ModelSpec (docs/formats/model.md). Reading reports the first
// problem with its JSON path; writing is canonical (shortest round-trip floats, limits in
// degrees rounded to 1e-4) so that file -> model -> file is byte-identical.
#include <charconv>
#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "core/json_util.h"
#include "dynahand/model.h"

namespace dynahand::model {
namespace {

using jsonread::FormatError;
using nlohmann::json;

using jsonread::degreesToRadians;
using jsonread::kDegPerRad;
using jsonread::num;

constexpr const char* kModelFormatName = "dynahand-model";

Handedness parseHandedness(const json& v, const std::string& path) {
  const std::string s = jsonread::string(v, path);
  if (s == "right") return Handedness::Right;
  if (s == "left") return Handedness::Left;
  if (s == "none") return Handedness::None;
  throw FormatError{path, fmt::format("'{}' is not one of right, left, none", s)};
}

const char* handednessName(Handedness h) {
  switch (h) {
    case Handedness::Right:
      return "right";
    case Handedness::Left:
      return "left";
    case Handedness::None:
      return "none";
  }
  return "none";
}

ModelSpec parseSpec(const json& doc) {
  using namespace jsonread;
  ModelSpec spec;
  if (!doc.is_object()) throw FormatError{"(document)", "expected a JSON object"};
  checkKeys(doc, "",
            {"format", "version", "metadata", "bodies", "joints", "collision", "keypoints"});
  const std::string format = string(field(doc, "", "format"), "format");
  if (format != kModelFormatName)
    throw FormatError{"format", fmt::format("'{}' is not '{}'", format, kModelFormatName)};
  const json& version = field(doc, "", "version");
  if (!version.is_number_integer()) throw FormatError{"version", "expected an integer"};
  if (version.get<long long>() != kModelFormatVersion) {
    throw FormatError{"version", fmt::format("{} is not supported (this build reads version {})",
                                             version.get<long long>(), kModelFormatVersion)};
  }

  const json& meta = field(doc, "", "metadata");
  objectAt(meta, "metadata");
  checkKeys(meta, "metadata", {"name", "handedness", "units", "referenceLength"});
  if (meta.contains("name")) spec.metadata.name = string(meta["name"], "metadata.name");
  spec.metadata.handedness =
      parseHandedness(field(meta, "metadata", "handedness"), "metadata.handedness");
  const std::string units = string(field(meta, "metadata", "units"), "metadata.units");
  if (units != "m")
    throw FormatError{"metadata.units", fmt::format("'{}' is not supported (only \"m\")", units)};
  if (meta.contains("referenceLength")) {
    spec.metadata.referenceLength = number(meta["referenceLength"], "metadata.referenceLength");
  }

  const json& bodies = arrayAt(field(doc, "", "bodies"), "bodies");
  for (size_t i = 0; i < bodies.size(); ++i) {
    const std::string path = fmt::format("bodies[{}]", i);
    const json& b = objectAt(bodies[i], path);
    checkKeys(b, path, {"name", "mass", "density", "vertices"});
    BodySpec body;
    body.name = string(field(b, path, "name"), path + ".name");
    if (b.contains("mass")) body.mass = number(b["mass"], path + ".mass");
    if (b.contains("density")) body.density = number(b["density"], path + ".density");
    const json& verts = arrayAt(field(b, path, "vertices"), path + ".vertices");
    for (size_t v = 0; v < verts.size(); ++v)
      body.vertices.push_back(vec3(verts[v], fmt::format("{}.vertices[{}]", path, v)));
    spec.bodies.push_back(std::move(body));
  }

  const json& joints = arrayAt(field(doc, "", "joints"), "joints");
  for (size_t j = 0; j < joints.size(); ++j) {
    const std::string path = fmt::format("joints[{}]", j);
    const json& o = objectAt(joints[j], path);
    checkKeys(o, path,
              {"parent", "child", "anchorParent", "anchorChild", "frame", "minDeg", "maxDeg"});
    JointSpec joint;
    joint.parent = string(field(o, path, "parent"), path + ".parent");
    joint.child = string(field(o, path, "child"), path + ".child");
    joint.anchorParent = vec3(field(o, path, "anchorParent"), path + ".anchorParent");
    joint.anchorChild = vec3(field(o, path, "anchorChild"), path + ".anchorChild");
    if (o.contains("frame")) joint.frame = quatWxyz(o["frame"], path + ".frame");
    joint.minAngle = degreesToRadians(vec3(field(o, path, "minDeg"), path + ".minDeg"));
    joint.maxAngle = degreesToRadians(vec3(field(o, path, "maxDeg"), path + ".maxDeg"));
    spec.joints.push_back(std::move(joint));
  }

  if (doc.contains("collision")) {
    const json& c = objectAt(doc["collision"], "collision");
    checkKeys(c, "collision", {"ignoreJointNeighbours", "ignorePairs"});
    if (c.contains("ignoreJointNeighbours")) {
      if (!c["ignoreJointNeighbours"].is_boolean())
        throw FormatError{"collision.ignoreJointNeighbours", "expected true or false"};
      spec.collision.ignoreJointNeighbours = c["ignoreJointNeighbours"].get<bool>();
    }
    if (c.contains("ignorePairs")) {
      const json& pairs = arrayAt(c["ignorePairs"], "collision.ignorePairs");
      for (size_t p = 0; p < pairs.size(); ++p) {
        const std::string path = fmt::format("collision.ignorePairs[{}]", p);
        const json& pair = arrayAt(pairs[p], path);
        if (pair.size() != 2) throw FormatError{path, "expected two body names"};
        spec.collision.ignoredPairs.emplace_back(string(pair[0], path + "[0]"),
                                                 string(pair[1], path + "[1]"));
      }
    }
  }

  if (doc.contains("keypoints")) {
    const json& kps = arrayAt(doc["keypoints"], "keypoints");
    for (size_t k = 0; k < kps.size(); ++k) {
      const std::string path = fmt::format("keypoints[{}]", k);
      const json& o = objectAt(kps[k], path);
      checkKeys(o, path, {"name", "body", "point", "radius"});
      KeypointSpec kp;
      kp.name = string(field(o, path, "name"), path + ".name");
      kp.body = string(field(o, path, "body"), path + ".body");
      kp.point = vec3(field(o, path, "point"), path + ".point");
      if (o.contains("radius")) kp.radius = number(o["radius"], path + ".radius");
      spec.keypoints.push_back(std::move(kp));
    }
  }
  return spec;
}

std::string vec(const Vec3& v) {
  return "[" + num(v.x()) + ", " + num(v.y()) + ", " + num(v.z()) + "]";
}
std::string degrees(const Vec3& rad) {
  std::string out = "[";
  for (int axis = 0; axis < 3; ++axis) {
    const double deg = std::round(static_cast<double>(rad[axis]) * kDegPerRad * 1e4) / 1e4;
    out += fmt::format("{}{}", axis ? ", " : "", deg == 0.0 ? 0.0 : deg);
  }
  return out + "]";
}
std::string quoted(const std::string& s) {
  return json(s).dump();
}

}  // namespace

Result<ArticulatedModel> parseModel(const std::string& jsonText, const std::string& sourceName) {
  json doc;
  try {
    doc = json::parse(jsonText);
  } catch (const json::exception& e) {  // parse_error, or out_of_range for overflowing numbers
    return Error{fmt::format("{}: not valid JSON: {}", sourceName, e.what())};
  }
  ModelSpec spec;
  try {
    spec = parseSpec(doc);
  } catch (const FormatError& e) {
    return Error{fmt::format("{}: {}: {}", sourceName, e.path, e.problem)};
  }
  Result<ArticulatedModel> model = buildModel(spec);
  if (!model) return Error{sourceName + ": " + model.message()};
  return model;
}

Result<ArticulatedModel> loadModel(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return Error{fmt::format("{}: cannot open model file", path.string())};
  std::ostringstream text;
  text << in.rdbuf();
  return parseModel(text.str(), path.string());
}

std::string modelToJson(const ArticulatedModel& model) {
  const ModelSpec spec = model.spec();
  std::string out;
  out += "{\n";
  out += fmt::format("  \"format\": \"{}\",\n  \"version\": {},\n", kModelFormatName,
                     kModelFormatVersion);
  out += fmt::format(
      "  \"metadata\": {{\"name\": {}, \"handedness\": \"{}\", \"units\": \"m\", "
      "\"referenceLength\": {}}},\n",
      quoted(spec.metadata.name), handednessName(spec.metadata.handedness),
      num(spec.metadata.referenceLength));
  out += "  \"bodies\": [\n";
  for (size_t i = 0; i < spec.bodies.size(); ++i) {
    const BodySpec& b = spec.bodies[i];
    out += fmt::format("    {{\"name\": {}, \"mass\": {},\n     \"vertices\": [", quoted(b.name),
                       num(b.mass.value_or(0.0f)));
    for (size_t v = 0; v < b.vertices.size(); ++v) {
      out += (v == 0 ? "" : (v % 4 == 0 ? ",\n                  " : ", ")) + vec(b.vertices[v]);
    }
    out += i + 1 < spec.bodies.size() ? "]},\n" : "]}\n";
  }
  out += "  ],\n  \"joints\": [\n";
  for (size_t j = 0; j < spec.joints.size(); ++j) {
    const JointSpec& o = spec.joints[j];
    out += fmt::format(
        "    {{\"parent\": {}, \"child\": {}, \"anchorParent\": {}, \"anchorChild\": {},\n"
        "     \"frame\": [{}, {}, {}, {}], \"minDeg\": {}, \"maxDeg\": {}}}{}\n",
        quoted(o.parent), quoted(o.child), vec(o.anchorParent), vec(o.anchorChild),
        num(o.frame.w()), num(o.frame.x()), num(o.frame.y()), num(o.frame.z()), degrees(o.minAngle),
        degrees(o.maxAngle), j + 1 < spec.joints.size() ? "," : "");
  }
  out += "  ],\n";
  out += fmt::format("  \"collision\": {{\"ignoreJointNeighbours\": {}, \"ignorePairs\": [",
                     spec.collision.ignoreJointNeighbours ? "true" : "false");
  for (size_t p = 0; p < spec.collision.ignoredPairs.size(); ++p) {
    out += fmt::format("{}[{}, {}]", p ? ", " : "", quoted(spec.collision.ignoredPairs[p].first),
                       quoted(spec.collision.ignoredPairs[p].second));
  }
  out += "]},\n  \"keypoints\": [\n";
  for (size_t k = 0; k < spec.keypoints.size(); ++k) {
    const KeypointSpec& kp = spec.keypoints[k];
    out += fmt::format("    {{\"name\": {}, \"body\": {}, \"point\": {}, \"radius\": {}}}{}\n",
                       quoted(kp.name), quoted(kp.body), vec(kp.point), num(kp.radius),
                       k + 1 < spec.keypoints.size() ? "," : "");
  }
  out += "  ]\n}\n";
  return out;
}

Status saveModel(const ArticulatedModel& model, const std::filesystem::path& path) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) return Error{fmt::format("{}: cannot open for writing", path.string())};
  out << modelToJson(model);
  out.close();
  if (!out) return Error{fmt::format("{}: write failed", path.string())};
  return Ok{};
}

}  // namespace dynahand::model
