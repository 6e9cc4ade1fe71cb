// dynahand model: writes a model file (docs/formats/model.md): the default hand at a given
// size and side, or the original authors' model converted; --check validates a model file.
#include <cstdio>
#include <string>

#include "dynahand/atomic_file.h"
#include "dynahand/command.h"
#include "dynahand/model.h"
#include "dynahand/model_intel.h"

namespace dynahand::cli {
namespace {

const CommandRegistration kModelCommand{Command{
    "model", "write the default hand (any size, either side) or a converted model as a model file",
    [](CLI::App& sub) -> std::function<int()> {
      struct Flags {
        model::HandDimensions dims;
        bool left = false;
        bool right = false;
        std::string out, fromIntel, check;
      };
      auto flags = std::make_shared<Flags>();
      sub.add_option("--length", flags->dims.length,
                     "hand length, wrist crease to middle fingertip, m")
          ->capture_default_str()
          ->check(CLI::Range(0.10, 0.30));
      sub.add_option("--width", flags->dims.width, "palm width across the knuckles, m")
          ->capture_default_str()
          ->check(CLI::Range(0.05, 0.13));
      sub.add_flag("--left", flags->left, "a left hand (the mirror image of the right hand)");
      sub.add_flag("--right", flags->right, "a right hand (the default)");
      sub.add_option("-o,--out", flags->out, "output file (default: standard output)");
      sub.add_option("--from-intel", flags->fromIntel,
                     "convert the original authors' model_hand.json instead "
                     "(--length/--width/--left then ignored)")
          ->check(CLI::ExistingFile);
      sub.add_option("--check", flags->check, "validate a model file, print a summary and exit")
          ->check(CLI::ExistingFile);
      sub.footer(
          "Examples:\n"
          "  dynahand model > right.json\n"
          "  dynahand model --length 0.18 --width 0.085 --left > left.json\n"
          "  dynahand model --from-intel ../shared/data/intel/model_hand.json -o intel_hand.json\n"
          "  dynahand model --check left.json\n"
          "Format: docs/formats/model.md; body frames and angles: docs/model.md.");
      return [flags]() -> int {
        if (flags->left && flags->right) throw UsageError("--left and --right are exclusive");
        if (!flags->check.empty()) {
          const Result<model::ArticulatedModel> m = model::loadModel(flags->check);
          if (!m) throw UsageError(m.message());
          float mass = 0.0f;
          for (const model::Body& b : m->bodies()) mass += b.mass;
          std::printf("%s: ok: '%s', %d bodies, %d joints, %zu keypoints, %.3f kg%s\n",
                      flags->check.c_str(), m->metadata().name.c_str(), m->bodyCount(),
                      m->jointCount(), m->keypoints().size(), static_cast<double>(mass),
                      m->hasKeypoints21() ? ", 21 hand keypoints" : "");
          return kExitOk;
        }
        std::string text;
        if (!flags->fromIntel.empty()) {
          const Result<model::IntelModel> imported = model::importIntelModel(flags->fromIntel);
          if (!imported) throw UsageError(imported.message());
          text = model::modelToJson(imported->model);
        } else {
          text = model::modelToJson(model::makeDefaultHand(
              flags->dims, flags->left ? model::Side::Left : model::Side::Right));
        }
        if (flags->out.empty()) {
          const bool written = std::fwrite(text.data(), 1, text.size(), stdout) == text.size();
          if (std::fflush(stdout) != 0 || !written || std::ferror(stdout) != 0)
            throw std::runtime_error("standard output: write failed (disk full?)");
          return kExitOk;
        }
        const Status s = writeFileAtomically(flags->out, text);
        if (!s) throw std::runtime_error(s.message());
        return kExitOk;
      };
    }}};

}  // namespace
}  // namespace dynahand::cli
