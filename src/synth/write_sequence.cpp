// Writing a synthetic sequence to disk: the canonical layout through SequenceWriter, model
// poses through savePoseSequence, the second hand's keypoints and synth.json
// (docs/formats/synth.md).
#include <fmt/format.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "dynahand/synth.h"

namespace dynahand::synth {
namespace {

constexpr int kSynthFormatVersion = 4;

const char* placementName(CameraPlacement p) {
  return p == CameraPlacement::DeskFacing ? "desk" : "head";
}
const char* backgroundName(Background b) {
  switch (b) {
    case Background::None:
      return "none";
    case Background::Wall:
      return "wall";
    case Background::Torso:
      return "torso";
  }
  return "none";
}

std::string keypointLine(int frame, const Keypoints21& k) {
  std::string line = fmt::format("{{\"frame\":{},\"keypoints21\":[", frame);
  for (std::size_t i = 0; i < k.size(); ++i)
    line += fmt::format("{}[{:.6f},{:.6f},{:.6f}]", i ? "," : "", k[i].x(), k[i].y(), k[i].z());
  return line + "]}\n";
}

std::string describe(const SyntheticSequence& seq, int writtenFrames) {
  const SynthOptions& o = seq.options();
  nlohmann::ordered_json j;
  j["format"] = "dynahand-synth";
  j["version"] = kSynthFormatVersion;
  if (o.poseFile.empty())
    j["clip"] = o.clip;
  else
    j["pose_file"] = o.poseFile.string();
  j["profile"] = o.profile;
  j["device"] = seq.profile().device;
  j["frames"] = writtenFrames;
  j["fps"] = o.framesPerSecond;
  j["speed"] = o.speed;
  j["seed"] = o.seed;
  j["hands"] = seq.handCount();
  j["hand_length_m"] = o.hand.length;
  j["hand_width_m"] = o.hand.width;
  j["scene"] = {{"placement", placementName(o.scene.placement)},
                {"background", backgroundName(o.scene.background)},
                {"background_distance_m", o.scene.backgroundDistance},
                {"table", o.scene.table},
                {"table_drop_m", o.scene.tableDrop},
                {"table_below_hand", o.scene.tableBelowHand},
                {"hand_distance_m", o.scene.handDistance},
                {"held_object", heldObjectName(o.scene.heldObject)},
                {"held_object_size_m", o.scene.heldObjectSize},
                {"view_shift_px", {o.scene.viewShift.x(), o.scene.viewShift.y()}}};
  const HandProportions& p = o.proportions;
  // Element by element (GCC's -Wnull-dereference misfires on nlohmann's std::array path).
  nlohmann::ordered_json bones = nlohmann::ordered_json::array();
  nlohmann::ordered_json thickness = nlohmann::ordered_json::array();
  for (std::size_t f = 0; f < p.boneLength.size(); ++f) {
    nlohmann::ordered_json finger = nlohmann::ordered_json::array();
    for (float length : p.boneLength[f]) finger.push_back(static_cast<double>(length));
    bones.push_back(std::move(finger));
    thickness.push_back(static_cast<double>(p.fingerThickness[f]));
  }
  j["proportions"] = {{"bone_length", std::move(bones)},
                      {"finger_thickness", std::move(thickness)},
                      {"palm_thickness", p.palmThickness}};
  return j.dump(2) + "\n";
}

}  // namespace

Status writeSequence(SyntheticSequence& seq, const std::filesystem::path& dir,
                     const std::function<bool(int, int)>& progress) {
  Result<SequenceWriter> writer =
      SequenceWriter::create(dir, seq.intrinsics(), seq.profile().depthScale,
                             seq.options().framesPerSecond, seq.profile().minRange);
  if (!writer) return writer.error();
  std::ofstream secondHand;
  if (seq.handCount() == 2) {
    secondHand.open(dir / "groundtruth_hand1.jsonl");
    if (!secondHand)
      return Error{(dir / "groundtruth_hand1.jsonl").string() + ": cannot create the file"};
  }
  std::vector<model::PoseSequence> poses(static_cast<std::size_t>(seq.handCount()));
  for (int h = 0; h < seq.handCount(); ++h) {
    for (const model::Body& body : seq.model(h).bodies())
      poses[static_cast<std::size_t>(h)].bodyNames.push_back(body.name);
    poses[static_cast<std::size_t>(h)].frames.reserve(static_cast<std::size_t>(seq.frameCount()));
  }

  const int total = seq.frameCount();
  for (int i = 0; i < total; ++i) {
    const SyntheticFrame& frame = seq.frame(i);
    if (Status s = writer->write(frame.depth, frame.hands[0].keypoints); !s) return s;
    for (std::size_t h = 0; h < frame.hands.size(); ++h)
      poses[h].frames.push_back(frame.hands[h].pose);
    if (secondHand.is_open()) secondHand << keypointLine(i, frame.hands[1].keypoints);
    if (progress && !progress(i + 1, total)) break;
  }
  if (Status s = writer->close(); !s) return s;
  if (secondHand.is_open()) {
    secondHand.close();
    if (!secondHand) return Error{(dir / "groundtruth_hand1.jsonl").string() + ": write failed"};
  }
  for (std::size_t h = 0; h < poses.size(); ++h) {
    const std::filesystem::path path = dir / (h == 0 ? "poses.jsonl" : "poses_hand1.jsonl");
    if (Status s = model::savePoseSequence(poses[h], path); !s) return s;
  }
  std::ofstream meta(dir / "synth.json");
  meta << describe(seq, static_cast<int>(poses[0].frames.size()));
  if (!meta) return Error{(dir / "synth.json").string() + ": write failed"};
  return Ok{};
}

}  // namespace dynahand::synth
