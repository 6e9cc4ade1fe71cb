// Tracker output formats (docs/formats.md, "Tracked poses"): JSON lines, CSV of the
// 21 keypoints, and BVH skeleton animation. Metres and unit quaternions (w, x, y, z)
// in JSON; metres in CSV; centimetres and degrees in BVH (what animation tools expect).
#pragma once

#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "dynahand/model.h"
#include "dynahand/tracker.h"

namespace dynahand::io {

inline constexpr int kTrackFormatVersion = 1;

struct JsonOptions {
  bool bodies = true;       // per-body poses
  bool openxr = true;       // the 26 OpenXR joints
  bool candidates = false;  // every simulation's error (and, with candidatePoses, poses)
  bool candidatePoses = false;
};

// One frame as a single-line JSON object (no trailing newline). bodyNames: the
// model's body names (the same for both hands).
std::string trackResultToJson(const track::TrackResult& result,
                              const model::ArticulatedModel& model,
                              const JsonOptions& options = {});

// Streams frames to a file as they come, so an interrupted run keeps what it wrote.
class TrackWriter {
 public:
  enum class Format { JsonLines, Csv };
  // The format follows the extension unless given: .jsonl/.json -> JSON lines, .csv -> CSV.
  static Result<std::unique_ptr<TrackWriter>> create(const std::filesystem::path& path,
                                                     const model::ArticulatedModel& model,
                                                     const JsonOptions& options = {});
  Status write(const track::TrackResult& result);
  Status close();
  Format format() const { return format_; }

 private:
  TrackWriter() = default;
  std::filesystem::path path_;
  const model::ArticulatedModel* model_ = nullptr;
  JsonOptions options_;
  Format format_ = Format::JsonLines;
  std::ofstream out_;
};

// BVH: a HIERARCHY from the model's bodies (root = the model's root with 6 channels,
// every other body 3 rotation channels, ZXY order) and a MOTION block of every frame
// added. Frames where the hand is not tracked repeat the last tracked pose.
class BvhWriter {
 public:
  BvhWriter(const model::ArticulatedModel& model, float framesPerSecond);
  void add(const model::ModelPose& pose);
  std::string text() const;
  Status save(const std::filesystem::path& path) const;
  int frameCount() const { return static_cast<int>(frames_.size()); }

 private:
  const model::ArticulatedModel* model_;
  float fps_;
  std::vector<std::vector<float>> frames_;  // channel values per frame
};

}  // namespace dynahand::io
