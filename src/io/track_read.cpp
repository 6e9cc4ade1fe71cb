// Reading `dynahand track` JSON lines back (docs/formats/tracked-poses.md), e.g. for
// `dynahand render`.
#include <fmt/format.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <unordered_map>

#include "dynahand/track_io.h"

namespace dynahand::io {

namespace {

using nlohmann::json;

Vec3 readVec(const json& j) {
  if (!j.is_array() || j.size() != 3) throw std::runtime_error("expected [x, y, z]");
  const Vec3 v(j[0].get<float>(), j[1].get<float>(), j[2].get<float>());
  if (!v.allFinite()) throw std::runtime_error("expected [x, y, z] of finite numbers");
  return v;
}
Quat readQuat(const json& j) {
  if (!j.is_array() || j.size() != 4) throw std::runtime_error("expected [w, x, y, z]");
  Quat q(j[0].get<float>(), j[1].get<float>(), j[2].get<float>(), j[3].get<float>());
  if (std::abs(q.norm() - 1.0f) > 1e-3f) throw std::runtime_error("not a unit quaternion");
  return q.normalized();
}
float readNumber(const json& j) {
  return j.is_number() ? j.get<float>() : std::numeric_limits<float>::quiet_NaN();
}
// A whole number that fits an int (get<int> of a float or a larger number would not).
int readInt(const json& j, const char* what) {
  constexpr int kMin = std::numeric_limits<int>::min(), kMax = std::numeric_limits<int>::max();
  bool fits = false;
  if (j.is_number_unsigned()) {
    fits = j.get<std::uint64_t>() <= static_cast<std::uint64_t>(kMax);
  } else if (j.is_number_integer()) {
    fits = j.get<std::int64_t>() >= kMin && j.get<std::int64_t>() <= kMax;
  }
  if (!fits) throw std::runtime_error(fmt::format("{}: {} is not a whole number", what, j.dump()));
  return j.get<int>();
}
// A finite number in [lo, hi]; else an error naming the field and the value as written. unit:
// appended to the range in the message ("" for a factor).
float readNumberIn(const json& j, const std::string& what, float lo, float hi,
                   const char* unit = "") {
  const float v = readNumber(j);
  if (!(v >= lo && v <= hi)) {
    throw std::runtime_error(
        fmt::format("{}: {} is not in [{}, {}]{}", what, j.dump(), lo, hi, unit));
  }
  return v;
}
// A hand size the default hand can be built at: finite, and within half and twice the sizes
// the commands accept (length 0.10-0.30 m, width 0.05-0.13 m).
float readHandDimension(const json& j, const char* what, float lo, float hi) {
  return readNumberIn(j, fmt::format("hand_size.{}", what), lo, hi, " m");
}

TrackedHand readHand(const json& h, const model::ArticulatedModel& model,
                     const std::unordered_map<std::string, std::size_t>& bodyIndex) {
  TrackedHand hand;
  hand.side =
      h.value("side", std::string("right")) == "left" ? model::Side::Left : model::Side::Right;
  hand.tracked = h.value("tracked", false);
  hand.error = h.contains("error") ? readNumber(h["error"]) : 0.0f;
  hand.simulation = h.value("simulation", std::string());
  if (hand.tracked) {
    const json& k = h.at("keypoints21");
    if (!k.is_array() || k.size() != 21) throw std::runtime_error("keypoints21: expected 21");
    for (std::size_t i = 0; i < 21; ++i) hand.keypoints21[i] = readVec(k[i]);
    if (h.contains("bodies")) {
      hand.pose.bodies.assign(model.bodies().size(), Pose{});
      std::vector<bool> seen(model.bodies().size(), false);
      for (const json& b : h["bodies"]) {
        const auto it = bodyIndex.find(b.at("name").get<std::string>());
        if (it == bodyIndex.end()) {
          throw std::runtime_error("bodies: '" + b.at("name").get<std::string>() +
                                   "' is not a body of the model");
        }
        hand.pose.bodies[it->second] = Pose{readVec(b.at("p")), readQuat(b.at("q"))};
        seen[it->second] = true;
      }
      for (std::size_t i = 0; i < seen.size(); ++i) {
        if (!seen[i]) throw std::runtime_error("bodies: no pose for " + model.bodies()[i].name);
      }
    }
  }
  if (h.contains("candidates")) {
    for (const json& c : h["candidates"]) {
      TrackedCandidate candidate;
      candidate.simulation = c.at("simulation").get<std::string>();
      candidate.error = readNumber(c.at("error"));
      if (c.contains("bodies")) {
        const json& bodies = c["bodies"];
        if (bodies.size() != model.bodies().size()) {
          throw std::runtime_error(fmt::format("candidates: {} bodies, the model has {}",
                                               bodies.size(), model.bodies().size()));
        }
        for (const json& b : bodies) {
          candidate.pose.bodies.push_back(Pose{readVec(b.at("p")), readQuat(b.at("q"))});
        }
      }
      hand.candidates.push_back(std::move(candidate));
    }
  }
  return hand;
}

}  // namespace

Result<std::vector<TrackedFrame>> readTrackJsonl(const std::filesystem::path& path,
                                                 const model::ArticulatedModel& model) {
  std::ifstream in(path);
  if (!in) return Error{path.string() + ": cannot open"};
  std::unordered_map<std::string, std::size_t> bodyIndex;
  for (std::size_t b = 0; b < model.bodies().size(); ++b) bodyIndex[model.bodies()[b].name] = b;
  std::vector<TrackedFrame> frames;
  std::string line;
  int lineNumber = 0;
  while (std::getline(in, line)) {
    ++lineNumber;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    try {
      const json j = json::parse(line);
      if (j.contains("version") && readInt(j["version"], "version") > kTrackFormatVersion) {
        throw std::runtime_error(
            fmt::format("\"version\" {} is newer than this dynahand understands ({})",
                        readInt(j["version"], "version"), kTrackFormatVersion));
      }
      TrackedFrame frame;
      frame.frame = readInt(j.at("frame"), "frame");
      frame.timeMs = j.value("time_ms", 0.0);
      if (j.contains("hand_size")) {
        const json& size = j["hand_size"];
        HandSizeRecord record;
        record.dimensions = {readHandDimension(size.at("length"), "length", 0.05f, 0.6f),
                             readHandDimension(size.at("width"), "width", 0.025f, 0.26f)};
        record.estimated = size.value("source", std::string("given")) == "estimated";
        if (size.contains("frames")) record.frames = readInt(size["frames"], "hand_size.frames");
        if (size.contains("fit")) record.fitScore = readNumber(size["fit"]);
        if (size.contains("metacarpals")) {
          const json& factors = size["metacarpals"];
          if (!factors.is_array() || factors.size() != record.metacarpals.size())
            throw std::runtime_error("hand_size.metacarpals: not an array of 5 numbers");
          // The synthesiser's widest proportions (--proportion-spread 0.5).
          for (std::size_t d = 0; d < record.metacarpals.size(); ++d)
            record.metacarpals[d] =
                readNumberIn(factors[d], fmt::format("hand_size.metacarpals[{}]", d), 0.5f, 1.5f);
        }
        frame.handSize = record;
      }
      for (const json& h : j.at("hands")) frame.hands.push_back(readHand(h, model, bodyIndex));
      frames.push_back(std::move(frame));
    } catch (const std::exception& e) {
      return Error{fmt::format("{}:{}: {}", path.string(), lineNumber, e.what())};
    }
  }
  if (frames.empty()) return Error{path.string() + ": no frames"};
  return frames;
}

}  // namespace dynahand::io
