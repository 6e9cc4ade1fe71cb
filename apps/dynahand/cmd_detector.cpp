// dynahand detector: the learned keypoint detector's data and figures. `data` writes a
// synthetic training or held-back set (docs/formats/detector-data.md) for train/; `eval`
// measures a weights file on a freshly generated set (the model card's figures).
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>

#include "dynahand/command.h"
#include "dynahand/detector.h"
#include "dynahand/detector_data.h"
#include "progress.h"

namespace dynahand::cli {
namespace {

// A number for a JSON line: NaN and infinities (a network that outputs NaN) are null.
std::string jsonNumber(double value, int decimals) {
  if (!std::isfinite(value)) return "null";
  char text[64];
  std::snprintf(text, sizeof text, "%.*f", decimals, value);
  return text;
}

detect::DataSplit parseSplit(const std::string& name) {
  if (name == "train") return detect::DataSplit::Train;
  if (name == "held-back") return detect::DataSplit::HeldBack;
  throw UsageError("--split must be 'train' or 'held-back' (got '" + name + "')");
}

const CommandRegistration kDetectorCommand{Command{
    "detector", "the learned keypoint detector: write synthetic training data, measure weights",
    [](CLI::App& sub) -> std::function<int()> {
      struct Flags {
        detect::DataOptions data;
        std::string split = "train", out, weights;
      };
      auto flags = std::make_shared<Flags>();
      sub.require_subcommand(1);
      CLI::App* data = sub.add_subcommand("data", "write a synthetic data file for train/");
      CLI::App* eval = sub.add_subcommand("eval", "measure a weights file on a generated set");
      for (CLI::App* app : {data, eval}) {
        app->add_option("--count", flags->data.count, "samples")
            ->capture_default_str()
            ->check(CLI::Range(1, 10000000));
        app->add_option("--seed", flags->data.seed, "sample i depends on (seed, i) only")
            ->capture_default_str();
        app->add_option("--split", flags->split, "train | held-back (held-back clips and sizes)")
            ->capture_default_str();
        app->add_option("--threads", flags->data.threads, "worker threads (same bytes for any)")
            ->capture_default_str()
            ->check(CLI::Range(1, 64));
        app->add_option("--proportion-spread", flags->data.proportionSpread,
                        "per-bone and per-finger shape factors in [1-s, 1+s]")
            ->capture_default_str()
            ->check(CLI::Range(0.0, 0.5));
        app->add_option("--held-object-share", flags->data.heldObjectShare,
                        "share of samples with an object held at the palm")
            ->capture_default_str()
            ->check(CLI::Range(0.0, 1.0));
        app->add_flag("--held-object-boxes", flags->data.heldObjectBoxes,
                      "held objects may be boxes as well as balls and cylinders");
        app->add_option("--shared-curl-share", flags->data.sharedCurlShare,
                        "share of random poses whose fingers curl together (a grasp)")
            ->capture_default_str()
            ->check(CLI::Range(0.0, 1.0));
        app->add_option("--head-view-share", flags->data.headViewShare,
                        "share of draws seen as from a head-mounted camera (forearm toward it)")
            ->capture_default_str()
            ->check(CLI::Range(0.0, 1.0));
      }
      data->add_option("-o,--out", flags->out, "output file")->required();
      eval->add_option("--weights", flags->weights,
                       "ONNX file (default: the shipped models/detector/detector.onnx)");
      sub.footer(
          "Examples:\n"
          "  dynahand detector data --count 60000 --seed 1 --threads 2 -o train.bin\n"
          "  dynahand detector data --split held-back --count 2000 --seed 2 -o heldback.bin\n"
          "  dynahand detector eval --split held-back --count 500 --seed 7\n"
          "Training: train/train_detector.py; model card: docs/detector.md.");
      return [flags, data]() -> int {
        flags->data.split = parseSplit(flags->split);
        if (data->parsed()) {
          Progress progress("detector data", flags->data.count, "samples");
          const Status s = detect::writeDataFile(flags->data, flags->out,
                                                 [&](int done, int) { progress.update(done); });
          if (!s) {
            std::fprintf(stderr, "dynahand detector data: %s\n", s.message().c_str());
            return kExitFailure;
          }
          progress.finish();
          return kExitOk;
        }
        const std::filesystem::path file = flags->weights.empty()
                                               ? detect::defaultDetectorFile()
                                               : std::filesystem::path(flags->weights);
        if (file.empty())
          throw UsageError("no detector weights found; give --weights FILE (docs/detector.md)");
        auto detector = detect::KeypointDetector::load(file);
        if (!detector) {
          std::fprintf(stderr, "dynahand detector eval: %s\n", detector.message().c_str());
          return detectorWeightsGiven(flags->weights) ? kExitUsage : kExitFailure;
        }
        const detect::DetectorFigures f = detect::evaluateDetector(**detector, flags->data);
        std::printf(
            "{\"weights\": \"%s\", \"split\": \"%s\", \"samples\": %d, \"seed\": %llu, "
            "\"mean_mm\": %s, \"p95_mm\": %s, \"mean_confidence\": %s, \"ms_per_crop\": "
            "%s}\n",
            file.string().c_str(), flags->split.c_str(), f.samples,
            static_cast<unsigned long long>(flags->data.seed), jsonNumber(f.meanMm, 2).c_str(),
            jsonNumber(f.p95Mm, 2).c_str(), jsonNumber(f.meanConfidence, 3).c_str(),
            jsonNumber(f.msPerCrop, 3).c_str());
        return kExitOk;
      };
    }}};

}  // namespace
}  // namespace dynahand::cli
