// Tracker speed: per-frame time of Tracker::track (cloud pipeline, the learned detector when
// its weights are found, every simulation, the error metric) on synthetic clips, one core.
// Target: p50 <= 3 ms at 320x240 with the detector. Each benchmark iteration is one frame;
// p50/p99 come from the per-frame times of all iterations. DYNAHAND_BENCH_SET="NAME=VALUE
// [NAME=VALUE ...]" sets tracker settings by name (as `dynahand track --set`), so that a
// setting's cost is timed in alternation with the same binary (scripts/bench_ab.sh).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "dynahand/model.h"
#include "dynahand/synth.h"
#include "dynahand/tracker.h"

namespace dynahand::track {
namespace {

double percentileMs(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const auto i = static_cast<std::size_t>(q * static_cast<double>(v.size() - 1) + 0.5);
  return v[std::min(i, v.size() - 1)];
}

void BM_TrackFrame(benchmark::State& state, const std::string& clip, const std::string& profile,
                   bool allStrategies, bool detector = true) {
  synth::SynthOptions o;
  o.clip = clip;
  o.profile = profile;
  o.frameCount = 60;
  Result<synth::SyntheticSequence> seq = synth::SyntheticSequence::create(o);
  if (!seq) {
    state.SkipWithError(seq.error().message.c_str());
    return;
  }
  TrackerSettings settings;
  if (!allStrategies) settings.strategies = {true, false, false, false, false, false};
  settings.detector.enabled = detector && allStrategies;
  if (const char* assignments = std::getenv("DYNAHAND_BENCH_SET")) {
    std::istringstream words(assignments);
    for (std::string assignment; words >> assignment;)
      if (const Status set = setTrackerSetting(settings, assignment); !set.ok()) {
        state.SkipWithError(("DYNAHAND_BENCH_SET: " + set.message()).c_str());
        return;
      }
  }
  auto tracker = Tracker::create(seq->model(0), seq->intrinsics(), settings);
  if (!tracker) {
    state.SkipWithError(tracker.error().message.c_str());
    return;
  }
  std::vector<DepthFrame> frames;
  for (int i = 0; i < o.frameCount; ++i) frames.push_back(seq->frame(i).depth);
  const model::ModelPose start = seq->frame(0).hands[0].pose;
  std::vector<double> ms;
  std::size_t i = 0;
  int points = 0;
  for (auto _ : state) {
    if (i == 0) {
      state.PauseTiming();
      (*tracker)->reset();
      (*tracker)->initialize(start);
      state.ResumeTiming();
    }
    const auto t0 = std::chrono::steady_clock::now();
    const TrackResult& r = (*tracker)->track(frames[i]);
    ms.push_back(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    if (!r.hands.empty()) points += r.hands[0].pointCount;
    benchmark::DoNotOptimize(r);
    i = (i + 1) % frames.size();
  }
  state.counters["p50_ms"] = percentileMs(ms, 0.5);
  state.counters["p99_ms"] = percentileMs(ms, 0.99);
  state.counters["points"] =
      static_cast<double>(points) / static_cast<double>(std::max<std::size_t>(ms.size(), 1));
  state.counters["frames/s"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}

BENCHMARK_CAPTURE(BM_TrackFrame, wave_tof_320x240, "wave", "tof", true)
    ->Unit(benchmark::kMillisecond)
    ->MinTime(2.0);
BENCHMARK_CAPTURE(BM_TrackFrame, count_tof_320x240, "count", "tof", true)
    ->Unit(benchmark::kMillisecond)
    ->MinTime(2.0);
BENCHMARK_CAPTURE(BM_TrackFrame, wave_sl_640x480, "wave", "structured-light", true)
    ->Unit(benchmark::kMillisecond)
    ->MinTime(2.0);
BENCHMARK_CAPTURE(BM_TrackFrame, wave_tof_320x240_no_detector, "wave", "tof", true, false)
    ->Unit(benchmark::kMillisecond)
    ->MinTime(2.0);
BENCHMARK_CAPTURE(BM_TrackFrame, wave_tof_320x240_normal_only, "wave", "tof", false)
    ->Unit(benchmark::kMillisecond)
    ->MinTime(2.0);

}  // namespace
}  // namespace dynahand::track
