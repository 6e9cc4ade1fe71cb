#include "dynahand/bench_suite.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <mutex>
#include <optional>
#include <thread>

#include <time.h>

#include "dynahand/synth.h"

namespace dynahand::eval {

namespace {

// 5 s at 30 fps: every default clip at least once through (count is 5 s long; at 2 s a clip
// showed only part of its motion and single items swung by several mm between builds). The
// suite still runs in a few minutes on 2 cores.
constexpr int kDefaultFrames = 150;
constexpr int kQuickFrames = 8;

std::string rowLabel(const SuiteItem& item) {
  if (item.ablation) return "ablation: " + item.variant;
  return fmt::format("{} / {} / {}", item.profile, item.size.name, item.autoInit ? "auto" : "gt");
}
// The standard items the ablations are compared with.
bool isAblationBaseline(const SuiteItem& item) {
  return !item.ablation && item.profile == "tof" && item.size.name == "medium" && !item.autoInit;
}

double threadCpuMs() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return 1e3 * static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_nsec);
}

}  // namespace

const std::vector<HandSize>& benchHandSizes() {
  // Adult hands: ~5th, 50th and 95th percentile hand length (wrist crease to middle tip).
  static const std::vector<HandSize> kSizes = {
      {"small", {0.165f, 0.075f}}, {"medium", {0.19f, 0.085f}}, {"large", {0.215f, 0.095f}}};
  return kSizes;
}

const std::vector<std::string>& targetedAblationClips() {
  static const std::vector<std::string> kClips = {"fast-translation", "finger-flips",
                                                  "grasp-cylinder"};
  return kClips;
}

std::vector<SuiteItem> standardSuite(const SuiteOptions& options) {
  const int frames =
      options.frames > 0 ? options.frames : (options.quick ? kQuickFrames : kDefaultFrames);
  std::vector<std::string> clipNames = synth::defaultClipSet();
  std::vector<std::string> profiles;
  for (const auto& p : synth::sensorProfiles()) profiles.push_back(p.name);
  std::vector<HandSize> sizes = benchHandSizes();
  if (options.quick) {
    clipNames = {"pinch", "wave"};
    profiles = {"tof", "structured-light"};
    sizes = {benchHandSizes()[1]};
  }
  std::vector<SuiteItem> items;
  for (std::size_t s = 0; s < sizes.size(); ++s) {
    for (std::size_t p = 0; p < profiles.size(); ++p) {
      for (bool autoInit : {false, true}) {
        for (std::size_t c = 0; c < clipNames.size(); ++c) {
          SuiteItem item;
          item.clip = clipNames[c];
          item.profile = profiles[p];
          item.size = sizes[s];
          item.autoInit = autoInit;
          item.frames = frames;
          item.seed = 1 + c + 10 * p + 100 * s;  // the same noise for a clip in every variant
          items.push_back(item);
        }
      }
    }
  }
  // Ablations on tof, medium hand, ground-truth start: each strategy off in turn, then
  // "normal only". Their baseline is the standard tof / medium / gt row.
  const HandSize medium = benchHandSizes()[1];
  const std::size_t tofIndex = static_cast<std::size_t>(
      std::find(profiles.begin(), profiles.end(), "tof") - profiles.begin());
  // variant -1: all strategies, the baseline for the targeted clips (for the default clips
  // the standard tof / medium / gt items are the baseline).
  for (int variant = -1; variant <= track::kStrategyCount; ++variant) {
    SuiteItem base;
    base.ablation = true;
    base.profile = "tof";
    base.size = medium;
    base.frames = frames;
    if (variant < 0) {
      base.variant = "all";
    } else if (variant < track::kStrategyCount) {
      base.variant =
          std::string("no ") + track::strategyName(static_cast<track::StrategyKind>(variant));
      base.tracker.strategies[static_cast<std::size_t>(variant)] = false;
    } else {
      base.variant = "normal only";
      base.tracker.strategies = {true, false, false, false, false};
    }
    const std::size_t mediumIndex = options.quick ? 0 : 1;
    for (std::size_t c = 0; c < clipNames.size() && variant >= 0; ++c) {
      if (options.quick && c > 0) break;  // one clip is enough to exercise the block
      SuiteItem item = base;
      item.clip = clipNames[c];
      item.seed = 1 + c + 10 * tofIndex + 100 * mediumIndex;
      items.push_back(item);
    }
    if (options.quick) continue;
    const auto& targeted = targetedAblationClips();
    for (std::size_t c = 0; c < targeted.size(); ++c) {
      SuiteItem item = base;
      item.targeted = true;
      item.clip = targeted[c];
      item.seed = 1 + clipNames.size() + c + 10 * tofIndex + 100 * mediumIndex;
      items.push_back(item);
    }
  }
  return items;
}

Result<SuiteItemResult> runSuiteItem(const SuiteItem& item) {
  synth::SynthOptions so;
  so.clip = item.clip;
  so.profile = item.profile;
  so.frameCount = item.frames;
  so.seed = item.seed;
  so.speed = item.speed;
  so.hand = item.size.dimensions;
  auto seq = synth::SyntheticSequence::create(so);
  if (!seq) return Error{seq.message()};
  track::TrackerSettings settings = item.tracker;
  settings.keepCandidates = false;  // no pictures here
  auto tracker = track::Tracker::create(seq->model(0), seq->intrinsics(), settings);
  if (!tracker) return Error{tracker.message()};
  SuiteItemResult result;
  result.item = item;
  result.keypoints.fps = so.framesPerSecond;
  for (int f = 0; f < item.frames; ++f) {
    const synth::SyntheticFrame& frame = seq->frame(f);
    if (f == 0 && !item.autoInit) (*tracker)->initialize(frame.hands[0].pose);
    const double cpuBefore = threadCpuMs();
    const track::TrackResult& r = (*tracker)->track(frame.depth);
    result.frameCpuMs.push_back(threadCpuMs() - cpuBefore);
    const track::HandResult& h = r.hands.front();
    result.frameMs.push_back(r.timeMs);
    result.keypoints.groundTruth.push_back(frame.hands[0].keypoints);
    result.keypoints.predicted.push_back(h.tracked ? std::optional<Keypoints21>(h.keypoints21)
                                                   : std::nullopt);
  }
  auto metrics = computeKeypointMetrics(result.keypoints);
  if (!metrics) return Error{metrics.message()};
  result.metrics = std::move(*metrics);
  for (std::size_t f = 0; f < result.metrics.perFrameMaxMm.size(); ++f) {
    const double maxMm = result.metrics.perFrameMaxMm[f];
    if (!std::isnan(maxMm) && maxMm <= kAcquiredMaxJointMm) {
      result.framesToAcquire = static_cast<int>(f);
      break;
    }
  }
  return result;
}

Result<std::vector<SuiteItemResult>> runSuite(const std::vector<SuiteItem>& items, int threads,
                                              const std::function<void(int, int)>& progress,
                                              const std::atomic<bool>* stop) {
  std::vector<std::optional<SuiteItemResult>> slots(items.size());
  std::atomic<std::size_t> next{0};
  std::mutex mutex;  // guards firstError, done and the progress callback
  std::optional<Error> firstError;
  int done = 0;
  auto worker = [&] {
    for (;;) {
      if (stop != nullptr && stop->load()) return;
      const std::size_t i = next.fetch_add(1);
      if (i >= items.size()) return;
      auto r = runSuiteItem(items[i]);
      std::lock_guard<std::mutex> lock(mutex);
      if (!r) {
        if (!firstError)
          firstError = Error{items[i].clip + " / " + items[i].profile + ": " + r.message()};
        continue;
      }
      slots[i] = std::move(*r);
      ++done;
      if (progress) progress(done, static_cast<int>(items.size()));
    }
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < std::max(1, threads); ++t) pool.emplace_back(worker);
  worker();
  for (auto& t : pool) t.join();
  if (firstError) return *firstError;
  std::vector<SuiteItemResult> results;
  for (auto& s : slots) {
    if (s) results.push_back(std::move(*s));
  }
  return results;
}

std::vector<SuiteRow> summarizeSuite(const std::vector<SuiteItemResult>& results) {
  std::vector<std::string> order;
  std::map<std::string, std::vector<const SuiteItemResult*>> groups;
  auto add = [&](const std::string& label, const SuiteItemResult& r) {
    if (!groups.contains(label)) order.push_back(label);
    groups[label].push_back(&r);
  };
  for (const auto& r : results) {
    if (!r.item.ablation) add(rowLabel(r.item), r);
  }
  for (const auto& r : results) {
    if (isAblationBaseline(r.item)) add("ablation: all (= tof / medium / gt)", r);
  }
  for (const auto& r : results) {
    if (r.item.ablation && !r.item.targeted) add(rowLabel(r.item), r);
  }
  std::vector<SuiteRow> rows;
  for (const std::string& label : order) {
    SuiteRow row;
    row.label = label;
    SequenceKeypoints all;
    std::vector<double> times, cpuTimes;
    double acquireSum = 0;
    int acquired = 0;
    for (const SuiteItemResult* r : groups[label]) {
      ++row.items;
      all.groundTruth.insert(all.groundTruth.end(), r->keypoints.groundTruth.begin(),
                             r->keypoints.groundTruth.end());
      all.predicted.insert(all.predicted.end(), r->keypoints.predicted.begin(),
                           r->keypoints.predicted.end());
      times.insert(times.end(), r->frameMs.begin(), r->frameMs.end());
      cpuTimes.insert(cpuTimes.end(), r->frameCpuMs.begin(), r->frameCpuMs.end());
      if (r->item.autoInit) {
        ++row.autoItems;
        if (r->framesToAcquire < 0) {
          ++row.neverAcquired;
        } else {
          acquireSum += r->framesToAcquire;
          ++acquired;
          row.maxFramesToAcquire = std::max(row.maxFramesToAcquire, r->framesToAcquire);
        }
      }
    }
    row.frames = static_cast<int>(times.size());
    if (auto m = computeKeypointMetrics(all); m) {
      row.meanMm = m->meanMm;
      row.p95Mm = m->p95Mm;
      row.success30 = m->successFraction[2];  // thresholds 10, 20, 30, 40, 50 mm
    }
    row.p50Ms = percentile(times, 0.5);
    row.p99Ms = percentile(times, 0.99);
    row.p50CpuMs = percentile(cpuTimes, 0.5);
    double totalMs = 0;
    for (double t : times) totalMs += t;
    row.framesPerSecond = totalMs > 0 ? 1000.0 * row.frames / totalMs : 0.0;
    row.meanFramesToAcquire = acquired > 0 ? acquireSum / acquired : 0.0;
    rows.push_back(row);
  }
  return rows;
}

namespace {

std::string acquireText(const SuiteRow& r) {
  if (r.autoItems == 0) return "-";
  if (r.autoItems == r.neverAcquired) return fmt::format("never ({})", r.neverAcquired);
  std::string s = fmt::format("{:.1f} / {}", r.meanFramesToAcquire, r.maxFramesToAcquire);
  if (r.neverAcquired > 0) s += fmt::format(", {} never", r.neverAcquired);
  return s;
}

}  // namespace

std::string suiteTableText(const std::vector<SuiteRow>& rows) {
  std::string s =
      fmt::format("{:<40} {:>5} {:>6} {:>8} {:>8} {:>7} {:>16} {:>7} {:>7} {:>7} {:>7}\n",
                  "suite row", "items", "frames", "mean mm", "p95 mm", "<=30mm", "acquire mean/max",
                  "p50 ms", "p99 ms", "CPU p50", "frame/s");
  for (const auto& r : rows) {
    s += fmt::format(
        "{:<40} {:>5} {:>6} {:>8.1f} {:>8.1f} {:>6.1f}% {:>16} {:>7.2f} {:>7.2f} {:>7.2f} "
        "{:>7.1f}\n",
        r.label, r.items, r.frames, r.meanMm, r.p95Mm, 100.0 * r.success30, acquireText(r), r.p50Ms,
        r.p99Ms, r.p50CpuMs, r.framesPerSecond);
  }
  return s;
}

std::string suiteTableMarkdown(const std::vector<SuiteRow>& rows) {
  std::string s =
      "| suite row | items | frames | mean error (mm) | p95 (mm) | frames max joint <= 30 mm | "
      "auto init: frames to acquire (mean / max) | p50 ms | p99 ms | p50 CPU ms | frames/s |\n"
      "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n";
  for (const auto& r : rows) {
    s += fmt::format(
        "| {} | {} | {} | {:.1f} | {:.1f} | {:.1f}% | {} | {:.2f} | {:.2f} | {:.2f} | {:.1f} |\n",
        r.label, r.items, r.frames, r.meanMm, r.p95Mm, 100.0 * r.success30, acquireText(r), r.p50Ms,
        r.p99Ms, r.p50CpuMs, r.framesPerSecond);
  }
  return s;
}

std::string ablationByClipMarkdown(const std::vector<SuiteItemResult>& results) {
  std::vector<std::string> variants, clips;
  std::map<std::pair<std::string, std::string>, const SuiteItemResult*> cell;
  auto note = [&](const std::string& variant, const SuiteItemResult& r) {
    if (std::find(variants.begin(), variants.end(), variant) == variants.end())
      variants.push_back(variant);
    if (std::find(clips.begin(), clips.end(), r.item.clip) == clips.end())
      clips.push_back(r.item.clip);
    cell[{variant, r.item.clip}] = &r;
  };
  for (const auto& r : results) {
    if (isAblationBaseline(r.item)) note("all", r);
  }
  for (const auto& r : results) {
    if (r.item.ablation) note(r.item.variant, r);
  }
  if (variants.empty()) return {};
  std::string s = "| clip |";
  std::string rule = "| --- |";
  for (const auto& v : variants) {
    s += " " + v + " |";
    rule += " ---: |";
  }
  s += "\n" + rule + "\n";
  for (const auto& clip : clips) {
    s += "| " + clip + " |";
    for (const auto& v : variants) {
      const auto it = cell.find({v, clip});
      s += it == cell.end() ? " - |"
                            : fmt::format(" {:.1f} ({:.0f}%) |", it->second->metrics.meanMm,
                                          100.0 * it->second->metrics.successFraction[2]);
    }
    s += '\n';
  }
  return s;
}

}  // namespace dynahand::eval
