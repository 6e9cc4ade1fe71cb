/// @file
/// Depth sequences on disk: the canonical dynahand layout (read and write) and the
/// other recordings dynahand can read. Layouts are documented in docs/formats.md.
///
/// Canonical layout (a directory):
///   camera.json          {"version":1,"width":W,"height":H,"fx":..,"fy":..,"cx":..,"cy":..,
///                         "depth_scale":0.001}   depth_scale = metres per stored unit
///   depth/000000.png ... 16-bit single-channel PNG, frames in order, no gaps
///   groundtruth.jsonl    optional, one line per frame:
///                        {"frame":i,"keypoints21":[[x,y,z] x 21]} (m, camera frame,
///                        MediaPipe order) or {"frame":i,"keypoints21":null} (no hand)
///
/// SequenceReader::open also reads, detected from the path:
///   - NAME.rs + NAME.json (the original authors' raw layout; path to either file or to NAME);
///   - a folder of NYU packed PNGs (8-bit RGB, depth mm = G * 256 + B);
///   - a folder of plain 16-bit PNGs (needs SequenceOpenOptions::intrinsics);
///   - OpenNI .oni recordings (when built with OpenNI2, see sequenceFormats()).
#pragma once

#include <array>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "dynahand/core.h"
#include "dynahand/depth_frame.h"

namespace dynahand {

/// The 21 hand keypoints, metres, camera frame, MediaPipe order (0 wrist, 1-4 thumb
/// CMC..tip, 5-8 index MCP..tip, 9-12 middle, 13-16 ring, 17-20 pinky).
using Keypoints21 = std::array<Vec3, 21>;

/// The version written into camera.json by SequenceWriter (missing = 1 when read).
inline constexpr int kSequenceFormatVersion = 1;

/// What a recording holds: its camera, depth scale, frame count and format.
struct SequenceInfo {
  Intrinsics intrinsics;          ///< the depth camera
  float depthScale = 0.001f;      ///< metres per stored depth unit
  int frameCount = 0;             ///< frames in the recording
  bool hasGroundTruth = false;    ///< groundtruth.jsonl present (canonical layout only)
  float framesPerSecond = 30.0f;  ///< frame i has timestamp i / framesPerSecond, s
  /// The camera's near range (m): nothing nearer is measured (camera.json "min_range_m");
  /// 0 = not recorded.
  float minRangeM = 0.0f;
  std::string format;          ///< "canonical", "intel-rs", "nyu-png", "png16", "oni"
  std::filesystem::path path;  ///< what was opened
};

/// Writes the canonical layout. camera.json is written by create(), each frame as it
/// arrives, groundtruth.jsonl once the first ground truth is given (earlier frames
/// then get null). Refuses a directory that already holds a sequence.
class SequenceWriter {
 public:
  /// Starts a sequence in dir (created if needed) and writes camera.json; errors for bad
  /// intrinsics, depth scale, frame rate or near range, or a directory that already holds a
  /// sequence. minRangeM: the camera's near range (m), 0 = not known (not written).
  static Result<SequenceWriter> create(const std::filesystem::path& dir,
                                       const Intrinsics& intrinsics, float depthScale,
                                       float framesPerSecond = 30.0f, float minRangeM = 0.0f);
  SequenceWriter(SequenceWriter&&) noexcept;             ///< Moves the writer.
  SequenceWriter& operator=(SequenceWriter&&) noexcept;  ///< Moves the writer.
  ~SequenceWriter();  ///< closes (errors are logged; call close() to see them)

  /// The frame must match the intrinsics' size and the writer's depth scale.
  Status write(const DepthFrame& frame,
               const std::optional<Keypoints21>& groundTruth = std::nullopt);
  Status close();  ///< flushes groundtruth.jsonl; further writes are refused
  int framesWritten() const { return frameCount_; }                ///< frames written so far
  const std::filesystem::path& directory() const { return dir_; }  ///< the sequence directory

 private:
  SequenceWriter() = default;
  std::filesystem::path dir_;
  Intrinsics intrinsics_;
  float depthScale_ = 0.001f;
  int frameCount_ = 0;
  bool closed_ = false;
  std::unique_ptr<std::ofstream> groundTruth_;  ///< open once any ground truth was written
};

/// How to interpret recordings that do not describe their camera themselves.
struct SequenceOpenOptions {
  /// Required for plain 16-bit PNG folders; for NYU folders it replaces the NYU
  /// Kinect intrinsics; ignored by formats that carry their own.
  std::optional<Intrinsics> intrinsics;
  /// Metres per stored unit for plain 16-bit PNG folders (default 0.001 = mm).
  std::optional<float> depthScale;
};

namespace sensor {
class FrameSource;  ///< one implementation per format (src/sensor/frame_source.h)
}

/// Random access to the frames of a recording. frame() decodes on demand; bad
/// frames (truncated PNG, wrong bit depth, wrong size) are reported per frame.
class SequenceReader {
 public:
  /// Detects the format from the path (see the file comment).
  static Result<SequenceReader> open(const std::filesystem::path& path);
  /// The same, with intrinsics or a depth scale for formats that lack them.
  static Result<SequenceReader> open(const std::filesystem::path& path,
                                     const SequenceOpenOptions& options);

  SequenceReader(SequenceReader&&) noexcept;             ///< Moves the reader.
  SequenceReader& operator=(SequenceReader&&) noexcept;  ///< Moves the reader.
  ~SequenceReader();

  const SequenceInfo& info() const { return info_; }   ///< what the recording holds
  int frameCount() const { return info_.frameCount; }  ///< info().frameCount
  /// index in [0, frameCount()); an out-of-range index is an Error, not a crash.
  Result<DepthFrame> frame(int index) const;
  std::optional<Keypoints21> groundTruth(int index) const;  ///< nullopt: none / no hand

 private:
  SequenceReader() = default;
  SequenceInfo info_;
  std::unique_ptr<sensor::FrameSource> source_;
  std::vector<std::optional<Keypoints21>> groundTruth_;  ///< (frameCount) when present
};

/// Formats SequenceReader::open understands in this build ("oni" only with OpenNI2).
std::vector<std::string> sequenceFormats();

}  // namespace dynahand
