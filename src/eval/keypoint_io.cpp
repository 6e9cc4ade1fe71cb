#include "dynahand/keypoint_io.h"

#include <cstdint>
#include <fstream>
#include <nlohmann/json.hpp>

namespace dynahand::eval {

namespace {

using nlohmann::json;

// Guards against absurd frame numbers (a million: over nine hours at 30 frames per second).
// Frames are indexed, so a frame number costs memory: 256 bytes a frame, 256 MB at this limit
// (10 million let a one-line file take 2.5 GB).
constexpr int kMaxFrames = 1'000'000;

Result<Keypoints21> parseKeypoints(const json& value) {
  if (!value.is_array() || value.size() != 21)
    return Error{"keypoints21 must be 21 [x,y,z] arrays"};
  Keypoints21 k;
  for (int j = 0; j < 21; ++j) {
    const json& p = value[static_cast<std::size_t>(j)];
    if (!p.is_array() || p.size() != 3) {
      return Error{"keypoints21[" + std::to_string(j) + "] must be [x,y,z]"};
    }
    for (int c = 0; c < 3; ++c) {
      const json& v = p[static_cast<std::size_t>(c)];
      if (!v.is_number()) {
        return Error{"keypoints21[" + std::to_string(j) + "] has a non-numeric coordinate"};
      }
      k[j][c] = v.get<float>();
    }
    if (!k[j].allFinite()) return Error{"keypoints21[" + std::to_string(j) + "] is not finite"};
  }
  return k;
}

}  // namespace

Result<KeypointSequence> readKeypointsJsonl(const std::filesystem::path& path,
                                            const std::string& side) {
  std::ifstream in(path);
  if (!in) return Error{path.string() + ": cannot open"};
  KeypointSequence seq;
  std::string line;
  int lineNumber = 0;
  int nextFrame = 0;
  while (std::getline(in, line)) {
    ++lineNumber;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    const std::string where = path.string() + ":" + std::to_string(lineNumber) + ": ";
    json obj = json::parse(line, nullptr, /*allow_exceptions=*/false);
    if (obj.is_discarded() || !obj.is_object()) return Error{where + "not a JSON object"};
    if (obj.contains("version")) {  // tracker output (track_io.h): format version 1
      if (!obj["version"].is_number_integer())
        return Error{where + "\"version\" must be an integer"};
      if (obj["version"].get<std::int64_t>() > 1)
        return Error{where + "\"version\" " + obj["version"].dump() +
                     " is newer than this dynahand understands (1)"};
    }
    std::int64_t frame = nextFrame;
    if (obj.contains("frame")) {
      if (!obj["frame"].is_number_integer()) return Error{where + "\"frame\" must be an integer"};
      // As a 64-bit number (get<int> wrapped 4294967296 to frame 0); an unsigned one past
      // the int64 range comes out negative.
      frame = obj["frame"].get<std::int64_t>();
    }
    if (frame < 0 || frame >= kMaxFrames) return Error{where + "frame number out of range"};
    nextFrame = static_cast<int>(frame) + 1;
    std::optional<Keypoints21> keypoints;
    if (obj.contains("hands")) {
      if (!obj["hands"].is_array()) return Error{where + "\"hands\" must be an array"};
      for (const json& hand : obj["hands"]) {
        if (!hand.is_object() || hand.value("side", std::string("right")) != side) continue;
        if (!hand.value("tracked", true) || !hand.contains("keypoints21") ||
            hand["keypoints21"].is_null()) {
          break;
        }
        auto k = parseKeypoints(hand["keypoints21"]);
        if (!k) return Error{where + k.message()};
        keypoints = *k;
        break;
      }
    } else if (obj.contains("keypoints21")) {
      if (!obj["keypoints21"].is_null()) {
        auto k = parseKeypoints(obj["keypoints21"]);
        if (!k) return Error{where + k.message()};
        keypoints = *k;
      }
    } else {
      return Error{where + "neither \"keypoints21\" nor \"hands\" present"};
    }
    if (static_cast<std::size_t>(frame) >= seq.frames.size()) {
      seq.frames.resize(static_cast<std::size_t>(frame) + 1);
    }
    seq.frames[static_cast<std::size_t>(frame)] = keypoints;
  }
  if (lineNumber == 0) return Error{path.string() + ": empty file"};
  return seq;
}

}  // namespace dynahand::eval
