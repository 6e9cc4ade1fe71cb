// The canonical layout: camera.json + depth/NNNNNN.png + optional groundtruth.jsonl.
#include <algorithm>
#include <cctype>
#include <cstdio>
#include <fstream>
#include <string>

#include "sensor/camera_json.h"
#include "sensor/frame_source.h"
#include "sensor/png_depth.h"

namespace dynahand::sensor {
namespace {

namespace fs = std::filesystem;

class CanonicalSource final : public FrameSource {
 public:
  CanonicalSource(fs::path depthDir, const SequenceInfo& info)
      : depthDir_(std::move(depthDir)), info_(info) {}

  Result<DepthFrame> read(int index) const override {
    const fs::path file = depthDir_ / framePngName(index);
    auto bytes = readFileBytes(file);
    if (!bytes) return bytes.error();
    auto frame =
        decodeDepthPng16(*bytes, file.string(), info_.intrinsics.width, info_.intrinsics.height);
    if (!frame) return frame.error();
    frame->depthScale = info_.depthScale;
    frame->timestamp = index / static_cast<double>(info_.framesPerSecond);
    return frame;
  }

 private:
  fs::path depthDir_;
  SequenceInfo info_;
};

// Frame number of a file named like 000042.png, or -1.
long long frameNumber(const std::string& filename) {
  if (filename.size() < 10 || filename.size() > 13 ||
      filename.substr(filename.size() - 4) != ".png")
    return -1;
  const std::string digits = filename.substr(0, filename.size() - 4);
  if (!std::all_of(digits.begin(), digits.end(),
                   [](unsigned char c) { return std::isdigit(c) != 0; }))
    return -1;
  return std::stoll(digits);
}

}  // namespace

Result<std::vector<std::optional<Keypoints21>>> readGroundTruthFile(const fs::path& file,
                                                                    int frameCount) {
  std::ifstream in(file);
  if (!in) return Error{file.string() + ": cannot open for reading"};
  std::vector<std::optional<Keypoints21>> truth(static_cast<std::size_t>(frameCount));
  std::vector<bool> seen(static_cast<std::size_t>(frameCount), false);
  std::string line;
  int lineNumber = 0;
  while (std::getline(in, line)) {
    ++lineNumber;
    if (std::all_of(line.begin(), line.end(), [](unsigned char c) { return std::isspace(c) != 0; }))
      continue;
    const std::string where = file.string() + " line " + std::to_string(lineNumber);
    auto parsed = parseGroundTruthLine(line, where);
    if (!parsed) return parsed.error();
    if (parsed->frame >= frameCount) {
      return Error{where + ": frame " + std::to_string(parsed->frame) +
                   " is past the last frame (" + std::to_string(frameCount) + " frames in depth/)"};
    }
    if (seen[static_cast<std::size_t>(parsed->frame)]) {
      return Error{where + ": frame " + std::to_string(parsed->frame) + " appears twice"};
    }
    seen[static_cast<std::size_t>(parsed->frame)] = true;
    truth[static_cast<std::size_t>(parsed->frame)] = parsed->keypoints;
  }
  if (in.bad()) return Error{file.string() + ": read error"};
  return truth;
}

Result<OpenedSource> openCanonical(const fs::path& dir) {
  const fs::path cameraFile = dir / "camera.json";
  auto text = readFileBytes(cameraFile);
  if (!text) return text.error();
  auto camera = parseCameraJson(
      std::string_view(reinterpret_cast<const char*>(text->data()), text->size()),  // NOLINT
      cameraFile.string());
  if (!camera) return camera.error();

  const fs::path depthDir = dir / "depth";
  std::error_code ec;
  if (!fs::is_directory(depthDir, ec)) {
    return Error{depthDir.string() +
                 ": missing (a sequence keeps its frames as depth/000000.png, ...)"};
  }
  std::vector<long long> numbers;
  for (const auto& entry : fs::directory_iterator(depthDir, ec)) {
    const std::string filename = entry.path().filename().string();
    if (filename.ends_with(".tmp")) continue;  // a write interrupted by a crash
    const long long number = frameNumber(filename);
    if (number < 0) {
      return Error{entry.path().string() +
                   ": unexpected file in depth/ (frames are named NNNNNN.png)"};
    }
    numbers.push_back(number);
  }
  if (ec) return Error{depthDir.string() + ": cannot list the folder: " + ec.message()};
  std::sort(numbers.begin(), numbers.end());
  for (std::size_t i = 0; i < numbers.size(); ++i) {
    if (numbers[i] != static_cast<long long>(i)) {
      return Error{(depthDir / framePngName(static_cast<int>(i))).string() +
                   ": missing (frames must be numbered from 000000 without gaps; found " +
                   std::to_string(numbers.size()) + " PNG files)"};
    }
  }

  OpenedSource opened;
  opened.info.intrinsics = camera->intrinsics;
  opened.info.depthScale = camera->depthScale;
  opened.info.framesPerSecond = camera->framesPerSecond;
  opened.info.minRangeM = camera->minRangeM;
  opened.info.frameCount = static_cast<int>(numbers.size());
  opened.info.format = "canonical";
  opened.info.path = dir;
  const fs::path truthFile = dir / "groundtruth.jsonl";
  if (fs::exists(truthFile, ec)) {
    auto truth = readGroundTruthFile(truthFile, opened.info.frameCount);
    if (!truth) return truth.error();
    opened.groundTruth = std::move(*truth);
    opened.info.hasGroundTruth = true;
  }
  opened.source = std::make_unique<CanonicalSource>(depthDir, opened.info);
  return opened;
}

}  // namespace dynahand::sensor
