#include "dynahand/keypoint_io.h"

#include <fstream>
#include <nlohmann/json.hpp>

namespace dynahand::eval {

namespace {

using nlohmann::json;

constexpr int kMaxFrames = 10'000'000;  // guards against absurd frame numbers

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
    int frame = nextFrame;
    if (obj.contains("frame")) {
      if (!obj["frame"].is_number_integer()) return Error{where + "\"frame\" must be an integer"};
      frame = obj["frame"].get<int>();
    }
    if (frame < 0 || frame >= kMaxFrames) return Error{where + "frame number out of range"};
    nextFrame = frame + 1;
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
