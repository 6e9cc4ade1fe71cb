// dynahand bench: the motion suite and the standard accuracy and speed suite
// (src/tools/include/dynahand/tools/bench_suite.h), printed as tables and written as Markdown
// (docs/benchmarks.md by default for `--suite all`); and the soak (soak.h): track or serve
// for a given time, resident memory and frame time at the start and the end.
#include <sys/utsname.h>

#include <chrono>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <thread>

#include <fmt/format.h>

#include "dynahand/atomic_file.h"
#include "dynahand/command.h"
#include "dynahand/progress.h"
#include "dynahand/tools/bench_suite.h"
#include "soak.h"

namespace dynahand::cli {
namespace {

struct BenchOptions {
  std::string markdown;  // default: docs/benchmarks.md for --suite all, none otherwise
  bool markdownGiven = false;
  std::string suite = "all";
  std::string data;  // default: ../shared/data from the working folder or the source tree
  int threads = 1, frames = 0;
  bool quick = false;
  bool noDetector = false;             // every item without the learned detector (an ablation)
  float keypointsFromTruthMm = -1.0f;  // >= 0: ground-truth keypoints with this noise, mm
  std::string trueShape;               // empty: the default hand; else which factors it takes
  std::string handSize = "given";      // or "auto": each item's hand estimated
  bool handSizeOnly = false;           // with auto: the size alone
  std::string rows;                    // only the items whose row label contains this (empty: all)
  bool items = false;                  // one line per item after each table
  std::vector<std::string> set;        // --set NAME=VALUE: every item's tracker settings
  std::vector<std::string> disable;    // --disable SIMULATION...: off on every item
  // --suite soak
  double minutes = 0.0;   // default: 60 (track), 15 (--serve)
  std::string soakInput;  // default: soak.h's
  bool serve = false, paced = false;
};

// ../shared/data beside the working folder, else beside the source tree this was built from.
std::filesystem::path defaultDataDir() {
  std::error_code ec;
  const std::filesystem::path here = std::filesystem::path("..") / "shared" / "data";
  if (std::filesystem::is_directory(here, ec)) return here;
  const std::filesystem::path source =
      std::filesystem::path(__FILE__).parent_path().parent_path().parent_path();
  const std::filesystem::path beside = source.parent_path() / "shared" / "data";
  if (std::filesystem::is_directory(beside, ec)) return beside;
  return {};
}

constexpr const char* kMotionIntro =
    "The motion suite (`dynahand bench --suite motion`; "
    "src/tools/include/dynahand/tools/bench_suite.h): the "
    "headline numbers. Items: every continuous segment of the original authors' "
    "`animbank.pose` (split where the wrist keypoint moves more than 4 cm or any keypoint more "
    "than 5.5 cm between frames: 12 cuts; of the 14 the data's README lists, 194 and 1769 move "
    "no keypoint more than 3.5 cm, less than ordinary fast motion, and stay inside their "
    "segments; each segment tracked from its own first frame) and every "
    "built-in one-hand clip at 2.5x speed (90 frames, 3 s), on all four sensor profiles "
    "(animbank on the desk camera is in the file's own placement, 0.18-0.55 m away, mostly "
    "nearer than structured light's 0.5 m minimum range: left out there); each on the desk camera "
    "(palm toward it; animbank in its own camera "
    "placement) and the head-mounted camera (back of the hand toward it; animbank re-placed "
    "rigidly), initialised from the first frame's ground truth (`gt`) or acquired "
    "automatically (`auto`). The rendered hands are shaped unlike the tracker's model (medium "
    "size; every bone length, finger and palm thickness factor uniform in [0.85, 1.15], one "
    "draw per clip or segment), so the error includes the model's misfit. Frames to acquire "
    "(`auto` rows): the first frame whose every joint is within 30 mm, mean / max over the "
    "items that got there, how many never did, and the share of all items that did within 5 "
    "frames. The continuous rows "
    "play the whole animbank through its cuts (`tof`, `gt` start): frames to re-acquire is the "
    "median over cuts of the frames from a cut until every joint is within 30 mm again "
    "(never: not before the next cut). Errors are 21-keypoint 3D errors against ground truth; a "
    "frame where the hand is lost counts as a failure in the <= 30 mm column. The held-object "
    "rows (`tof`, `gt` start) put an object against the palm (docs/synth.md, `--object`): "
    "`grasp-cylinder` and `reach-grasp-lift` at 2.5x with a ball, a cylinder and a box each, and "
    "every animbank segment with one of the three in turn; their errors count only the joints "
    "the object does not hide (whose pixel does not show the object). The table rows (`tof`, "
    "`gt` start) play every animbank segment above a table 8 cm below the rest wrist position, "
    "lowered where the segment's captured motion would take the hand into it until no joint "
    "comes within 1.5 cm of it (`dynahand synth --table --table-drop 0.08 --table-below-hand`); "
    "joints it hides (a table pixel in front of them) are not scored. The image-border rows "
    "(`tof`, `gt` start) play every clip at 2.5x with the scene moved in the image "
    "(`dynahand synth --view-shift`) so that the palm's centre lies about 30 pixels from the top, "
    "the left or the right border (the clips take these in turn): the fingers or one side of "
    "the hand go on out of view; joints outside the image are not scored. The detector alone is "
    "the learned detector's own keypoints (no physics) against the same truth, over the frames "
    "it ran on (their share in brackets when not all), as the tracker ran it: what the physics "
    "adds is the difference to the mean error. The model misfit is the tracker's model fitted "
    "to each frame's true keypoints under its joint limits: the rendered hand is shaped unlike "
    "the model, so no pose of the model reaches its keypoints, and this error of a perfect fit "
    "is the floor under the mean error. Times are the tracker's wall time per frame on one "
    "thread (synthesis not included).";

constexpr const char* kStandardIntro =
    "The standard suite (`dynahand bench --suite standard`), kept as regression rows: every "
    "default clip x sensor profile x hand size at normal speed on the desk camera, the "
    "rendered hand shaped like the model, initialised from the first frame's ground truth "
    "(`gt`) or acquired automatically (`auto`), synthetic input with fixed seeds; then "
    "ablations on `tof`, medium hand, `gt` (each simulation off in turn, and normal only), on "
    "the default clips and, in the per-clip table only, on clips the strategies target "
    "(fast-translation, finger-flips, grasp-cylinder). Frames to acquire: the first frame "
    "whose maximum joint error is <= 30 mm (mean / max, and the share of items within 5 "
    "frames). Times are the tracker's wall time per frame on one "
    "thread (synthesis not included); frames/s = frames over the summed wall time; CPU ms is "
    "that thread's CPU time in the tracker, which a loaded machine inflates much less than "
    "wall time.";

std::string cpuModel() {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("model name", 0) == 0) {
      const auto colon = line.find(':');
      if (colon != std::string::npos) return line.substr(colon + 2);
    }
  }
  return "unknown CPU";
}

std::string machineLine() {
  utsname u{};
  uname(&u);
  double load[3] = {0, 0, 0};
  std::ifstream("/proc/loadavg") >> load[0] >> load[1] >> load[2];
  char text[512];
  std::snprintf(text, sizeof text, "%s, %u hardware threads, %s %s; load average %.2f %.2f %.2f",
                cpuModel().c_str(), std::thread::hardware_concurrency(), u.sysname, u.release,
                load[0], load[1], load[2]);
  return text;
}

struct SuiteRun {
  std::vector<eval::SuiteItemResult> results;
  int totalFrames = 0;
  double wallS = 0;
};

// Runs items with a progress line; false when interrupted or failed (message printed).
Result<SuiteRun> runItems(const char* name, const std::vector<eval::SuiteItem>& items,
                          int threads) {
  SuiteRun run;
  for (const auto& item : items) run.totalFrames += item.frames;
  std::printf("bench %s: %zu items, %d frames, %d thread(s)%s\n", name, items.size(),
              run.totalFrames, threads,
              threads > 1 ? " (per-frame times stay single-core per item)" : "");
  Progress progress(name, static_cast<int>(items.size()), "items");
  std::atomic<bool> stop{false};
  const auto start = std::chrono::steady_clock::now();
  auto results = eval::runSuite(
      items, threads,
      [&](int done, int) {
        progress.update(done);
        if (interrupted()) stop = true;
      },
      &stop);
  progress.finish(interrupted() ? "(interrupted: the table covers the items finished)" : "");
  if (!results) return results.error();
  run.wallS = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  run.results = std::move(*results);
  return run;
}

// --items: one line per item (its row, clip, mean / p95 error, share within 30 mm, the
// detector alone's and the model misfit's mean error), to see which clips or segments a row's
// figures come from.
void printItems(const SuiteRun& run) {
  std::printf("\n%-48s %-28s %8s %8s %7s %11s %9s\n", "row", "item", "mean mm", "p95 mm", "<=30mm",
              "detector mm", "misfit mm");
  for (const eval::SuiteItemResult& r : run.results) {
    const eval::KeypointMetrics& m = r.metrics;
    const double within =
        m.successFraction.size() > 2 ? 100.0 * m.successFraction[2] : 0.0;  // 30 mm
    std::printf("%-48s %-28s %8.1f %8.1f %6.1f%% %11.1f %9.1f\n", eval::rowLabel(r.item).c_str(),
                r.item.clip.c_str(), m.meanMm, m.p95Mm, within, r.detectorMeanMm, r.misfitMm);
  }
}

std::string runLine(const SuiteRun& run, int threads) {
  return fmt::format(
      "Items: {}, frames: {}, wall time {} s on {} thread(s){}", run.results.size(),
      run.totalFrames, static_cast<int>(run.wallS + 0.5), threads,
      threads > 1 ? " (items run in parallel; each item's frames on one thread)" : "");
}

// --true-shape's parts by name.
const std::map<std::string, eval::TrueShape> kTrueShapeParts = {
    {"all", eval::TrueShape::All},
    {"metacarpals", eval::TrueShape::Metacarpals},
    {"phalanges", eval::TrueShape::Phalanges},
    {"thickness", eval::TrueShape::Thickness}};

// The items as the options ask: those of the rows --rows names, without the learned detector
// when --no-detector.
std::vector<eval::SuiteItem> asAsked(std::vector<eval::SuiteItem> items, const BenchOptions& o) {
  if (!o.rows.empty()) {
    std::erase_if(items, [&](const eval::SuiteItem& item) {
      return eval::rowLabel(item).find(o.rows) == std::string::npos;
    });
    if (items.empty())
      throw std::runtime_error("--rows '" + o.rows + "': no row has that in its name");
  }
  if (o.noDetector)
    for (eval::SuiteItem& item : items) item.tracker.detector.enabled = false;
  for (eval::SuiteItem& item : items) applyTrackerSettings(o.set, item.tracker);
  for (eval::SuiteItem& item : items) disableSimulations(o.disable, item.tracker);
  if (o.keypointsFromTruthMm >= 0.0f)
    for (eval::SuiteItem& item : items) item.truthKeypointsNoiseM = 0.001f * o.keypointsFromTruthMm;
  if (!o.trueShape.empty())
    for (eval::SuiteItem& item : items) item.trueShape = kTrueShapeParts.at(o.trueShape);
  if (o.handSize == "auto") {
    if (!o.trueShape.empty()) throw UsageError("--hand-size auto does not go with --true-shape");
    for (eval::SuiteItem& item : items)
      item.handEstimate =
          o.handSizeOnly ? eval::HandEstimate::Size : eval::HandEstimate::Metacarpals;
  } else if (o.handSizeOnly) {
    throw UsageError("--hand-size-only goes with --hand-size auto");
  }
  return items;
}

// --suite soak: one soak run, its table, and the Markdown when --markdown is given.
int runSoakBench(const BenchOptions& o, const std::string& commandLine) {
  soak::SoakOptions options;
  options.seconds = 60.0 * (o.minutes > 0.0 ? o.minutes : o.serve ? 15.0 : 60.0);
  options.input = o.soakInput;
  if (o.frames > 0) options.clipFrames = o.frames;
  options.serve = o.serve;
  options.paced = o.paced;
  options.detector = !o.noDetector;
  options.stop = [] { return interrupted(); };
  const std::string machine = machineLine();
  installInterruptHandler();
  Result<soak::SoakReport> report = soak::runSoak(options);
  if (!report) {
    if (report.message().rfind("--soak-input", 0) == 0) throw UsageError(report.message());
    throw std::runtime_error(report.message());
  }
  std::printf("\n%s", soak::soakText(*report).c_str());
  if (!o.markdown.empty()) {
    std::ostringstream md;
    md << "# Soak benchmark\n\n"
       << "- Command: `" << commandLine << "`\n"
       << "- Machine: " << machine << " (at the start)\n\n"
       << soak::soakMarkdown(*report);
    const Status written = writeFileAtomically(o.markdown, md.str());  // whole or untouched
    if (!written) throw std::runtime_error(written.message());
    std::printf("wrote %s\n", o.markdown.c_str());
  }
  if (interrupted()) return 130;
  return report->pass() ? kExitOk : kExitFailure;
}

int runBench(const BenchOptions& o, const std::string& commandLine) {
  const bool soakOptions = o.minutes > 0.0 || !o.soakInput.empty() || o.serve || o.paced;
  if (o.suite != "soak" && soakOptions)
    throw UsageError("--minutes, --soak-input, --serve and --paced go with --suite soak");
  if (o.paced && !o.serve) throw UsageError("--paced goes with --serve");
  if (o.suite == "soak" && (!o.set.empty() || !o.disable.empty()))
    throw UsageError("--set and --disable go with --suite motion, standard or all");
  if (o.suite == "soak") return runSoakBench(o, commandLine);
  const bool motion = o.suite != "standard", standard = o.suite != "motion";
  const std::string machineBefore = machineLine();
  installInterruptHandler();
  std::ostringstream md;
  md << "# Benchmarks\n\n"
     << "- Command: `" << commandLine << "`\n"
     << "- Machine: " << machineBefore << " (at the start)\n";
  std::string body;

  if (motion) {
    eval::MotionSuiteOptions options;
    options.quick = o.quick;
    options.frames = o.frames;
    options.data = o.data.empty() ? defaultDataDir() : std::filesystem::path(o.data);
    Result<eval::MotionSuite> suite = eval::motionSuite(options);
    if (!suite) throw std::runtime_error(suite.message());
    if (!suite->skipped.empty()) std::printf("bench motion: %s\n", suite->skipped.c_str());
    Result<SuiteRun> run = runItems("motion", asAsked(suite->items, o), o.threads);
    if (!run) throw std::runtime_error(run.message());
    const auto rows = eval::summarizeSuite(run->results);
    std::printf("\n%s", eval::motionTableText(rows).c_str());
    if (o.items) printItems(*run);
    std::printf("\n%zu items in %.0f s wall time on %d thread(s)\n\n", run->results.size(),
                run->wallS, o.threads);
    body += "## Motion suite\n\n" + std::string(kMotionIntro) + "\n\n- " + runLine(*run, o.threads);
    if (suite->animbankPoses > 0)
      body += fmt::format("; animbank: {} poses, {} segments", suite->animbankPoses,
                          suite->animbankSegments);
    if (!suite->skipped.empty()) body += "; " + suite->skipped;
    body += "\n\n" + eval::motionTableMarkdown(rows) + "\n";
  }
  if (standard && !interrupted()) {
    eval::SuiteOptions options;
    options.quick = o.quick;
    options.frames = o.frames;
    Result<SuiteRun> run =
        runItems("standard", asAsked(eval::standardSuite(options), o), o.threads);
    if (!run) throw std::runtime_error(run.message());
    const auto rows = eval::summarizeSuite(run->results);
    std::printf("\n%s", eval::suiteTableText(rows).c_str());
    if (o.items) printItems(*run);
    std::printf("\n%zu items in %.0f s wall time on %d thread(s)\n", run->results.size(),
                run->wallS, o.threads);
    body += "## Standard suite (regression rows)\n\n" + std::string(kStandardIntro) + "\n\n- " +
            runLine(*run, o.threads) + "\n\n" + eval::suiteTableMarkdown(rows) + "\n" +
            "### Ablations by clip\n\nMean error in mm (frames with max joint error <= 30 mm) "
            "on `tof`, medium hand, `gt` start.\n\n" +
            eval::ablationByClipMarkdown(run->results);
  }

  const std::string markdown =
      o.markdownGiven ? o.markdown : (o.suite == "all" ? "docs/benchmarks.md" : "");
  if (!markdown.empty()) {
    md << "\n" << body;
    const Status written = writeFileAtomically(markdown, md.str());  // whole or untouched
    if (!written) throw std::runtime_error(written.message());
    std::printf("wrote %s\n", markdown.c_str());
  }
  return interrupted() ? 130 : kExitOk;
}

const CommandRegistration kBenchCommand{Command{
    "bench",
    "run the motion and standard accuracy and speed suites (docs/benchmarks.md), or a soak",
    [](CLI::App& sub) -> std::function<int()> {
      auto o = std::make_shared<BenchOptions>();
      sub.add_option("--suite", o->suite,
                     "motion (the headline: animbank segments and clips at 2.5x, desk and head "
                     "cameras, varied hand proportions), standard (regression rows and "
                     "ablations), all (both; writes docs/benchmarks.md), or soak (track, or "
                     "--serve, for --minutes; resident memory and frame time at the start and "
                     "the end)")
          ->capture_default_str()
          ->check(CLI::IsMember({"motion", "standard", "all", "soak"}));
      sub.add_option("--data", o->data,
                     "folder with intel/animbank.pose (default ../shared/data from the working "
                     "folder or the source tree; absent: the animbank rows are skipped)");
      sub.add_flag("--quick", o->quick,
                   "a few short items (CI): 2 clips, 1-2 profiles, 8 frames; 2 animbank "
                   "segments and the first cut");
      sub.add_option("--frames", o->frames,
                     "frames per clip item (default: standard 150, motion 90; quick 8; soak: "
                     "frames per synthetic clip, 300)")
          ->check(CLI::Range(2, 100000));
      sub.add_option("--threads", o->threads,
                     "items run in parallel (each item on one thread: per-frame times stay "
                     "single-core while threads <= idle cores)")
          ->check(CLI::Range(1, 64));
      sub.add_flag("--no-detector", o->noDetector,
                   "every item without the learned detector (the paper's simulations only)");
      sub.add_option("--keypoints-from-truth", o->keypointsFromTruthMm,
                     "every item given the ground-truth keypoints plus Gaussian noise of this "
                     "standard deviation per axis (mm) instead of the learned detector's: what "
                     "a perfect (0) or a given-noise detector would give (the error is the "
                     "tracked skeleton's, not the report's blend toward the given keypoints)")
          ->check(CLI::Range(0.0f, 100.0f));
      sub.add_option("--true-shape", o->trueShape,
                     "every item tracked with the default hand shaped like the rendered hand: "
                     "all its bone length and thickness factors, the metacarpals (where the "
                     "knuckles and the thumb base sit), the phalanges, or the thicknesses "
                     "alone; what a model fitted to the user's hand would give")
          ->check(CLI::IsMember(kTrueShapeParts));
      sub.add_option("--hand-size", o->handSize,
                     "given (the default hand at the rendered hand's size) or auto: each item "
                     "tracked with the hand `dynahand track --hand-size auto` estimates from its "
                     "first 30 frames (size and metacarpals)")
          ->check(CLI::IsMember({"given", "auto"}));
      sub.add_flag("--hand-size-only", o->handSizeOnly,
                   "with --hand-size auto: the size alone, the default proportions");
      sub.add_option("--rows", o->rows,
                     "only the items of the rows whose name contains TEXT (e.g. 'held objects', "
                     "'tof / head'); with --suite all, each suite must have such rows");
      sub.add_flag("--items", o->items,
                   "after each table, one line per item: its row, clip or segment, mean and "
                   "p95 error and share of frames with every joint within 30 mm");
      addTrackerSettingOption(sub, o->set);
      sub.add_option("--disable", o->disable,
                     "simulations to switch off on every item: normal, gross_motion, grasp_bias, "
                     "finger_flip, feature_detection, detector_fit");
      sub.add_option("--minutes", o->minutes,
                     "soak: how long (default 60; 15 with --serve; fractions allowed)")
          ->check(CLI::Range(0.01, 10000.0));
      sub.add_option("--soak-input", o->soakInput,
                     "soak: synth:CLIP[,CLIP...] (rendered on the fly at tof, played in turn; "
                     "default synth:wave,open-close,pinch) or a recording, looped; with --serve "
                     "one input as dynahand serve takes it (default synth:wave)");
      sub.add_flag("--serve", o->serve,
                   "soak: through dynahand serve's session and server with one WebSocket client "
                   "reading every message");
      sub.add_flag("--paced", o->paced,
                   "soak --serve: at the input's frame rate (default: as fast as it goes, as "
                   "serve --fast)");
      sub.add_option("--markdown", o->markdown,
                     "Markdown report ('' to skip; default docs/benchmarks.md for --suite all, "
                     "none for one suite)")
          ->each([o](const std::string&) { o->markdownGiven = true; });
      sub.footer(
          "Examples:\n"
          "  dynahand bench --threads 2                      # both suites, docs/benchmarks.md\n"
          "  dynahand bench --suite motion --threads 2       # the motion suite, table only\n"
          "  dynahand bench --suite motion --data ../shared/data --markdown /tmp/motion.md\n"
          "  dynahand bench --suite motion --threads 2 --no-detector   # without the detector\n"
          "  dynahand bench --suite motion --rows 'held objects' --threads 2\n"
          "  dynahand bench --suite motion --rows 'tof / ' --set detector.selectionWeight=0\n"
          "  dynahand bench --quick --markdown /tmp/bench.md\n"
          "  dynahand bench --suite soak --minutes 60 --markdown /tmp/soak-track.md\n"
          "  dynahand bench --suite soak --serve --minutes 15 --markdown /tmp/soak-serve.md");
      return [o] {
        std::string line = "dynahand bench";
        if (o->suite != "all") line += " --suite " + o->suite;
        if (o->quick) line += " --quick";
        if (o->frames > 0) line += " --frames " + std::to_string(o->frames);
        if (o->threads > 1) line += " --threads " + std::to_string(o->threads);
        if (o->noDetector) line += " --no-detector";
        if (o->keypointsFromTruthMm >= 0.0f)
          line += fmt::format(" --keypoints-from-truth {}", o->keypointsFromTruthMm);
        if (!o->trueShape.empty()) line += " --true-shape " + o->trueShape;
        if (o->handSize == "auto") line += " --hand-size auto";
        if (o->handSizeOnly) line += " --hand-size-only";
        if (!o->rows.empty()) line += " --rows '" + o->rows + "'";
        if (o->items) line += " --items";
        for (const std::string& a : o->set) line += " --set " + a;
        for (const std::string& d : o->disable) line += " --disable " + d;
        if (o->minutes > 0.0) line += fmt::format(" --minutes {}", o->minutes);
        if (!o->soakInput.empty()) line += " --soak-input " + o->soakInput;
        if (o->serve) line += " --serve";
        if (o->paced) line += " --paced";
        return runBench(*o, line);
      };
    }}};

}  // namespace
}  // namespace dynahand::cli
