// dynahand version: prints the version and the libraries it was built with.
#include <Eigen/Core>
#include <cstdio>

#include "dynahand/command.h"

namespace dynahand::cli {
namespace {

const CommandRegistration kVersionCommand{Command{
    "version", "print the version and build information",
    [](CLI::App& sub) -> std::function<int()> {
      sub.footer("Example:\n  dynahand version");
      return [] {
        std::printf("dynahand %s (Eigen %d.%d.%d, C++%ld)\n", DYNAHAND_VERSION, EIGEN_WORLD_VERSION,
                    EIGEN_MAJOR_VERSION, EIGEN_MINOR_VERSION, __cplusplus / 100 % 100);
        return kExitOk;
      };
    }}};

}  // namespace
}  // namespace dynahand::cli
