// dynahand cameras: lists the depth cameras the compiled back ends can see.
#include <cstdio>

#include "dynahand/camera.h"
#include "dynahand/command.h"

namespace dynahand::cli {
namespace {

std::string joined(const std::vector<std::string>& items) {
  std::string text;
  for (const std::string& item : items) text += (text.empty() ? "" : ", ") + item;
  return text.empty() ? "none" : text;
}

const CommandRegistration kCamerasCommand{Command{
    "cameras", "list connected depth cameras", [](CLI::App& sub) -> std::function<int()> {
      auto details = std::make_shared<bool>(false);
      sub.add_flag("--details", *details, "open each camera and print its depth stream intrinsics");
      sub.footer(
          "Prints one camera per line as SPEC  NAME; pass SPEC to 'dynahand record --camera'.\n"
          "Exits with 1 when no camera is found.\n"
          "Examples:\n"
          "  dynahand cameras\n"
          "  dynahand cameras --details");
      return [details] {
        const std::vector<std::string> backends = cameraBackends();
        const CameraScan scan = DepthCamera::list();
        for (const std::string& problem : scan.problems)
          std::fprintf(stderr, "note: %s\n", problem.c_str());
        if (scan.cameras.empty()) {
          std::fprintf(stderr, "No depth cameras found (camera back ends in this build: %s).\n",
                       joined(backends).c_str());
          return kExitFailure;
        }
        for (const CameraInfo& camera : scan.cameras) {
          std::printf("%-28s %s\n", camera.spec().c_str(), camera.name.c_str());
          if (!*details) continue;
          auto opened = DepthCamera::open(camera.spec());
          if (!opened) {
            std::printf("    cannot open: %s\n", opened.message().c_str());
            continue;
          }
          const Intrinsics& k = (*opened)->intrinsics();
          std::printf("    %dx%d  fx %.2f  fy %.2f  cx %.2f  cy %.2f  depth unit %g m\n", k.width,
                      k.height, static_cast<double>(k.fx), static_cast<double>(k.fy),
                      static_cast<double>(k.cx), static_cast<double>(k.cy),
                      static_cast<double>((*opened)->depthScale()));
        }
        return kExitOk;
      };
    }}};

}  // namespace
}  // namespace dynahand::cli
