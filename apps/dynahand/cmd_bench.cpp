// dynahand bench: the standard accuracy and speed suite (include/dynahand/bench_suite.h),
// printed as one table and written as Markdown (docs/benchmarks.md by default).
#include <sys/utsname.h>

#include <chrono>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "dynahand/bench_suite.h"
#include "dynahand/command.h"
#include "dynahand/progress.h"

namespace dynahand::cli {
namespace {

struct BenchOptions {
  std::string markdown = "docs/benchmarks.md";
  int threads = 1, frames = 0;
  bool quick = false;
};

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

int runBench(const BenchOptions& o, const std::string& commandLine) {
  eval::SuiteOptions options;
  options.quick = o.quick;
  options.frames = o.frames;
  const std::vector<eval::SuiteItem> items = eval::standardSuite(options);
  int totalFrames = 0;
  for (const auto& item : items) totalFrames += item.frames;
  std::printf("bench: %zu items, %d frames, %d thread(s)%s\n", items.size(), totalFrames, o.threads,
              o.threads > 1 ? " (per-frame times stay single-core per item)" : "");
  const std::string machineBefore = machineLine();
  installInterruptHandler();
  Progress progress("bench", static_cast<int>(items.size()), "items");
  std::atomic<bool> stop{false};
  const auto start = std::chrono::steady_clock::now();
  auto results = eval::runSuite(
      items, o.threads,
      [&](int done, int) {
        progress.update(done);
        if (interrupted()) stop = true;
      },
      &stop);
  progress.finish(interrupted() ? "(interrupted: the table covers the items finished)" : "");
  if (!results) throw std::runtime_error(results.message());
  const double wallS =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const auto rows = eval::summarizeSuite(*results);
  std::printf("\n%s", eval::suiteTableText(rows).c_str());
  std::printf("\n%zu items in %.0f s wall time on %d thread(s)\n", results->size(), wallS,
              o.threads);

  if (!o.markdown.empty()) {
    const std::time_t now = std::time(nullptr);
    char date[64];
    std::strftime(date, sizeof date, "%Y-%m-%d %H:%M UTC", std::gmtime(&now));
    std::ostringstream md;
    md << "# Benchmarks\n\n"
       << "The standard suite of `dynahand bench` (include/dynahand/bench_suite.h): every "
          "built-in clip x sensor profile x hand size, initialised from the first frame's "
          "ground truth (`gt`) or acquired automatically (`auto`), synthetic input with fixed "
          "seeds; then ablations on `tof`, medium hand, `gt` (each simulation off in turn, "
          "and normal only), on the default clips and, in the per-clip table only, on clips "
          "the strategies target (fast-translation, finger-flips, grasp-cylinder). Errors are "
          "21-keypoint 3D errors against ground truth; a frame "
          "where the hand is lost counts as a failure in the <= 30 mm column. Frames to acquire: "
          "the first frame whose maximum joint error is <= 30 mm. Times are the tracker's wall "
          "time per frame on one thread (synthesis not included); frames/s = frames over the "
          "summed wall time; CPU ms is that thread's CPU time in the tracker, which a loaded "
          "machine inflates much less than wall time.\n\n"
       << "- Command: `" << commandLine << "`\n"
       << "- Date: " << date << "\n"
       << "- Machine: " << machineBefore << " (at the start)\n"
       << "- Items: " << results->size() << ", frames: " << totalFrames << ", wall time "
       << static_cast<int>(wallS + 0.5) << " s on " << o.threads << " thread(s)"
       << (o.threads > 1 ? " (items run in parallel; each item's frames on one thread)" : "")
       << "\n\n"
       << eval::suiteTableMarkdown(rows) << "\n"
       << "## Ablations by clip\n\nMean error in mm (frames with max joint error <= 30 mm) "
          "on `tof`, medium hand, `gt` start.\n\n"
       << eval::ablationByClipMarkdown(*results);
    const std::filesystem::path path(o.markdown);
    if (path.has_parent_path()) {
      std::error_code ec;
      std::filesystem::create_directories(path.parent_path(), ec);
    }
    std::ofstream out(path);
    out << md.str();
    if (!out) throw std::runtime_error(o.markdown + ": cannot write");
    std::printf("wrote %s\n", o.markdown.c_str());
  }
  return interrupted() ? 130 : kExitOk;
}

const CommandRegistration kBenchCommand{Command{
    "bench", "run the standard accuracy and speed suite and write docs/benchmarks.md",
    [](CLI::App& sub) -> std::function<int()> {
      auto o = std::make_shared<BenchOptions>();
      sub.add_flag("--quick", o->quick, "a few short items (CI): 2 clips, 2 profiles, 8 frames");
      sub.add_option("--frames", o->frames, "frames per item (default 150; quick 8)")
          ->check(CLI::Range(2, 100000));
      sub.add_option("--threads", o->threads,
                     "items run in parallel (each item on one thread: per-frame times stay "
                     "single-core while threads <= idle cores)")
          ->check(CLI::Range(1, 64));
      sub.add_option("--markdown", o->markdown, "Markdown report ('' to skip)");
      sub.footer(
          "Examples:\n"
          "  dynahand bench --threads 2\n"
          "  dynahand bench --quick --markdown /tmp/bench.md");
      return [o] {
        std::string line = "dynahand bench";
        if (o->quick) line += " --quick";
        if (o->frames > 0) line += " --frames " + std::to_string(o->frames);
        if (o->threads > 1) line += " --threads " + std::to_string(o->threads);
        return runBench(*o, line);
      };
    }}};

}  // namespace
}  // namespace dynahand::cli
