// Synthetic sensor speed: the analytic renderer alone (the >= 500 frames/s at 320x240 target),
// each sensor profile's degradation, and whole frames (kinematics + render + sensor).
#include <benchmark/benchmark.h>

#include <vector>

#include "dynahand/synth.h"

namespace dynahand::synth {
namespace {

// 60 hand surfaces along the "count" clip through the tof camera, plus its background.
struct RenderScene {
  std::vector<std::vector<RoundCone>> surfaces;
  SensorProfile profile;
  explicit RenderScene(const std::string& profileName) {
    SynthOptions o;
    o.clip = "count";
    o.profile = profileName;
    o.frameCount = 60;
    o.framesPerSecond = 12.0f;  // 60 frames span the 5 s clip
    Result<SyntheticSequence> seq = SyntheticSequence::create(o);
    profile = seq->profile();
    for (int f = 0; f < o.frameCount; ++f) {
      const HandTruth truth = seq->truth(f, 0);
      HandSkeleton skeleton;
      skeleton.keypoints = truth.keypoints;
      skeleton.elbow = truth.pose.bodies[0].transform(Vec3(0.0f, 0.0f, -0.27f));
      surfaces.emplace_back();
      buildHandSurface(skeleton, SurfaceRadii{}, surfaces.back());
    }
  }
};

void BM_RenderHand(benchmark::State& state, bool wall) {
  const RenderScene scene("tof");
  DepthRenderer renderer(scene.profile.intrinsics);
  const Plane plane{Vec3::UnitZ(), 0.8f};
  if (wall) renderer.setBackground(std::span(&plane, 1), {});
  std::size_t i = 0;
  for (auto _ : state) {
    renderer.clear();
    renderer.draw(scene.surfaces[i], PixelLabel::Hand0);
    benchmark::DoNotOptimize(renderer.depth().data());
    i = (i + 1) % scene.surfaces.size();
  }
  state.counters["frames/s"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK_CAPTURE(BM_RenderHand, 320x240, false)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_RenderHand, 320x240_wall, true)->Unit(benchmark::kMicrosecond);

void BM_Sensor(benchmark::State& state, const std::string& profileName) {
  const RenderScene scene(profileName);
  DepthRenderer renderer(scene.profile.intrinsics);
  const Plane plane{Vec3::UnitZ(), 1.0f};
  renderer.setBackground(std::span(&plane, 1), {});
  renderer.draw(scene.surfaces[30], PixelLabel::Hand0);
  SensorSimulator sensor(scene.profile, 1);
  DepthFrame out;
  int frame = 0;
  for (auto _ : state) {
    sensor.apply(renderer.depth(), renderer.labels(), frame++, 0.0, out);
    benchmark::DoNotOptimize(out.depth.data());
  }
  state.counters["frames/s"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK_CAPTURE(BM_Sensor, ideal, std::string("ideal"))->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_Sensor, tof, std::string("tof"))->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_Sensor, structured_light, std::string("structured-light"))
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_Sensor, active_stereo, std::string("active-stereo"))
    ->Unit(benchmark::kMicrosecond);

// A whole frame as SyntheticSequence::frame makes it: clip sample, kinematics, surface,
// render, sensor.
void BM_SyntheticFrame(benchmark::State& state, const std::string& profileName) {
  SynthOptions o;
  o.clip = "count";
  o.profile = profileName;
  o.frameCount = 150;
  o.scene.background = Background::Wall;
  Result<SyntheticSequence> seq = SyntheticSequence::create(o);
  int frame = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(seq->frame(frame).depth.depth.data());
    frame = (frame + 1) % o.frameCount;
  }
  state.counters["frames/s"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK_CAPTURE(BM_SyntheticFrame, tof_wall, std::string("tof"))->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_SyntheticFrame, ideal_wall, std::string("ideal"))
    ->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace dynahand::synth
