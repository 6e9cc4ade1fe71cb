#include "dynahand/command.h"

namespace dynahand::cli {

std::vector<Command>& commandRegistry() {
  static std::vector<Command> registry;
  return registry;
}

}  // namespace dynahand::cli
