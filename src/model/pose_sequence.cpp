// Pose sequences as JSON lines (docs/formats/pose.md): a header line naming the format,
// version and bodies, then one line per frame with every body's [px, py, pz, qw, qx, qy, qz].
#include <charconv>
#include <cmath>
#include <fstream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "core/json_util.h"
#include "dynahand/model_pose.h"

namespace dynahand::model {
namespace {

using jsonread::FormatError;
using nlohmann::json;

using jsonread::num;

constexpr const char* kPoseFormatName = "dynahand-pose";

void parseHeader(const json& doc, PoseSequence& seq) {
  using namespace jsonread;
  objectAt(doc, "(header)");
  checkKeys(doc, "", {"format", "version", "bodies"});
  const std::string format = string(field(doc, "", "format"), "format");
  if (format != kPoseFormatName)
    throw FormatError{"format", fmt::format("'{}' is not '{}'", format, kPoseFormatName)};
  const json& version = field(doc, "", "version");
  if (!version.is_number_integer() || version.get<long long>() != kPoseFormatVersion) {
    throw FormatError{"version", fmt::format("{} is not supported (this build reads version {})",
                                             version.dump(), kPoseFormatVersion)};
  }
  const json& bodies = arrayAt(field(doc, "", "bodies"), "bodies");
  if (bodies.empty()) throw FormatError{"bodies", "no bodies"};
  for (size_t i = 0; i < bodies.size(); ++i)
    seq.bodyNames.push_back(string(bodies[i], fmt::format("bodies[{}]", i)));
}

ModelPose parseFrame(const json& doc, size_t expectedFrame, size_t bodyCount) {
  using namespace jsonread;
  objectAt(doc, "(frame)");
  checkKeys(doc, "", {"frame", "poses"});
  const json& frame = field(doc, "", "frame");
  if (!frame.is_number_integer() ||
      frame.get<long long>() != static_cast<long long>(expectedFrame)) {
    throw FormatError{"frame", fmt::format("{}, expected {} (frames are numbered in order from 0)",
                                           frame.dump(), expectedFrame)};
  }
  const json& poses = arrayAt(field(doc, "", "poses"), "poses");
  if (poses.size() != bodyCount) {
    throw FormatError{"poses", fmt::format("{} poses for {} bodies", poses.size(), bodyCount)};
  }
  ModelPose pose;
  pose.bodies.resize(bodyCount);
  for (size_t b = 0; b < bodyCount; ++b) {
    const std::string path = fmt::format("poses[{}]", b);
    const json& v = poses[b];
    if (!v.is_array() || v.size() != 7)
      throw FormatError{path, "expected [px, py, pz, qw, qx, qy, qz]"};
    float x[7];
    for (size_t k = 0; k < 7; ++k) x[k] = number(v[k], fmt::format("{}[{}]", path, k));
    const Quat q(x[3], x[4], x[5], x[6]);
    if (std::abs(q.norm() - 1.0f) > 1e-3f)
      throw FormatError{path, "orientation is not a unit quaternion"};
    pose.bodies[b] = Pose{Vec3(x[0], x[1], x[2]), q.normalized()};
  }
  return pose;
}

}  // namespace

Result<PoseSequence> loadPoseSequence(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) return Error{fmt::format("{}: cannot open pose sequence", path.string())};
  PoseSequence seq;
  std::string line;
  int lineNumber = 0;
  bool haveHeader = false;
  while (std::getline(in, line)) {
    ++lineNumber;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    json doc;
    try {
      doc = json::parse(line);
    } catch (const json::exception& e) {  // parse_error, or out_of_range for overflowing numbers
      return Error{fmt::format("{}:{}: not valid JSON: {}", path.string(), lineNumber, e.what())};
    }
    try {
      if (!haveHeader) {
        parseHeader(doc, seq);
        haveHeader = true;
      } else {
        seq.frames.push_back(parseFrame(doc, seq.frames.size(), seq.bodyNames.size()));
      }
    } catch (const FormatError& e) {
      return Error{fmt::format("{}:{}: {}: {}", path.string(), lineNumber, e.path, e.problem)};
    }
  }
  if (!haveHeader)
    return Error{fmt::format("{}: empty pose sequence (no header line)", path.string())};
  return seq;
}

Status savePoseSequence(const PoseSequence& sequence, const std::filesystem::path& path) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) return Error{fmt::format("{}: cannot open for writing", path.string())};
  out << fmt::format("{{\"format\": \"{}\", \"version\": {}, \"bodies\": {}}}\n", kPoseFormatName,
                     kPoseFormatVersion, json(sequence.bodyNames).dump());
  for (size_t f = 0; f < sequence.frames.size(); ++f) {
    const ModelPose& pose = sequence.frames[f];
    if (pose.bodies.size() != sequence.bodyNames.size()) {
      return Error{fmt::format("{}: frame {} has {} poses for {} bodies", path.string(), f,
                               pose.bodies.size(), sequence.bodyNames.size())};
    }
    std::string line = fmt::format("{{\"frame\": {}, \"poses\": [", f);
    for (size_t b = 0; b < pose.bodies.size(); ++b) {
      const Pose& p = pose.bodies[b];
      line +=
          fmt::format("{}[{}, {}, {}, {}, {}, {}, {}]", b ? ", " : "", num(p.p.x()), num(p.p.y()),
                      num(p.p.z()), num(p.q.w()), num(p.q.x()), num(p.q.y()), num(p.q.z()));
    }
    out << line << "]}\n";
  }
  out.close();
  if (!out) return Error{fmt::format("{}: write failed", path.string())};
  return Ok{};
}

Status checkPoseSequence(const PoseSequence& sequence, const ArticulatedModel& model) {
  if (sequence.bodyNames.size() != model.bodies().size()) {
    return Error{fmt::format("pose sequence has {} bodies, the model '{}' has {}",
                             sequence.bodyNames.size(), model.metadata().name,
                             model.bodies().size())};
  }
  for (size_t b = 0; b < sequence.bodyNames.size(); ++b) {
    if (sequence.bodyNames[b] != model.bodies()[b].name) {
      return Error{fmt::format("pose sequence body {} is '{}', the model's is '{}'", b,
                               sequence.bodyNames[b], model.bodies()[b].name)};
    }
  }
  return Ok{};
}

}  // namespace dynahand::model
