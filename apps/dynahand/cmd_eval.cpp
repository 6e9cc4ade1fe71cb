// dynahand eval: accuracy of a tracked sequence against ground truth.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <string>
#include <utility>

#include "dynahand/atomic_file.h"
#include "dynahand/command.h"
#include "dynahand/keypoint_io.h"
#include "dynahand/metrics.h"

namespace dynahand::cli {
namespace {

struct EvalOptions {
  std::string gt, pred, side = "right", out;
  double fps = 30.0;
  double lostMm = 50.0;
};

int runEval(const EvalOptions& o) {
  auto gt = eval::readKeypointsJsonl(o.gt);
  if (!gt) throw UsageError(gt.message());
  auto pred = eval::readKeypointsJsonl(o.pred, o.side);
  if (!pred) throw UsageError(pred.message());
  const auto anyHand = [](const eval::KeypointSequence& k) {
    return std::any_of(k.frames.begin(), k.frames.end(),
                       [](const auto& f) { return f.has_value(); });
  };
  if (!anyHand(*pred)) {
    // No frame of this side: a wrong --side (a mean over 0 frames says nothing) unless the
    // other side is lost throughout too.
    const std::string other = o.side == "right" ? "left" : "right";
    auto otherHand = eval::readKeypointsJsonl(o.pred, other);
    if (otherHand && anyHand(*otherHand)) {
      throw UsageError("--side " + o.side + ": " + o.pred + " has no tracked " + o.side +
                       " hand (it has the " + other + " one; use --side " + other + ")");
    }
  }
  eval::SequenceKeypoints s;
  s.groundTruth = gt->frames;
  s.predicted = pred->frames;
  const std::size_t n = std::max(s.groundTruth.size(), s.predicted.size());
  s.groundTruth.resize(n);
  s.predicted.resize(n);
  s.fps = o.fps;
  eval::MetricsOptions options;
  options.lostThresholdMm = o.lostMm;
  auto m = eval::computeKeypointMetrics(s, options);
  if (!m) throw std::runtime_error(m.message());

  std::fputs(eval::summaryText(*m).c_str(), stdout);
  if (!o.out.empty()) {
    const std::filesystem::path dir(o.out);
    const std::string title = std::filesystem::path(o.pred).filename().string();
    // Each file whole or not at all; the message names the one that failed.
    for (const auto& [name, text] :
         {std::pair<const char*, std::string>{"report.md",
                                              eval::markdownReport(*m, "Evaluation of " + title)},
          {"error_over_time.svg", eval::svgErrorOverTime(*m, "Error over time")},
          {"success_curve.svg", eval::svgSuccessCurve(*m, "Success curve")}}) {
      const Status written = writeFileAtomically(dir / name, text);
      if (!written) throw std::runtime_error(written.message());
    }
    std::printf("wrote %s/{report.md,error_over_time.svg,success_curve.svg}\n", dir.c_str());
  }
  return kExitOk;
}

const CommandRegistration kEvalCommand{Command{
    "eval", "measure 21-keypoint accuracy of tracked poses against ground truth",
    [](CLI::App& sub) -> std::function<int()> {
      auto o = std::make_shared<EvalOptions>();
      sub.add_option("--gt", o->gt, "ground truth JSON lines (groundtruth.jsonl)")
          ->required()
          ->check(CLI::ExistingFile);
      sub.add_option("--pred", o->pred, "tracker output JSON lines (dynahand track --out)")
          ->required()
          ->check(CLI::ExistingFile);
      sub.add_option("--side", o->side, "which hand of the prediction to evaluate")
          ->check(CLI::IsMember({"right", "left"}));
      sub.add_option("--fps", o->fps, "frames per second, for recovery times")
          ->check(CLI::Range(0.001, 100000.0));
      sub.add_option("--lost-mm", o->lostMm, "a frame whose max joint error exceeds this is lost")
          ->check(CLI::Range(0.001, 100000.0));
      sub.add_option("--out", o->out, "folder for report.md and SVG plots");
      sub.footer(
          "Examples:\n"
          "  dynahand eval --gt clip/groundtruth.jsonl --pred poses.jsonl\n"
          "  dynahand eval --gt clip/groundtruth.jsonl --pred poses.jsonl --out report/");
      return [o] { return runEval(*o); };
    }}};

}  // namespace
}  // namespace dynahand::cli
