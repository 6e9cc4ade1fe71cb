// Import of the original authors' model_hand.json and their .pose files. Each control cage
// is Catmull-Clark subdivided (2 levels, as their tracker did) and the hull of the result is
// the bone's shape; the hull's centroid is the centre-of-mass frame origin that .pose files
// store, so the subdivision level matters for exact pose conversion.
#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "core/json_util.h"
#include "dynahand/model_intel.h"

namespace dynahand::model {
namespace {

using jsonread::FormatError;
using nlohmann::json;

using jsonread::degreesToRadians;

const char* const kHandBodyNames[17] = {
    "forearm",        "palm",          "thumb_metacarpal", "thumb_proximal",  "thumb_distal",
    "index_proximal", "index_middle",  "index_distal",     "middle_proximal", "middle_middle",
    "middle_distal",  "ring_proximal", "ring_middle",      "ring_distal",     "pinky_proximal",
    "pinky_middle",   "pinky_distal"};

int index(const json& v, const std::string& path, size_t count) {
  if (!v.is_number_integer()) throw FormatError{path, "expected an integer"};
  const long long i = v.get<long long>();
  if (i < 0 || i >= static_cast<long long>(count))
    throw FormatError{path, fmt::format("index {} out of range [0, {})", i, count)};
  return static_cast<int>(i);
}

// Quaternion stored x, y, z, w.
Quat quatXyzw(const json& v, const std::string& path) {
  if (!v.is_array() || v.size() != 4) throw FormatError{path, "expected [x, y, z, w]"};
  return Quat(jsonread::number(v[3], path + "[3]"), jsonread::number(v[0], path + "[0]"),
              jsonread::number(v[1], path + "[1]"), jsonread::number(v[2], path + "[2]"));
}

struct ParsedIntel {
  ModelSpec spec;
  std::vector<float> restNumbers;
};

ParsedIntel parseIntel(const json& doc, const IntelImportOptions& options) {
  using namespace jsonread;
  ParsedIntel parsed;
  ModelSpec& spec = parsed.spec;
  objectAt(doc, "(document)");
  const json& cages = arrayAt(field(doc, "", "controlcages"), "controlcages");
  if (cages.empty()) throw FormatError{"controlcages", "no bodies"};
  const size_t n = cages.size();
  for (size_t b = 0; b < n; ++b) {
    const std::string path = fmt::format("controlcages[{}]", b);
    const json& cage = objectAt(cages[b], path);
    PolygonMesh mesh;
    const json& verts = arrayAt(field(cage, path, "verts"), path + ".verts");
    for (size_t v = 0; v < verts.size(); ++v)
      mesh.vertices.push_back(vec3(verts[v], fmt::format("{}.verts[{}]", path, v)));
    const json& faces = arrayAt(field(cage, path, "faces"), path + ".faces");
    for (size_t f = 0; f < faces.size(); ++f) {
      const std::string facePath = fmt::format("{}.faces[{}]", path, f);
      const json& face = arrayAt(faces[f], facePath);
      if (face.size() < 3) throw FormatError{facePath, "a face needs at least 3 vertices"};
      std::vector<int> indices;
      for (size_t i = 0; i < face.size(); ++i)
        indices.push_back(index(face[i], fmt::format("{}[{}]", facePath, i), mesh.vertices.size()));
      mesh.faces.push_back(std::move(indices));
    }
    for (int level = 0; level < options.subdivisions && !mesh.faces.empty(); ++level)
      mesh = catmullClark(mesh);
    const std::string name = n == 17 ? kHandBodyNames[b] : fmt::format("bone{}", b);
    spec.bodies.push_back(BodySpec{name, std::move(mesh.vertices), std::nullopt, std::nullopt});
  }
  const json& joints = arrayAt(field(doc, "", "joints"), "joints");
  for (size_t j = 0; j < joints.size(); ++j) {
    const std::string path = fmt::format("joints[{}]", j);
    const json& o = objectAt(joints[j], path);
    JointSpec joint;
    joint.parent =
        spec.bodies[static_cast<size_t>(index(field(o, path, "rbi0"), path + ".rbi0", n))].name;
    joint.child =
        spec.bodies[static_cast<size_t>(index(field(o, path, "rbi1"), path + ".rbi1", n))].name;
    joint.anchorParent = vec3(field(o, path, "p0"), path + ".p0");
    joint.anchorChild = vec3(field(o, path, "p1"), path + ".p1");
    joint.frame = quatXyzw(field(o, path, "jointframe"), path + ".jointframe");
    joint.minAngle = degreesToRadians(vec3(field(o, path, "rangemin"), path + ".rangemin"));
    joint.maxAngle = degreesToRadians(vec3(field(o, path, "rangemax"), path + ".rangemax"));
    spec.joints.push_back(std::move(joint));
  }
  const json& pose = arrayAt(field(doc, "", "pose"), "pose");
  if (pose.size() != n)
    throw FormatError{"pose", fmt::format("{} poses for {} bodies", pose.size(), n)};
  for (size_t b = 0; b < n; ++b) {
    const std::string path = fmt::format("pose[{}]", b);
    const json& p = arrayAt(pose[b], path);
    if (p.size() != 7) throw FormatError{path, "expected [px, py, pz, qx, qy, qz, qw]"};
    for (size_t k = 0; k < 7; ++k)
      parsed.restNumbers.push_back(number(p[k], fmt::format("{}[{}]", path, k)));
  }
  spec.metadata.name = "hand_tracking_samples model_hand.json";
  spec.metadata.handedness = n == 17 ? Handedness::Right : Handedness::None;
  spec.collision.ignoreJointNeighbours = true;
  return parsed;
}

// Keypoints of the 17-bone hand: joint centres at each bone's origin, fingertips where the
// bone's axis leaves its hull, radii as the depth of the point inside its bone.
void addHandKeypoints(ModelSpec& spec, const ArticulatedModel& model) {
  auto depth = [&](int body, const Vec3& p) {
    return std::max(0.0f, -model.bodies()[static_cast<size_t>(body)].shape.signedDistance(p));
  };
  auto add = [&](const std::string& name, int body, const Vec3& p, float radius) {
    spec.keypoints.push_back(
        KeypointSpec{name, model.bodies()[static_cast<size_t>(body)].name, p, radius});
  };
  auto tip = [&](int body) {
    const physics::ConvexShape& shape = model.bodies()[static_cast<size_t>(body)].shape;
    const Vec3 c = shape.centroid();
    const float top = shape.support(Vec3::UnitZ()).z();
    const Vec3 origin(c.x(), c.y(), top + 0.01f);
    const std::optional<float> t = shape.raycast(origin, Vec3(0, 0, -1), 1.0f);
    return t ? Vec3(origin + Vec3(0, 0, -*t)) : Vec3(c.x(), c.y(), top);
  };
  const float wristRadius =
      std::max(depth(1, Vec3::Zero()), depth(0, model.joints()[0].anchorParent));
  add("wrist", 1, Vec3::Zero(), wristRadius);
  add("palm_center", 1, model.bodies()[1].shape.centroid(),
      model.bodies()[1].shape.inscribedRadius());
  const char* digits[5] = {"thumb", "index", "middle", "ring", "pinky"};
  const char* jointNames[2][3] = {{"cmc", "mcp", "ip"}, {"mcp", "pip", "dip"}};
  for (int d = 0; d < 5; ++d) {
    const int first = 2 + 3 * d;
    const auto& names = jointNames[d == 0 ? 0 : 1];
    for (int i = 0; i < 3; ++i)
      add(fmt::format("{}_{}", digits[d], names[i]), first + i, Vec3::Zero(),
          depth(first + i, Vec3::Zero()));
    add(fmt::format("{}_tip", digits[d]), first + 2, tip(first + 2),
        0.8f * depth(first + 2, Vec3::Zero()));
    if (d > 0) {
      // Metacarpal bases: a fifth of the way from the wrist to the knuckle, in the palm.
      const Vec3 mcp = model.joints()[static_cast<size_t>(first - 1)].anchorParent;
      add(fmt::format("{}_cmc", digits[d]), 1, 0.2f * mcp, depth(first, Vec3::Zero()));
    }
  }
}

bool overlapping(const physics::ConvexShape& a, const Pose& pa, const physics::ConvexShape& b,
                 const Pose& pb) {
  for (const Vec3& v : a.vertices()) {
    if (b.signedDistance(pb.inverseTransform(pa.transform(v))) < 0.0f) return true;
  }
  for (const Vec3& v : b.vertices()) {
    if (a.signedDistance(pa.inverseTransform(pb.transform(v))) < 0.0f) return true;
  }
  return false;
}

}  // namespace

Result<ModelPose> intelPoseFromNumbers(std::span<const float> numbers,
                                       const ArticulatedModel& model) {
  const size_t n = model.bodies().size();
  if (numbers.size() != 7 * n) {
    return Error{fmt::format("{} numbers, expected {} ({} bodies x 7)", numbers.size(), 7 * n, n)};
  }
  ModelPose pose;
  pose.bodies.resize(n);
  for (size_t b = 0; b < n; ++b) {
    const float* x = numbers.data() + 7 * b;
    for (int k = 0; k < 7; ++k) {
      if (!std::isfinite(x[k])) return Error{fmt::format("body {}: number {} is not finite", b, k)};
    }
    const Quat q(x[6], x[3], x[4], x[5]);
    if (std::abs(q.norm() - 1.0f) > 1e-3f)
      return Error{fmt::format("body {}: orientation is not a unit quaternion", b)};
    pose.bodies[b].q = q.normalized();
    // The file holds the centre-of-mass frame; the body frame origin is at -centroid in it.
    pose.bodies[b].p =
        Vec3(x[0], x[1], x[2]) - pose.bodies[b].q * model.bodies()[b].shape.centroid();
  }
  return pose;
}

std::vector<float> intelPoseToNumbers(const ModelPose& pose, const ArticulatedModel& model) {
  std::vector<float> numbers;
  numbers.reserve(7 * pose.bodies.size());
  for (size_t b = 0; b < pose.bodies.size(); ++b) {
    const Pose& p = pose.bodies[b];
    const Vec3 com = p.transform(model.bodies()[b].shape.centroid());
    numbers.insert(numbers.end(), {com.x(), com.y(), com.z(), p.q.x(), p.q.y(), p.q.z(), p.q.w()});
  }
  return numbers;
}

Result<IntelModel> importIntelModel(const std::filesystem::path& path,
                                    const IntelImportOptions& options) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return Error{fmt::format("{}: cannot open model file", path.string())};
  std::ostringstream text;
  text << in.rdbuf();
  json doc;
  try {
    doc = json::parse(text.str());
  } catch (const json::exception& e) {
    return Error{fmt::format("{}: not valid JSON: {}", path.string(), e.what())};
  }
  ParsedIntel parsed;
  try {
    parsed = parseIntel(doc, options);
  } catch (const FormatError& e) {
    return Error{fmt::format("{}: {}: {}", path.string(), e.path, e.problem)};
  }
  Result<ArticulatedModel> first = buildModel(parsed.spec);
  if (!first) return Error{fmt::format("{}: {}", path.string(), first.message())};
  Result<ModelPose> rest = intelPoseFromNumbers(parsed.restNumbers, *first);
  if (!rest) return Error{fmt::format("{}: pose: {}", path.string(), rest.message())};

  // Their bones interpenetrate in the rest pose (the paper's figure shows it); such pairs
  // cannot be meant to collide.
  const size_t n = first->bodies().size();
  for (size_t a = 0; a < n; ++a) {
    for (size_t b = a + 1; b < n; ++b) {
      if (!first->collides(static_cast<int>(a), static_cast<int>(b))) continue;
      if (overlapping(first->bodies()[a].shape, rest->bodies[a], first->bodies()[b].shape,
                      rest->bodies[b])) {
        parsed.spec.collision.ignoredPairs.emplace_back(first->bodies()[a].name,
                                                        first->bodies()[b].name);
      }
    }
  }
  if (n == 17) addHandKeypoints(parsed.spec, *first);
  Result<ArticulatedModel> model = buildModel(parsed.spec);
  if (!model) return Error{fmt::format("{}: {}", path.string(), model.message())};
  if (model->hasKeypoints21()) {
    const auto kp = keypoints21(*model, *rest);
    ModelSpec spec = model->spec();
    // Length of the straightened middle finger chain (the rest pose is slightly flexed).
    spec.metadata.referenceLength = handLength(kp);
    model = buildModel(spec);
    if (!model) return Error{fmt::format("{}: {}", path.string(), model.message())};
  }
  return IntelModel{std::move(model).value(), std::move(rest).value()};
}

Result<std::vector<ModelPose>> loadIntelPoses(const std::filesystem::path& path,
                                              const ArticulatedModel& model) {
  std::ifstream in(path);
  if (!in) return Error{fmt::format("{}: cannot open pose file", path.string())};
  std::vector<ModelPose> poses;
  std::vector<float> numbers;
  std::string line;
  int lineNumber = 0;
  while (std::getline(in, line)) {
    ++lineNumber;
    numbers.clear();
    const char* p = line.data();
    const char* end = line.data() + line.size();
    while (true) {
      while (p < end && (*p == ' ' || *p == '\t' || *p == '\r')) ++p;
      if (p >= end) break;
      float value = 0.0f;
      const auto result = std::from_chars(p, end, value);
      if (result.ec != std::errc()) {
        const char* stop = p;
        while (stop < end && *stop != ' ' && *stop != '\t') ++stop;
        return Error{fmt::format("{}:{}: '{}' is not a number", path.string(), lineNumber,
                                 std::string(p, stop))};
      }
      numbers.push_back(value);
      p = result.ptr;
    }
    if (numbers.empty()) continue;
    Result<ModelPose> pose = intelPoseFromNumbers(numbers, model);
    if (!pose) return Error{fmt::format("{}:{}: {}", path.string(), lineNumber, pose.message())};
    poses.push_back(std::move(pose).value());
  }
  if (poses.empty()) return Error{fmt::format("{}: no poses", path.string())};
  return poses;
}

std::string intelPoseLine(const ModelPose& pose, const ArticulatedModel& model) {
  const std::vector<float> numbers = intelPoseToNumbers(pose, model);
  std::string line;
  for (size_t i = 0; i < numbers.size(); ++i) {
    char buf[32];
    const float v = numbers[i] == 0.0f ? 0.0f : numbers[i];
    const auto result = std::to_chars(buf, buf + sizeof buf, v);
    // Their layout: bodies separated by three spaces, position and orientation by two.
    line += std::string(buf, result.ptr) + (i % 7 == 6 ? "   " : i % 7 == 2 ? "  " : " ");
  }
  return line;
}

Status saveIntelPoses(const std::filesystem::path& path, const ArticulatedModel& model,
                      std::span<const ModelPose> poses) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) return Error{fmt::format("{}: cannot open for writing", path.string())};
  for (const ModelPose& pose : poses) {
    if (pose.bodies.size() != model.bodies().size()) {
      return Error{fmt::format("{}: a pose has {} bodies, the model {}", path.string(),
                               pose.bodies.size(), model.bodies().size())};
    }
    out << intelPoseLine(pose, model) << "\n";
  }
  out.close();
  if (!out) return Error{fmt::format("{}: write failed", path.string())};
  return Ok{};
}

}  // namespace dynahand::model
