#include "dynahand/command.h"

#include "dynahand/model.h"

namespace dynahand::cli {

std::vector<Command>& commandRegistry() {
  static std::vector<Command> registry;
  return registry;
}

void addHandModelOptions(CLI::App& sub, HandModelOptions& o, bool withModelFile) {
  if (withModelFile)
    sub.add_option("--model", o.modelFile, "hand model file (default: the built-in hand)");
  o.lengthOption = sub.add_option("--hand-length", o.length,
                                  "built-in hand: wrist crease to middle fingertip, m")
                       ->check(CLI::Range(0.10f, 0.30f));
  o.widthOption =
      sub.add_option("--hand-width", o.width, "built-in hand: palm width at the knuckles, m")
          ->check(CLI::Range(0.05f, 0.15f));
}

model::ArticulatedModel handModel(const HandModelOptions& o) {
  if (o.modelFile.empty()) return model::makeDefaultHand({o.length, o.width});
  auto loaded = model::loadModel(o.modelFile);
  if (!loaded) throw UsageError(loaded.message());
  return std::move(*loaded);
}

}  // namespace dynahand::cli
