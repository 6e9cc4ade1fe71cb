// The example scenes in examples/scenes/, shared by the playground tests.
#pragma once

#include <filesystem>
#include <string>

namespace dynahand::playground::test {

inline std::filesystem::path sceneFile(const std::string& name) {
  return std::filesystem::path(DYNAHAND_SOURCE_DIR) / "examples" / "scenes" / (name + ".json");
}

}  // namespace dynahand::playground::test
