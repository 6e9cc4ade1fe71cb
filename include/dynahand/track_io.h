/// @file
/// Tracker output formats (docs/formats.md, "Tracked poses"): JSON lines, CSV of the
/// 21 keypoints, the original authors' .pose, and BVH skeleton animation. Metres and unit
/// quaternions (w, x, y, z) in JSON; metres in CSV; centimetres and degrees in BVH (what animation
/// tools expect).
#pragma once

#include <array>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "dynahand/atomic_file.h"
#include "dynahand/hand_size.h"
#include "dynahand/model.h"
#include "dynahand/tracker.h"

namespace dynahand::io {

/// The "version" written in every JSON line; readTrackJsonl rejects newer ones.
inline constexpr int kTrackFormatVersion = 1;

/// The built-in hand's size the poses were tracked with ("hand_size" in every JSON line).
struct HandSizeRecord {
  model::HandDimensions dimensions;  ///< m
  bool estimated = false;            ///< by estimateHandSize (hand_size.h); else given
  int frames = 0;                    ///< estimated: frames the estimate used
  float fitScore = 0.0f;             ///< estimated: HandSizeEstimate::fitScore
  /// Each digit's metacarpal length factor (thumb..pinky; model::HandShape::boneLength[d][0]),
  /// 1: the default hand's. Estimated ones: HandSizeEstimate::shape.
  std::array<float, 5> metacarpals = {1.0f, 1.0f, 1.0f, 1.0f, 1.0f};

  /// The built-in hand's shape this record describes (its metacarpals; the rest 1).
  model::HandShape shape() const;
  /// The record of an estimate (estimated = true).
  static HandSizeRecord fromEstimate(const track::HandSizeEstimate& estimate);
};

/// What trackResultToJson writes besides the keypoints.
struct JsonOptions {
  std::optional<HandSizeRecord> handSize;  ///< none: a model file (its size is not a record)
  bool bodies = true;                      ///< per-body poses
  bool openxr = true;                      ///< the 26 OpenXR joints
  bool candidates = false;      ///< every simulation's error (and, with candidatePoses, poses)
  bool candidatePoses = false;  ///< with candidates: each simulation's body poses
  /// The input's index of the tracker's first frame: the frame numbers written are
  /// TrackResult::frame plus this (`dynahand track --start N` tracks from input frame N).
  int firstFrame = 0;
};

/// One frame as a single-line JSON object (no trailing newline). model: the tracked model,
/// whose body names label the poses (the same for both hands).
std::string trackResultToJson(const track::TrackResult& result,
                              const model::ArticulatedModel& model,
                              const JsonOptions& options = {});

/// Streams frames as they come to PATH.part and renames it to PATH on close(): a run that is
/// interrupted and closes keeps what it wrote under PATH; one that dies leaves only PATH.part,
/// never a partial file under the final name.
class TrackWriter {
 public:
  /// The file format written, chosen by the extension (see create).
  enum class Format { JsonLines, Csv, IntelPose };
  /// The format follows the extension: .jsonl/.json/.ndjson -> JSON lines, .csv -> CSV,
  /// .pose -> the original authors' format (model_intel.h) of the first hand, one line per
  /// frame; frames where it is lost repeat the nearest tracked pose (earlier, else later).
  static Result<std::unique_ptr<TrackWriter>> create(const std::filesystem::path& path,
                                                     const model::ArticulatedModel& model,
                                                     const JsonOptions& options = {});
  /// Writes one frame and flushes it (.pose may hold lines back until a tracked frame).
  Status write(const track::TrackResult& result);
  Status close();  ///< flushes, closes and renames PATH.part to PATH (once; later calls: Ok)
  Format format() const { return format_; }  ///< the format being written

 private:
  TrackWriter() = default;
  const model::ArticulatedModel* model_ = nullptr;
  JsonOptions options_;
  Format format_ = Format::JsonLines;
  AtomicFileWriter file_;         ///< PATH.part until close()
  model::ModelPose lastTracked_;  ///< .pose: repeated while the hand is lost
  int pendingLines_ = 0;          ///< .pose: frames before the first tracked one
};

/// One simulation's outcome for a TrackedHand (written with JsonOptions::candidates).
struct TrackedCandidate {
  std::string simulation;  ///< strategyName()
  float error = 0.0f;      ///< m
  model::ModelPose pose;   ///< empty unless written with candidate poses
};
/// One hand of one frame read back from the JSON lines.
struct TrackedHand {
  model::Side side = model::Side::Right;  ///< which hand
  bool tracked = false;                   ///< a pose was reported (the hand was not lost)
  model::ModelPose pose;  ///< body poses (empty when not tracked or written without bodies)
  std::array<Vec3, 21> keypoints21{};        ///< MediaPipe order, m (zero when not tracked)
  float error = 0.0f;                        ///< the winner's error, m
  std::string simulation;                    ///< the winning simulation's strategyName()
  std::vector<TrackedCandidate> candidates;  ///< empty unless written with candidates
};
/// One frame (one JSON line) read back.
struct TrackedFrame {
  int frame = 0;                           ///< frame index, from 0
  double timeMs = 0.0;                     ///< tracker time for the frame, ms
  std::optional<HandSizeRecord> handSize;  ///< none when the line has no hand_size
  std::vector<TrackedHand> hands;          ///< the hands, as written
};

/// Reads `dynahand track` JSON lines. Bodies are matched to `model` by name (candidates'
/// bodies by order); errors name the file, line and problem.
Result<std::vector<TrackedFrame>> readTrackJsonl(const std::filesystem::path& path,
                                                 const model::ArticulatedModel& model);

/// BVH: a HIERARCHY from the model's bodies (root = the model's root with 6 channels,
/// every other body 3 rotation channels, ZXY order) and a MOTION block of every frame
/// added. Frames where the hand is not tracked repeat the last tracked pose.
class BvhWriter {
 public:
  /// A writer for poses of `model` (kept by reference), played at framesPerSecond.
  BvhWriter(const model::ArticulatedModel& model, float framesPerSecond);
  /// Appends one MOTION frame from a full model pose (every body).
  void add(const model::ModelPose& pose);
  std::string text() const;  ///< the whole BVH file: HIERARCHY and MOTION
  /// Writes text() to path atomically (never a truncated file under path).
  Status save(const std::filesystem::path& path) const;
  int frameCount() const { return static_cast<int>(frames_.size()); }  ///< frames added

 private:
  const model::ArticulatedModel* model_;
  float fps_;
  std::vector<std::vector<float>> frames_;  ///< channel values per frame
};

}  // namespace dynahand::io
