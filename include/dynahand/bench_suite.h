// The standard accuracy and speed suite behind `dynahand bench` (docs/benchmarks.md):
// every built-in motion clip x sensor profile x hand size, with ground-truth first-frame
// initialisation and with automatic acquisition, plus ablations (each simulation strategy
// off in turn, and "normal only"). Synthetic input with fixed seeds, so runs compare.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "dynahand/metrics.h"
#include "dynahand/model.h"
#include "dynahand/tracker.h"

namespace dynahand::eval {

struct HandSize {
  std::string name;  // "small", "medium", "large"
  model::HandDimensions dimensions;
};
const std::vector<HandSize>& benchHandSizes();
// Clips outside the default set that the ablations also run, each for the strategies it
// targets: fast-translation (gross motion; the detector re-acquires), finger-flips (finger
// flip), grasp-cylinder (grasp bias).
const std::vector<std::string>& targetedAblationClips();

struct SuiteItem {
  std::string variant = "all";  // "all", "no <strategy>" or "normal only"
  bool ablation = false;        // part of the ablation block (tof, medium, gt init)
  // An ablation item on a clip a strategy targets beyond the default set
  // (targetedAblationClips(), not synth::defaultClipSet()):
  // in the per-clip ablation table only, not in the summary rows.
  bool targeted = false;
  std::string clip, profile;
  HandSize size;
  bool autoInit = false;  // false: initialised from frame 0's ground truth
  // The tracker's settings (ablations switch strategies off); keepCandidates is ignored.
  track::TrackerSettings tracker;
  int frames = 0;
  float speed = 1.0f;      // clip time multiplier (0.5: half speed)
  std::uint64_t seed = 1;  // sensor noise
};

struct SuiteOptions {
  bool quick = false;  // a few short items, for CI
  int frames = 0;      // frames per item; 0: 60 (quick: 8)
};
std::vector<SuiteItem> standardSuite(const SuiteOptions& options);

inline constexpr double kAcquiredMaxJointMm = 30.0;  // "tracking" for frames-to-acquire

struct SuiteItemResult {
  SuiteItem item;
  SequenceKeypoints keypoints;  // ground truth and prediction per frame
  KeypointMetrics metrics;
  std::vector<double> frameMs;     // tracker wall time per frame (one thread), ms
  std::vector<double> frameCpuMs;  // CPU time of that thread in track(), ms: on a loaded
                                   // machine wall time grows, CPU time much less
  int framesToAcquire = -1;        // first frame with max joint error <= 30 mm; -1: never
};

// Synthesises and tracks one item on the calling thread.
Result<SuiteItemResult> runSuiteItem(const SuiteItem& item);

// Runs items on `threads` worker threads (each item on one thread, so per-frame times are
// single-core times as long as threads <= idle cores). progress(done, total) is called
// from the workers, serialised; `stop` (may be null) ends the run early: results then
// hold the items finished. Results are in item order.
Result<std::vector<SuiteItemResult>> runSuite(const std::vector<SuiteItem>& items, int threads,
                                              const std::function<void(int, int)>& progress,
                                              const std::atomic<bool>* stop = nullptr);

// One table row: items aggregated over clips.
struct SuiteRow {
  std::string label;  // e.g. "tof / medium / gt" or "ablation: no grasp_bias"
  int items = 0, frames = 0;
  double meanMm = 0, p95Mm = 0;
  double success30 = 0;  // fraction of frames with max joint error <= 30 mm
  double p50Ms = 0, p99Ms = 0, framesPerSecond = 0;  // wall time
  double p50CpuMs = 0;
  int autoItems = 0;               // items with automatic acquisition
  double meanFramesToAcquire = 0;  // over auto items that acquired
  int maxFramesToAcquire = -1;
  int neverAcquired = 0;
};
std::vector<SuiteRow> summarizeSuite(const std::vector<SuiteItemResult>& results);

// The table as fixed-width text (terminal) and as Markdown.
std::string suiteTableText(const std::vector<SuiteRow>& rows);
std::string suiteTableMarkdown(const std::vector<SuiteRow>& rows);
// Mean error (mm) per clip for every ablation variant: what each strategy buys where.
std::string ablationByClipMarkdown(const std::vector<SuiteItemResult>& results);

}  // namespace dynahand::eval
