#include "dynahand/command.h"

#include <cmath>
#include <cstdlib>
#include <string>

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

void addTrackerSettingOption(CLI::App& sub, std::vector<std::string>& assignments) {
  sub.add_option("--set", assignments,
                 "NAME=VALUE: a tracker setting by name, e.g. detector.selectionWeight=0 "
                 "(repeatable; 'dynahand settings' lists them with their defaults)")
      ->take_all()
      ->allow_extra_args(false);
}

void applyTrackerSettings(const std::vector<std::string>& assignments,
                          track::TrackerSettings& settings) {
  for (const std::string& a : assignments)
    if (const Status s = track::setTrackerSetting(settings, a); !s)
      throw UsageError("--set: " + s.message());
}

void checkTrackerSettings(const std::vector<std::string>& assignments) {
  track::TrackerSettings settings;
  applyTrackerSettings(assignments, settings);
}

void disableSimulations(const std::vector<std::string>& names, track::TrackerSettings& settings) {
  for (const std::string& name : names) {
    int kind = 0;
    while (kind < track::kStrategyCount &&
           name != track::strategyName(static_cast<track::StrategyKind>(kind)))
      ++kind;
    if (kind == track::kStrategyCount)
      throw UsageError("--disable: unknown simulation '" + name + "'");
    settings.strategies[static_cast<std::size_t>(kind)] = false;
  }
}

model::ArticulatedModel handModel(const HandModelOptions& o) {
  if (o.modelFile.empty()) return model::makeDefaultHand({o.length, o.width});
  auto loaded = model::loadModel(o.modelFile);
  if (!loaded) throw UsageError(loaded.message());
  // What the tracker's hand rig needs (src/track/hand_rig.cpp), checked here so that the
  // message names the file.
  if (loaded->bodyCount() != 17 || loaded->jointCount() != 16 || !loaded->hasKeypoints21()) {
    throw UsageError(o.modelFile +
                     ": not a hand model: the tracker needs 17 bodies, 16 joints "
                     "and the 21 hand keypoints (model '" +
                     loaded->metadata().name + "' has " + std::to_string(loaded->bodyCount()) +
                     " bodies, " + std::to_string(loaded->jointCount()) + " joints)");
  }
  return std::move(*loaded);
}

bool detectorWeightsGiven(const std::string& detectorOption) {
  const char* env = std::getenv("DYNAHAND_DETECTOR");
  return !detectorOption.empty() || (env != nullptr && *env != '\0');
}

namespace {
// CLI::Range and the commands' own checks compare, and every comparison with NaN is false:
// refuse NaN and infinities before any of them sees the value.
const CLI::Validator kFinite(
    [](std::string& value) -> std::string {
      double v = 0.0;
      if (CLI::detail::lexical_cast(value, v) && !std::isfinite(v))
        return "must be a finite number (got " + value + ")";
      return {};
    },
    "", "FINITE");

bool takesFloats(const CLI::Option& option) {
  // CLI11 names the value type FLOAT for float and double (also in vectors and tuples).
  return option.get_type_name().find("FLOAT") != std::string::npos;
}
}  // namespace

void requireFiniteFloats(CLI::App& app) {
  for (CLI::Option* option : app.get_options()) {
    if (takesFloats(*option)) option->check(kFinite);
  }
  for (CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; }))
    requireFiniteFloats(*sub);
}

}  // namespace dynahand::cli
