// Subcommand registry for the dynahand tool. Each cmd_<name>.cpp defines one
// subcommand and registers it with a static CommandRegistration, so adding a
// command never touches main.cpp.
#pragma once

#include <CLI/CLI.hpp>

#include <functional>
#include <string>
#include <vector>

namespace dynahand::cli {

// Exit codes shared by all subcommands.
inline constexpr int kExitOk = 0;
inline constexpr int kExitFailure = 1;  // the job ran and failed (bad data, missed target)
inline constexpr int kExitUsage = 2;    // bad flags, bad values, missing input path

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

// Thrown by a command for a usage problem found after parsing (e.g. a missing
// input path); main prints the message and exits with kExitUsage.
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

}  // namespace dynahand::cli
