// Subcommand registry for the dynahand tool. Each cmd_<name>.cpp defines one
// subcommand and registers it with a static CommandRegistration, so adding a
// command never touches main.cpp.
#pragma once

#include <CLI/CLI.hpp>

#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "dynahand/model.h"
#include "dynahand/tracker.h"

namespace dynahand::cli {

// Exit codes shared by all subcommands.
inline constexpr int kExitOk = 0;
inline constexpr int kExitFailure = 1;  // the job ran and failed, not for its input (a full
                                        // disk, no camera, a missed benchmark target)
inline constexpr int kExitUsage = 2;    // bad input: flags, values, a missing or malformed input
                                        // file (also found while running: a frame that does not
                                        // decode); UsageError

struct Command {
  std::string name;
  std::string summary;
  // Adds options to `sub`; returns the function run when `sub` was chosen.
  std::function<std::function<int()>(CLI::App& sub)> setup;
};

std::vector<Command>& commandRegistry();

struct CommandRegistration {
  explicit CommandRegistration(Command command) { commandRegistry().push_back(std::move(command)); }
};

// Thrown by a command for bad input found after parsing (a missing input path, a file that
// does not parse, a depth frame that does not decode); main prints the message and exits with
// kExitUsage.
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Adds a check to every option of `app` and its subcommands that takes floating-point values:
// NaN and infinities are refused (exit kExitUsage, the message names the option).
void requireFiniteFloats(CLI::App& app);

// Whether the user chose the detector weights (--detector FILE, or DYNAHAND_DETECTOR): then
// weights that do not load are bad input (kExitUsage), otherwise a broken installation.
bool detectorWeightsGiven(const std::string& detectorOption);

// --set NAME=VALUE (repeatable): TrackerSettings fields by name (track::setTrackerSetting;
// `dynahand settings` lists them), applied after the command's own options.
void addTrackerSettingOption(CLI::App& sub, std::vector<std::string>& assignments);
// Applies them in order; an unknown name or a bad value is a UsageError naming it.
void applyTrackerSettings(const std::vector<std::string>& assignments,
                          track::TrackerSettings& settings);
// The same check without settings to apply them to (before any input is opened).
void checkTrackerSettings(const std::vector<std::string>& assignments);

// --disable SIMULATION...: each named simulation (track::strategyName) off; an unknown name is
// a UsageError naming it.
void disableSimulations(const std::vector<std::string>& names, track::TrackerSettings& settings);

// --model / --hand-length / --hand-width: the hand model a recording is (or was) tracked with.
struct HandModelOptions {
  std::string modelFile;  // empty: the built-in hand at the size below
  float length = 0.19f;   // wrist crease to middle fingertip, m
  float width = 0.085f;   // palm width at the knuckles, m
  // Set by addHandModelOptions: whether the user gave a size (a given value wins over one
  // read from a file or estimated).
  const CLI::Option* lengthOption = nullptr;
  const CLI::Option* widthOption = nullptr;
  bool lengthGiven() const { return lengthOption != nullptr && lengthOption->count() > 0; }
  bool widthGiven() const { return widthOption != nullptr && widthOption->count() > 0; }
};
// Adds the options to `sub`; --model only when withModelFile.
void addHandModelOptions(CLI::App& sub, HandModelOptions& o, bool withModelFile = true);

// The right hand's model: the file, or the built-in hand at the given size. A file that does
// not load is a UsageError naming it.
model::ArticulatedModel handModel(const HandModelOptions& o);

}  // namespace dynahand::cli
