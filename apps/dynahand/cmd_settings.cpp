// dynahand settings: the tracker settings `--set NAME=VALUE` takes, with their defaults.
#include <cstdio>

#include "dynahand/command.h"
#include "dynahand/tracker.h"

namespace dynahand::cli {
namespace {

const CommandRegistration kSettingsCommand{Command{
    "settings", "list the tracker settings --set takes (track, bench), with their defaults",
    [](CLI::App& sub) -> std::function<int()> {
      sub.footer(
          "Examples:\n"
          "  dynahand settings\n"
          "  dynahand track clip/ --init gt --set detector.selectionWeight=0\n"
          "  dynahand bench --suite motion --rows 'tof / ' --set detector.fitStartPoseWeight=0.07");
      return [] {
        for (const track::NamedSetting& s : track::namedSettings())
          std::printf("%-44s %-11s %s\n", s.name.c_str(), s.value.c_str(), s.description.c_str());
        return kExitOk;
      };
    }}};

}  // namespace
}  // namespace dynahand::cli
