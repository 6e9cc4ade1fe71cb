// Writes the seed corpora of the fuzz targets other than the sensor one (that is
// make_sensor_seeds): valid files made by dynahand's own writers plus a few near-misses, one
// folder per target, so fuzzing starts inside each reader instead of at its first check.
// scripts/fuzz.sh adds the repository's example files (examples/scenes, tests/model/data).
// Usage: make_seeds OUTPUT_DIR   (writes OUTPUT_DIR/<target>/...)
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "dynahand/model.h"
#include "dynahand/model_intel.h"
#include "dynahand/model_pose.h"
#include "dynahand/track_io.h"

namespace {

namespace fs = std::filesystem;
using namespace dynahand;

int written = 0;

void save(const fs::path& dir, const std::string& name, const std::string& bytes) {
  fs::create_directories(dir);
  std::ofstream out(dir / name, std::ios::binary | std::ios::trunc);
  out << bytes;
  ++written;
}

std::string readFile(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// A few poses of the default hand: rest, flexed, spread, moved.
std::vector<model::ModelPose> samplePoses(const model::ArticulatedModel& hand) {
  std::vector<model::ModelPose> poses;
  for (int i = 0; i < 3; ++i) {
    model::JointAngles a = model::zeroAngles(hand);
    for (Vec3& angle : a.angles)
      angle = Vec3(0.4f * static_cast<float>(i), 0.05f * static_cast<float>(i), 0.0f);
    model::clampToLimits(hand, a);
    a.root.p = Vec3(0.02f * static_cast<float>(i), -0.01f, 0.4f);
    a.root.q = Quat(Eigen::AngleAxisf(0.3f * static_cast<float>(i), Vec3::UnitY()));
    poses.push_back(model::forwardKinematics(hand, a));
  }
  return poses;
}

// A small two-body model: a box forearm and a box palm joined at the wrist.
std::string twoBoxModel() {
  return R"({"format": "dynahand-model", "version": 1,
  "metadata": {"name": "two boxes", "handedness": "none", "units": "m", "referenceLength": 0.1},
  "bodies": [
    {"name": "base", "density": 1000, "vertices": [[-0.01,-0.01,0],[0.01,-0.01,0],[-0.01,0.01,0],
      [0.01,0.01,0],[-0.01,-0.01,0.05],[0.01,-0.01,0.05],[-0.01,0.01,0.05],[0.01,0.01,0.05]]},
    {"name": "tip", "mass": 0.01, "vertices": [[-0.01,-0.01,0],[0.01,-0.01,0],[-0.01,0.01,0],
      [0.01,0.01,0],[0,0,0.04]]}
  ],
  "joints": [{"parent": "base", "child": "tip", "anchorParent": [0, 0, 0.05],
    "anchorChild": [0, 0, 0], "frame": [1, 0, 0, 0], "minDeg": [-10, -20, 0], "maxDeg": [90, 20, 0]}],
  "collision": {"ignoreJointNeighbours": true, "ignorePairs": [["base", "tip"]]},
  "keypoints": [{"name": "end", "body": "tip", "point": [0, 0, 0.04], "radius": 0.002}]
}
)";
}

// The authors' model_hand.json layout (docs/formats/model.md) for a model: a box around each
// body's hull as its control cage (theirs have 8-30 vertices; full hulls would make each
// import slow under the sanitizers), joints with x, y, z, w frames and degree limits, the
// rest pose as centre-of-mass frames.
std::string intelModelJson(const model::ArticulatedModel& m, const model::ModelPose& rest) {
  std::string s = "{\"controlcages\": [";
  for (std::size_t b = 0; b < m.bodies().size(); ++b) {
    Vec3 lo = Vec3::Constant(1e9f), hi = Vec3::Constant(-1e9f);
    for (const Vec3& v : m.bodies()[b].shape.vertices()) {
      lo = lo.cwiseMin(v);
      hi = hi.cwiseMax(v);
    }
    s += b ? ",\n{\"verts\": [" : "\n{\"verts\": [";
    for (int i = 0; i < 8; ++i) {
      s += fmt::format("{}[{},{},{}]", i ? "," : "", (i & 1 ? hi : lo).x(), (i & 2 ? hi : lo).y(),
                       (i & 4 ? hi : lo).z());
    }
    s += "], \"faces\": [[0,2,3,1],[4,5,7,6],[0,1,5,4],[2,6,7,3],[0,4,6,2],[1,3,7,5]]}";
  }
  s += "],\n\"joints\": [";
  constexpr float kDeg = 57.29578f;
  for (std::size_t j = 0; j < m.joints().size(); ++j) {
    const model::Joint& joint = m.joints()[j];
    s += fmt::format(
        "{}\n{{\"rbi0\": {}, \"rbi1\": {}, \"p0\": [{},{},{}], \"p1\": [{},{},{}], "
        "\"jointframe\": [{},{},{},{}], \"rangemin\": [{},{},{}], \"rangemax\": [{},{},{}]}}",
        j ? "," : "", joint.parent, joint.child, joint.anchorParent.x(), joint.anchorParent.y(),
        joint.anchorParent.z(), joint.anchorChild.x(), joint.anchorChild.y(), joint.anchorChild.z(),
        joint.frame.x(), joint.frame.y(), joint.frame.z(), joint.frame.w(),
        joint.minAngle.x() * kDeg, joint.minAngle.y() * kDeg, joint.minAngle.z() * kDeg,
        joint.maxAngle.x() * kDeg, joint.maxAngle.y() * kDeg, joint.maxAngle.z() * kDeg);
  }
  s += "],\n\"pose\": [";
  const std::vector<float> numbers = model::intelPoseToNumbers(rest, m);
  for (std::size_t b = 0; b < m.bodies().size(); ++b) {
    s += b ? ",\n[" : "\n[";
    for (std::size_t k = 0; k < 7; ++k) s += fmt::format("{}{}", k ? "," : "", numbers[7 * b + k]);
    s += "]";
  }
  return s + "]}\n";
}

track::TrackResult sampleResult(const model::ArticulatedModel& hand, const model::ModelPose& pose,
                                int frame, bool tracked) {
  track::TrackResult r;
  r.frame = frame;
  r.timeMs = 12.5;
  track::HandResult h;
  h.tracked = tracked;
  h.pose = pose;
  h.keypoints21 = model::keypoints21(hand, pose);
  h.openxr26 = model::openxr26(hand, pose);
  h.error = 0.004f;
  h.simulation = track::StrategyKind::GraspBias;
  track::Candidate c;
  c.kind = track::StrategyKind::Normal;
  c.ran = true;
  c.error = 0.006f;
  c.pose = pose;
  h.candidates.push_back(c);
  r.hands.push_back(h);
  return r;
}

std::string groundTruthLine(int frame, const track::Keypoints21& k) {
  std::string line = fmt::format("{{\"frame\":{},\"keypoints21\":[", frame);
  for (std::size_t i = 0; i < k.size(); ++i)
    line += fmt::format("{}[{:.6f},{:.6f},{:.6f}]", i ? "," : "", k[i].x(), k[i].y(), k[i].z());
  return line + "]}\n";
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: make_seeds OUTPUT_DIR\n");
    return 2;
  }
  const fs::path out = argv[1];
  const model::ArticulatedModel hand = model::makeDefaultHand();
  const std::vector<model::ModelPose> poses = samplePoses(hand);

  // Model files.
  save(out / "model_json", "default-hand.json", model::modelToJson(hand));
  save(out / "model_json", "left-hand.json",
       model::modelToJson(model::makeDefaultHand({0.16f, 0.07f}, model::Side::Left)));
  save(out / "model_json", "two-boxes.json", twoBoxModel());
  save(out / "model_json", "wrong-version.json",
       R"({"format": "dynahand-model", "version": 2, "metadata": {}, "bodies": [], "joints": []})");

  // The authors' hand model: the default hand's hulls as control cages, and a two-body one.
  save(out / "model_intel", "default-hand-cages.json", intelModelJson(hand, poses[0]));
  const Result<model::ArticulatedModel> boxes = model::parseModel(twoBoxModel(), "two boxes");
  if (boxes) {
    model::JointAngles a = model::zeroAngles(*boxes);
    model::clampToLimits(*boxes, a);
    save(out / "model_intel", "two-cages.json",
         intelModelJson(*boxes, model::forwardKinematics(*boxes, a)));
  }

  // Pose sequences (JSON lines) and .pose files.
  model::PoseSequence sequence;
  for (const model::Body& b : hand.bodies()) sequence.bodyNames.push_back(b.name);
  sequence.frames = poses;
  const fs::path scratch = fs::temp_directory_path() / "dynahand-make-seeds";
  fs::create_directories(scratch);
  if (model::savePoseSequence(sequence, scratch / "poses.jsonl"))
    save(out / "pose_jsonl", "default-hand.jsonl", readFile(scratch / "poses.jsonl"));
  save(out / "pose_jsonl", "header-only.jsonl",
       "{\"format\": \"dynahand-pose\", \"version\": 1, \"bodies\": [\"a\", \"b\"]}\n"
       "{\"frame\": 0, \"poses\": [[0, 0, 0.4, 1, 0, 0, 0], [0, 0.1, 0.4, 0, 1, 0, 0]]}\n");
  if (model::saveIntelPoses(scratch / "fuzz.pose", hand, poses))
    save(out / "intel_pose", "default-hand.pose", readFile(scratch / "fuzz.pose"));
  save(out / "intel_pose", "short-line.pose", "0 0 0.4  0 0 0 1   1 2 3\n");

  // Tracked poses: a tracked frame with everything, a lost one, one with the hand size.
  io::JsonOptions all;
  all.candidates = true;
  all.candidatePoses = true;
  io::JsonOptions sized;
  sized.handSize = io::HandSizeRecord{{0.18f, 0.08f}, true, 30, 0.98f};
  save(out / "track_jsonl", "tracked.jsonl",
       io::trackResultToJson(sampleResult(hand, poses[1], 0, true), hand, all) + "\n" +
           io::trackResultToJson(sampleResult(hand, poses[2], 1, false), hand, all) + "\n");
  save(out / "track_jsonl", "hand-size.jsonl",
       io::trackResultToJson(sampleResult(hand, poses[0], 0, true), hand, sized) + "\n");
  save(out / "track_jsonl", "groundtruth.jsonl",
       groundTruthLine(0, model::keypoints21(hand, poses[0])) +
           "{\"frame\":1,\"keypoints21\":null}\n" +
           groundTruthLine(3, model::keypoints21(hand, poses[2])));

  // Viewer client messages and request targets.
  for (const char* action : {"pause", "resume", "step"})
    save(out / "viewer_messages", action,
         fmt::format("{{\"type\":\"control\",\"action\":\"{}\"}}", action));
  save(out / "viewer_messages", "unknown-action", R"({"type":"control","action":"rewind"})");
  save(out / "viewer_messages", "token", "/?token=0123456789abcdef0123456789abcdef&x=1");
  save(out / "viewer_messages", "resource", "assets/viewer.js");

  std::error_code ignored;
  fs::remove_all(scratch, ignored);
  std::printf("make_seeds: wrote %d seeds under %s\n", written, out.c_str());
  return 0;
}
