// The contact sheet: every profile x a few clips, depth shaded, ground-truth skeleton on top.
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>

#include "dynahand/synth.h"

namespace dynahand::synth {
namespace {

constexpr int kTileWidth = 320, kTileHeight = 240;

// MediaPipe bones as (from, to) keypoint pairs.
constexpr int kBones[][2] = {{0, 1},   {1, 2},   {2, 3},   {3, 4},   {0, 5},   {5, 6},   {6, 7},
                             {7, 8},   {5, 9},   {9, 10},  {10, 11}, {11, 12}, {9, 13},  {13, 14},
                             {14, 15}, {15, 16}, {13, 17}, {17, 18}, {18, 19}, {19, 20}, {0, 17}};

// Per-finger joint colours (BGR): wrist/palm, thumb, index, middle, ring, pinky.
const cv::Scalar kFingerColour[6] = {{255, 255, 255}, {0, 200, 255}, {0, 255, 0},
                                     {255, 255, 0},   {255, 0, 255}, {80, 80, 255}};

int fingerOf(int keypoint) {
  return keypoint == 0 ? 0 : 1 + (keypoint - 1) / 4;
}

cv::Mat shadeDepth(const DepthFrame& depth, float nearM, float farM) {
  cv::Mat grey(depth.height, depth.width, CV_8UC1);
  cv::Mat valid(depth.height, depth.width, CV_8UC1);
  for (int v = 0; v < depth.height; ++v) {
    for (int u = 0; u < depth.width; ++u) {
      const float z = depth.metres(u, v);
      const float s = std::clamp((z - nearM) / (farM - nearM), 0.0f, 1.0f);
      grey.at<unsigned char>(v, u) = static_cast<unsigned char>(std::lround(255.0f * (1.0f - s)));
      valid.at<unsigned char>(v, u) = z > 0.0f ? 255 : 0;
    }
  }
  cv::Mat colour;
  cv::applyColorMap(grey, colour, cv::COLORMAP_TURBO);
  colour.setTo(cv::Scalar(0, 0, 0), valid == 0);
  return colour;
}

void drawSkeleton(cv::Mat& tile, const Intrinsics& k, const Keypoints21& keypoints, float scale) {
  auto pixel = [&](const Vec3& p) {
    const Vec2 uv = k.project(p) * scale;
    return cv::Point(static_cast<int>(std::lround(uv.x())), static_cast<int>(std::lround(uv.y())));
  };
  for (const auto& bone : kBones)
    cv::line(tile, pixel(keypoints[static_cast<std::size_t>(bone[0])]),
             pixel(keypoints[static_cast<std::size_t>(bone[1])]), cv::Scalar(255, 255, 255), 1,
             cv::LINE_AA);
  for (int i = 0; i < 21; ++i)
    cv::circle(tile, pixel(keypoints[static_cast<std::size_t>(i)]), 2, kFingerColour[fingerOf(i)],
               cv::FILLED, cv::LINE_AA);
}

}  // namespace

Status writeContactSheet(const std::filesystem::path& pngPath,
                         const std::vector<std::string>& clipNames, const Scene& scene,
                         std::uint64_t seed) {
  if (clipNames.empty()) return Error{"contact sheet: no clips given"};
  const std::vector<SensorProfile>& profiles = sensorProfiles();
  cv::Mat sheet(kTileHeight * static_cast<int>(profiles.size()),
                kTileWidth * static_cast<int>(clipNames.size()), CV_8UC3, cv::Scalar(0, 0, 0));
  for (std::size_t row = 0; row < profiles.size(); ++row) {
    for (std::size_t col = 0; col < clipNames.size(); ++col) {
      SynthOptions options;
      options.clip = clipNames[col];
      options.profile = profiles[row].name;
      options.seed = seed;
      options.scene = scene;
      const auto info = std::find_if(clips().begin(), clips().end(),
                                     [&](const ClipInfo& c) { return c.name == clipNames[col]; });
      if (info == clips().end())
        return Error{"contact sheet: unknown clip '" + clipNames[col] + "'"};
      const int index =
          static_cast<int>(std::lround(0.45f * info->duration * options.framesPerSecond));
      options.frameCount = index + 1;
      Result<SyntheticSequence> seq = SyntheticSequence::create(options);
      if (!seq) return seq.error();
      const SyntheticFrame& frame = seq->frame(index);
      const Vec3 wrist = frame.hands[0].keypoints[0];
      cv::Mat tile = shadeDepth(frame.depth, wrist.z() - 0.12f, wrist.z() + 0.35f);
      const float scale = static_cast<float>(kTileWidth) / static_cast<float>(frame.depth.width);
      if (tile.cols != kTileWidth)
        cv::resize(tile, tile, cv::Size(kTileWidth, kTileHeight), 0, 0, cv::INTER_NEAREST);
      for (const HandTruth& hand : frame.hands)
        drawSkeleton(tile, seq->intrinsics(), hand.keypoints, scale);
      const std::string label = profiles[row].name + " | " + clipNames[col];
      cv::putText(tile, label, cv::Point(6, 16), cv::FONT_HERSHEY_SIMPLEX, 0.45,
                  cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
      tile.copyTo(sheet(cv::Rect(kTileWidth * static_cast<int>(col),
                                 kTileHeight * static_cast<int>(row), kTileWidth, kTileHeight)));
    }
  }
  std::error_code ec;
  if (pngPath.has_parent_path()) std::filesystem::create_directories(pngPath.parent_path(), ec);
  try {
    if (!cv::imwrite(pngPath.string(), sheet))
      return Error{pngPath.string() + ": could not write the PNG"};
  } catch (const cv::Exception& e) {
    return Error{pngPath.string() + ": " + e.what()};
  }
  return Ok{};
}

}  // namespace dynahand::synth
