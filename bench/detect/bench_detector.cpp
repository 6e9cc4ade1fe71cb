// The learned detector's cost on one core: the crop from a processed cloud frame, and the
// network (OpenCV DNN, one thread) on a crop. Target: crop + network <= 1 ms.
#include <benchmark/benchmark.h>

#include "dynahand/detector.h"
#include "dynahand/synth.h"

namespace dynahand::detect {
namespace {

synth::SynthOptions waveOptions(int frames) {
  synth::SynthOptions o;
  o.clip = "wave";
  o.profile = "tof";
  o.frameCount = frames;
  return o;
}

struct Fixture {
  CloudFrame cloud;
  HandCrop crop;
  Intrinsics intrinsics;
  bool ok = false;
  std::string error;
  Fixture() {
    auto seq = synth::SyntheticSequence::create(waveOptions(3));
    if (!seq) {
      error = seq.message();
      return;
    }
    intrinsics = seq->intrinsics();
    CloudPipeline pipeline(intrinsics);
    ok = pipeline.process(seq->frame(1).depth, cloud).ok() && makeCrop(cloud, false, crop);
    if (!ok) error = "no hand segmented";
  }
};

void BM_Crop(benchmark::State& state) {
  Fixture f;
  if (!f.ok) return state.SkipWithError(f.error.c_str());
  for (auto _ : state) {
    makeCrop(f.cloud, false, f.crop);
    benchmark::DoNotOptimize(f.crop.pixels.data());
  }
}
BENCHMARK(BM_Crop)->Unit(benchmark::kMicrosecond);

void BM_Network(benchmark::State& state) {
  Fixture f;
  if (!f.ok) return state.SkipWithError(f.error.c_str());
  const auto file = defaultDetectorFile();
  if (file.empty()) return state.SkipWithError("no detector weights (models/detector)");
  auto detector = KeypointDetector::load(file);
  if (!detector) return state.SkipWithError(detector.message().c_str());
  for (auto _ : state) {
    const DetectedKeypoints& d = (*detector)->detect(f.crop, f.intrinsics);
    benchmark::DoNotOptimize(d.points.data());
  }
}
BENCHMARK(BM_Network)->Unit(benchmark::kMicrosecond)->MinTime(1.0);

}  // namespace
}  // namespace dynahand::detect
