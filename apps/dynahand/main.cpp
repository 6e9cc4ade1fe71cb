// The dynahand command: thin front end over the library. Subcommands live in
// cmd_<name>.cpp files and register themselves (command.h).
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <map>

#include "dynahand/camera.h"
#include "dynahand/command.h"
#include "dynahand/core.h"

int main(int argc, char** argv) {
  using namespace dynahand::cli;
  CLI::App app{
      "dynahand: dynamics-based 3D skeletal hand tracking from depth cameras.\n"
      "Run 'dynahand COMMAND --help' for a command's options and examples."};
  app.set_version_flag("--version", std::string("dynahand ") + DYNAHAND_VERSION);
  int verbosity = 2;
  app.add_option("-v,--verbosity", verbosity, "log level: 0 errors, 1 warnings, 2 info, 3 debug")
      ->check(CLI::Range(0, 3));
  app.require_subcommand(1);

  auto& registry = commandRegistry();
  std::sort(registry.begin(), registry.end(),
            [](const Command& a, const Command& b) { return a.name < b.name; });
  std::map<CLI::App*, std::function<int()>> runners;
  for (auto& command : registry) {
    CLI::App* sub = app.add_subcommand(command.name, command.summary);
    runners[sub] = command.setup(*sub);
  }
  requireFiniteFloats(app);

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "dynahand: %s (see 'dynahand --help')\n", e.what());
    return kExitUsage;
  }
  dynahand::setLogLevel(verbosity);
  for (auto& [sub, run] : runners) {
    if (sub->parsed()) {
      try {
        const int code = run();
        if (dynahand::cameraDriverThreadsOutliveCameras()) {
          // OpenNI's driver threads outlive everything: end without static destructors.
          std::fflush(nullptr);
          std::_Exit(code);
        }
        return code;
      } catch (const UsageError& e) {
        std::fprintf(stderr, "dynahand %s: %s\n", sub->get_name().c_str(), e.what());
        return kExitUsage;
      } catch (const std::exception& e) {
        std::fprintf(stderr, "dynahand %s: error: %s\n", sub->get_name().c_str(), e.what());
        return kExitFailure;
      }
    }
  }
  return kExitUsage;
}
