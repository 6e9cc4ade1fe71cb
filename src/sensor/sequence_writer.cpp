// SequenceWriter: the canonical layout, written frame by frame.
#include <cmath>
#include <cstdio>

#include "core/log.h"
#include "dynahand/sequence.h"
#include "sensor/camera_json.h"
#include "sensor/png_depth.h"

namespace dynahand {
namespace {

namespace fs = std::filesystem;

}  // namespace

SequenceWriter::SequenceWriter(SequenceWriter&&) noexcept = default;
SequenceWriter& SequenceWriter::operator=(SequenceWriter&&) noexcept = default;

SequenceWriter::~SequenceWriter() {
  if (!dir_.empty() && !closed_) {
    if (auto status = close(); !status) log::error("{}", status.message());
  }
}

Result<SequenceWriter> SequenceWriter::create(const fs::path& dir, const Intrinsics& intrinsics,
                                              float depthScale, float framesPerSecond,
                                              float minRangeM) {
  if (const std::string problem = intrinsics.problem(); !problem.empty()) {
    return Error{dir.string() + ": cannot write a sequence with bad intrinsics: " + problem};
  }
  if (auto ok = sensor::checkDepthScale(static_cast<double>(depthScale), dir.string()); !ok)
    return ok.error();
  if (!std::isfinite(framesPerSecond) || framesPerSecond <= 0.0f) {
    return Error{dir.string() + ": frames per second must be positive"};
  }
  if (!std::isfinite(minRangeM) || minRangeM < 0.0f || minRangeM > 100.0f) {
    return Error{dir.string() + ": the near range must be in [0, 100] m"};
  }
  std::error_code ec;
  if (fs::exists(dir / "camera.json", ec) || fs::exists(dir / "depth", ec)) {
    return Error{dir.string() +
                 ": already holds a sequence (camera.json or depth/); choose a new folder"};
  }
  fs::create_directories(dir / "depth", ec);
  if (ec) return Error{(dir / "depth").string() + ": cannot create: " + ec.message()};
  const std::string json =
      sensor::formatCameraJson({intrinsics, depthScale, framesPerSecond, minRangeM});
  const auto* bytes = reinterpret_cast<const std::uint8_t*>(json.data());  // NOLINT
  if (auto ok = sensor::writeFileBytes(dir / "camera.json", {bytes, json.size()}); !ok)
    return ok.error();
  SequenceWriter writer;
  writer.dir_ = dir;
  writer.intrinsics_ = intrinsics;
  writer.depthScale_ = depthScale;
  return writer;
}

Status SequenceWriter::write(const DepthFrame& frame,
                             const std::optional<Keypoints21>& groundTruth) {
  const std::string where = dir_.string() + " frame " + std::to_string(frameCount_);
  if (closed_) return Error{where + ": the writer is closed"};
  if (!frame.consistent()) return Error{where + ": depth buffer does not match width x height"};
  if (frame.width != intrinsics_.width || frame.height != intrinsics_.height) {
    return Error{where + ": frame is " + std::to_string(frame.width) + " x " +
                 std::to_string(frame.height) + " but the sequence is " +
                 std::to_string(intrinsics_.width) + " x " + std::to_string(intrinsics_.height)};
  }
  if (frame.depthScale != depthScale_) {
    return Error{where + ": frame depth scale " + std::to_string(frame.depthScale) +
                 " m/unit differs from the sequence's " + std::to_string(depthScale_)};
  }
  if (groundTruth) {
    for (const Vec3& p : *groundTruth) {
      if (!p.allFinite()) return Error{where + ": ground-truth keypoints are not finite"};
    }
  }
  auto png = sensor::encodeDepthPng16(frame);
  if (!png) return Error{where + ": " + png.message()};
  if (auto ok = sensor::writeFileBytes(dir_ / "depth" / sensor::framePngName(frameCount_), *png);
      !ok)
    return ok;

  if (groundTruth && !groundTruth_) {
    const fs::path file = dir_ / "groundtruth.jsonl";
    groundTruth_ = std::make_unique<std::ofstream>(file, std::ios::trunc);
    if (!*groundTruth_) return Error{file.string() + ": cannot open for writing"};
    for (int i = 0; i < frameCount_; ++i)
      *groundTruth_ << sensor::formatGroundTruthLine(i, std::nullopt);
  }
  if (groundTruth_) {
    *groundTruth_ << sensor::formatGroundTruthLine(frameCount_, groundTruth);
    if (!*groundTruth_) return Error{(dir_ / "groundtruth.jsonl").string() + ": write error"};
  }
  ++frameCount_;
  return Ok{};
}

Status SequenceWriter::close() {
  if (closed_) return Ok{};
  closed_ = true;
  if (groundTruth_) {
    groundTruth_->close();
    if (groundTruth_->fail())
      return Error{(dir_ / "groundtruth.jsonl").string() + ": write error on close"};
    groundTruth_.reset();
  }
  return Ok{};
}

}  // namespace dynahand
