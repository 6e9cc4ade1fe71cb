// dynahand demo: synthesise the built-in clips, track them, evaluate against ground
// truth, print a summary table and write a contact sheet of tracked frames. The main
// job behind README's first command; needs no camera and no download.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "dynahand/command.h"
#include "dynahand/metrics.h"
#include "dynahand/progress.h"
#include "dynahand/synth.h"
#include "dynahand/tools/overlay.h"
#include "dynahand/tracker.h"

namespace dynahand::cli {
namespace {

struct DemoOptions {
  std::string out = "out", profile = "tof", init = "gt";
  std::vector<std::string> clips;
  int frames = 90;
  float speed = 1.0f;
};

struct ClipSummary {
  std::string clip;
  eval::KeypointMetrics metrics;
  double p50Ms = 0, p99Ms = 0;
};

int runDemo(const DemoOptions& o) {
  const std::vector<std::string> clips = o.clips.empty() ? synth::defaultClipSet() : o.clips;
  installInterruptHandler();
  std::vector<ClipSummary> summaries;
  std::vector<eval::RgbImage> tiles;
  std::vector<double> allTimes;
  eval::SequenceKeypoints all;
  Progress progress("demo", static_cast<int>(clips.size()) * o.frames);
  int done = 0;
  for (const std::string& clip : clips) {
    synth::SynthOptions so;
    so.clip = clip;
    so.profile = o.profile;
    so.frameCount = o.frames;
    so.speed = o.speed;
    auto seq = synth::SyntheticSequence::create(so);
    if (!seq) throw UsageError(seq.message());
    const auto& hand = seq->model(0);
    auto tracker = track::Tracker::create(hand, seq->intrinsics());
    if (!tracker) throw std::runtime_error(tracker.message());
    eval::SequenceKeypoints keypoints;
    keypoints.fps = so.framesPerSecond;
    std::vector<double> times;
    for (int f = 0; f < o.frames && !interrupted(); ++f) {
      const synth::SyntheticFrame& frame = seq->frame(f);
      if (f == 0 && o.init == "gt") (*tracker)->initialize(frame.hands[0].pose);
      const track::TrackResult& r = (*tracker)->track(frame.depth);
      const auto& h = r.hands[0];
      times.push_back(r.timeMs);
      keypoints.groundTruth.push_back(frame.hands[0].keypoints);
      keypoints.predicted.push_back(h.tracked ? std::optional<Keypoints21>(h.keypoints21)
                                              : std::nullopt);
      // Four tiles per clip: depth, the model (faint), truth (green) and estimate (red).
      if ((f + 1) % std::max(1, o.frames / 4) == 0 && f > 0) {
        const Keypoints21& truth = frame.hands[0].keypoints;
        const float z = truth[9].z();
        eval::RgbImage image = eval::shadeDepth(frame.depth, z - 0.10f, z + 0.15f);
        if (h.tracked)
          eval::drawModel(image, seq->intrinsics(), hand, h.pose, {255, 255, 255}, 0.45f);
        eval::drawSkeleton(image, seq->intrinsics(), truth, {40, 220, 40}, 1);
        if (h.tracked)
          eval::drawSkeleton(image, seq->intrinsics(), h.keypoints21, {230, 30, 30}, 1);
        std::vector<Vec3> box(truth.begin(), truth.end());
        eval::RgbImage tile = eval::cropAround(image, seq->intrinsics(), box, 12, 240, 240);
        char label[96];
        double err = 0;
        for (int k = 0; k < 21; ++k)
          err += static_cast<double>(
              (h.keypoints21[static_cast<std::size_t>(k)] - truth[static_cast<std::size_t>(k)])
                  .norm());
        std::snprintf(label, sizeof label, "%s f%d %.0f mm", clip.c_str(), f, 1000.0 * err / 21.0);
        eval::drawLabel(tile, label);
        tiles.push_back(std::move(tile));
      }
      progress.update(++done, clip);
    }
    auto m = eval::computeKeypointMetrics(keypoints);
    if (!m) throw std::runtime_error(m.message());
    summaries.push_back({clip, *m, eval::percentile(times, 0.5), eval::percentile(times, 0.99)});
    all.groundTruth.insert(all.groundTruth.end(), keypoints.groundTruth.begin(),
                           keypoints.groundTruth.end());
    all.predicted.insert(all.predicted.end(), keypoints.predicted.begin(),
                         keypoints.predicted.end());
    allTimes.insert(allTimes.end(), times.begin(), times.end());
    if (interrupted()) break;
  }
  progress.finish();
  auto total = eval::computeKeypointMetrics(all);
  if (!total) throw std::runtime_error(total.message());
  summaries.push_back(
      {"all", *total, eval::percentile(allTimes, 0.5), eval::percentile(allTimes, 0.99)});

  std::ostringstream table;
  table << "| clip | frames | mean error (mm) | p95 (mm) | frames max joint <= 30 mm | lost | p50 "
           "ms | p99 ms |\n"
        << "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n";
  std::printf("\n%-16s %6s %9s %8s %9s %5s %7s %7s\n", "clip", "frames", "mean mm", "p95 mm",
              "<=30mm", "lost", "p50 ms", "p99 ms");
  for (const auto& s : summaries) {
    const auto& m = s.metrics;
    std::printf("%-16s %6d %9.1f %8.1f %8.1f%% %5d %7.2f %7.2f\n", s.clip.c_str(), m.frames,
                m.meanMm, m.p95Mm, 100.0 * m.successFraction[2], m.lostFrames, s.p50Ms, s.p99Ms);
    char row[256];
    std::snprintf(row, sizeof row, "| %s | %d | %.1f | %.1f | %.1f%% | %d | %.2f | %.2f |\n",
                  s.clip.c_str(), m.frames, m.meanMm, m.p95Mm, 100.0 * m.successFraction[2],
                  m.lostFrames, s.p50Ms, s.p99Ms);
    table << row;
  }
  const std::filesystem::path dir(o.out);
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  const eval::RgbImage sheet = eval::contactSheet(tiles, 4);
  const Status saved = sheet.savePng(dir / "demo.png");
  if (!saved) throw std::runtime_error(saved.message());
  std::ofstream(dir / "demo.md") << "# dynahand demo (" << o.profile << ", init " << o.init << ", "
                                 << o.frames << " frames per clip, speed " << o.speed << ")\n\n"
                                 << table.str();
  std::printf("\nwrote %s (green: ground truth, red: tracked, white: the model) and %s\n",
              (dir / "demo.png").c_str(), (dir / "demo.md").c_str());
  return kExitOk;
}

const CommandRegistration kDemoCommand{Command{
    "demo", "synthesise built-in clips, track and evaluate them, write a contact sheet",
    [](CLI::App& sub) -> std::function<int()> {
      auto o = std::make_shared<DemoOptions>();
      sub.add_option("--out", o->out, "output folder for demo.png and demo.md");
      sub.add_option("--clips", o->clips,
                     "clips to run (default: the built-in set; see 'dynahand synth --list')");
      sub.add_option("--frames", o->frames, "frames per clip")->check(CLI::Range(4, 100000));
      sub.add_option("--profile", o->profile, "sensor profile")
          ->check(CLI::IsMember({"ideal", "tof", "structured-light", "active-stereo"}));
      sub.add_option("--speed", o->speed, "clip speed multiplier")->check(CLI::Range(0.05f, 10.0f));
      sub.add_option("--init", o->init,
                     "gt: start from the first frame's ground truth; auto: acquire")
          ->check(CLI::IsMember({"gt", "auto"}));
      sub.footer(
          "Examples:\n"
          "  dynahand demo\n"
          "  dynahand demo --clips wave pinch --frames 60 --out /tmp/demo\n"
          "  dynahand demo --profile structured-light --init auto");
      return [o] { return runDemo(*o); };
    }}};

}  // namespace
}  // namespace dynahand::cli
