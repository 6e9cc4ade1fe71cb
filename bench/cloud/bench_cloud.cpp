// Depth frame -> filtered, segmented, voxel-subsampled cloud + boundary planes.
// Targets (issue 5): 640x480 <= 1.0 ms, 320x240 <= 0.3 ms per frame on one core.
//
//   build/<dir>/bench/cloud/bench_cloud --benchmark_repetitions=5
//       --benchmark_report_aggregates_only=true   (one command line)
#include <benchmark/benchmark.h>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <vector>

#include "cloud/scenes.h"
#include "dynahand/cloud.h"
#include "dynahand/hand_split.h"

namespace dynahand {
namespace {

namespace fs = std::filesystem;

struct Clip {
  Intrinsics k;
  std::vector<DepthFrame> frames;
};

// A hand with its forearm 0.45 m from the camera in front of a wall at 0.9 m.
Clip syntheticClip(int width, int height) {
  Clip clip;
  clip.k = cloud::scenes::camera(width, height);
  clip.frames.push_back(cloud::scenes::render(
      clip.k, cloud::scenes::handWithForearm(Vec3(0.03f, -0.02f, 0.45f), 0.35f), 0.9f));
  return clip;
}

// All sr305-hands frames, optionally halved (every other pixel, intrinsics halved).
Clip sr305Clip(bool half) {
  Clip clip;
  const char* env = std::getenv("DYNAHAND_SHARED_DIR");
  const fs::path root = fs::path(env ? env : DYNAHAND_SHARED_DIR) / "data" / "sr305-hands";
  if (!fs::is_directory(root)) return clip;
  for (const char* name : {"20210326-230536", "20210326-231615"}) {
    std::ifstream file(root / name / "camera.json");
    const nlohmann::json camera = nlohmann::json::parse(file);
    const int step = half ? 2 : 1;
    clip.k.width = camera.at("width").get<int>() / step;
    clip.k.height = camera.at("height").get<int>() / step;
    clip.k.fx = camera.at("fx").get<float>() / static_cast<float>(step);
    clip.k.fy = camera.at("fy").get<float>() / static_cast<float>(step);
    clip.k.cx = camera.at("cx").get<float>() / static_cast<float>(step);
    clip.k.cy = camera.at("cy").get<float>() / static_cast<float>(step);
    const float scale = camera.at("depth_scale").get<float>();
    std::vector<fs::path> pngs;
    for (const auto& e : fs::directory_iterator(root / name / "depth")) pngs.push_back(e.path());
    std::sort(pngs.begin(), pngs.end());
    for (const fs::path& png : pngs) {
      const cv::Mat image = cv::imread(png.string(), cv::IMREAD_UNCHANGED);
      if (image.type() != CV_16UC1) continue;
      DepthFrame frame(clip.k.width, clip.k.height, scale);
      for (int v = 0; v < clip.k.height; ++v) {
        for (int u = 0; u < clip.k.width; ++u) {
          frame.at(u, v) = image.at<std::uint16_t>(v * step, u * step);
        }
      }
      clip.frames.push_back(std::move(frame));
    }
  }
  return clip;
}

void runPipeline(benchmark::State& state, const Clip& clip, const CloudConfig& config) {
  if (clip.frames.empty()) {
    state.SkipWithError("no frames (../shared/data/sr305-hands absent)");
    return;
  }
  CloudPipeline pipeline(clip.k, config);
  CloudFrame out;
  for (const DepthFrame& f : clip.frames) {  // warm-up: buffers reach their size
    if (!pipeline.process(f, out).ok()) state.SkipWithError("bad frame");
  }
  std::size_t i = 0;
  std::size_t points = 0;
  std::size_t samples = 0;
  std::size_t boxSamples = 0;
  std::size_t frames = 0;
  for (auto _ : state) {
    const Status status = pipeline.process(clip.frames[i], out);
    benchmark::DoNotOptimize(status);
    benchmark::DoNotOptimize(out.points.data());
    points += out.pointCount();
    samples += static_cast<std::size_t>(out.segment.sampleCount);
    boxSamples += static_cast<std::size_t>(out.filterColumns) * out.filterRows;
    ++frames;
    i = (i + 1) % clip.frames.size();
  }
  const auto perFrame = [&](std::size_t n) {
    return static_cast<double>(n) / static_cast<double>(std::max<std::size_t>(frames, 1));
  };
  // Voxels out; segmented samples voxelised; samples filtered (the box at the stride).
  state.counters["points"] = perFrame(points);
  state.counters["samples"] = perFrame(samples);
  state.counters["boxSamples"] = perFrame(boxSamples);
  state.counters["frames/s"] =
      benchmark::Counter(static_cast<double>(frames), benchmark::Counter::kIsRate);
}

CloudConfig withGrowStep2() {
  CloudConfig config;
  config.segmentation.growStep = 2;
  return config;
}
void BM_Cloud_Synthetic320x240_GrowStep2(benchmark::State& state) {
  static const Clip clip = syntheticClip(320, 240);
  runPipeline(state, clip, withGrowStep2());
}
void BM_Cloud_Sr305_320x240_GrowStep2(benchmark::State& state) {
  static const Clip clip = sr305Clip(true);
  runPipeline(state, clip, withGrowStep2());
}

CloudConfig withBilateral() {
  CloudConfig config;
  config.filter.bilateral = true;
  return config;
}

void BM_Cloud_Synthetic640x480(benchmark::State& state) {
  static const Clip clip = syntheticClip(640, 480);
  runPipeline(state, clip, CloudConfig{});
}
void BM_Cloud_Synthetic320x240(benchmark::State& state) {
  static const Clip clip = syntheticClip(320, 240);
  runPipeline(state, clip, CloudConfig{});
}
void BM_Cloud_Sr305_640x480(benchmark::State& state) {
  static const Clip clip = sr305Clip(false);
  runPipeline(state, clip, CloudConfig{});
}
void BM_Cloud_Sr305_320x240(benchmark::State& state) {
  static const Clip clip = sr305Clip(true);
  runPipeline(state, clip, CloudConfig{});
}
void BM_Cloud_Sr305_640x480_Bilateral(benchmark::State& state) {
  static const Clip clip = sr305Clip(false);
  runPipeline(state, clip, withBilateral());
}
void BM_Cloud_Sr305_320x240_Bilateral(benchmark::State& state) {
  static const Clip clip = sr305Clip(true);
  runPipeline(state, clip, withBilateral());
}

BENCHMARK(BM_Cloud_Synthetic640x480)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Cloud_Synthetic320x240_GrowStep2)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Cloud_Sr305_320x240_GrowStep2)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Cloud_Synthetic320x240)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Cloud_Sr305_640x480)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Cloud_Sr305_320x240)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Cloud_Sr305_640x480_Bilateral)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Cloud_Sr305_320x240_Bilateral)->Unit(benchmark::kMicrosecond);

// Stages alone, on the sr305 frames' voxel input.
void BM_VoxelGrid_Sr305Hand(benchmark::State& state) {
  static const Clip clip = sr305Clip(false);
  if (clip.frames.empty()) {
    state.SkipWithError("no frames");
    return;
  }
  CloudPipeline pipeline(clip.k);
  CloudFrame out;
  if (!pipeline.process(clip.frames[0], out).ok()) state.SkipWithError("bad frame");
  std::vector<Vec3> pixels;  // the segmented pixels as points
  for (int v = 0; v < clip.k.height; ++v) {
    for (int u = 0; u < clip.k.width; ++u) {
      if (out.mask[static_cast<std::size_t>(v) * clip.k.width + u]) {
        pixels.push_back(
            clip.k.deproject(static_cast<float>(u), static_cast<float>(v), out.depthAt(u, v)));
      }
    }
  }
  VoxelGrid grid(0.005f, 16384);
  for (auto _ : state) {
    grid.clear();
    for (const Vec3& p : pixels) grid.add(p);
    benchmark::DoNotOptimize(grid.voxelCount());
  }
  state.counters["pixels"] = static_cast<double>(pixels.size());
  state.counters["voxels"] = grid.voxelCount();
}
BENCHMARK(BM_VoxelGrid_Sr305Hand)->Unit(benchmark::kMicrosecond);

void BM_HandSplit_TwoBlobs(benchmark::State& state) {
  std::vector<Vec3> points;
  for (int i = 0; i < 1000; ++i) {
    const float t = static_cast<float>(i) * 0.618034f;
    const float side = i % 2 ? 0.15f : -0.15f;
    points.emplace_back(side + 0.04f * std::sin(t * 7.0f), 0.04f * std::cos(t * 3.0f),
                        0.5f + 0.02f * std::sin(t));
  }
  HandSplitter splitter;
  HandSplit split;
  for (auto _ : state) {
    splitter.split(points, split);
    benchmark::DoNotOptimize(split.handCount);
  }
}
BENCHMARK(BM_HandSplit_TwoBlobs)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace dynahand
