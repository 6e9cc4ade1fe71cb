#include "core/log.h"

#include <spdlog/sinks/stdout_color_sinks.h>

#include <algorithm>

#include "dynahand/core.h"

namespace dynahand {

namespace log {
spdlog::logger& logger() {
  // Logs go to stderr so stdout stays clean for data (JSON lines, model files).
  static std::shared_ptr<spdlog::logger> instance = [] {
    auto l = spdlog::stderr_color_mt("dynahand");
    l->set_pattern("%^[%l]%$ %v");
    l->set_level(spdlog::level::info);
    return l;
  }();
  return *instance;
}
}  // namespace log

void setLogLevel(int level) {
  static constexpr spdlog::level::level_enum kLevels[] = {
      spdlog::level::err, spdlog::level::warn, spdlog::level::info, spdlog::level::debug};
  log::logger().set_level(kLevels[std::clamp(level, 0, 3)]);
}

}  // namespace dynahand
