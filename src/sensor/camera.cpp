// DepthCamera's static entry points: the table of compiled back ends.
#include <atomic>
#include <cmath>
#include <span>

#include "sensor/camera_backends.h"

namespace dynahand {
namespace {

std::span<const sensor::CameraBackend* const> compiledBackends() {
  static const sensor::CameraBackend* const kBackends[] = {
#ifdef DYNAHAND_HAVE_OPENNI2
      &sensor::kOpenNI2Backend,
#endif
#ifdef DYNAHAND_HAVE_FREENECT
      &sensor::kFreenectBackend,
#endif
#ifdef DYNAHAND_HAVE_REALSENSE2
      &sensor::kRealSenseBackend,
#endif
      nullptr};
  return {kBackends, std::size(kBackends) - 1};
}

std::string backendNames() {
  std::string names;
  for (const auto* backend : compiledBackends())
    names += (names.empty() ? "" : ", ") + std::string(backend->name);
  return names.empty() ? "none" : names;
}

}  // namespace

namespace sensor {
namespace {
std::atomic<bool> driverThreadsOutlive{false};
}  // namespace
void noteDriverThreadsOutliveCameras() {
  driverThreadsOutlive = true;
}
float focalFromFieldOfView(int pixels, float fovRadians) {
  return 0.5f * static_cast<float>(pixels) / std::tan(0.5f * fovRadians);
}
}  // namespace sensor

bool cameraDriverThreadsOutliveCameras() {
  return sensor::driverThreadsOutlive;
}

std::vector<std::string> cameraBackends() {
  std::vector<std::string> names;
  for (const auto* backend : compiledBackends()) names.emplace_back(backend->name);
  return names;
}

CameraScan DepthCamera::list() {
  CameraScan scan;
  for (const auto* backend : compiledBackends()) backend->list(scan);
  return scan;
}

Result<std::unique_ptr<DepthCamera>> DepthCamera::open(const std::string& spec,
                                                       const CameraOptions& options) {
  if (options.width <= 0 || options.height <= 0 || options.fps <= 0) {
    return Error{"camera options: width, height and fps must be positive"};
  }
  if (spec.empty()) {
    const CameraScan scan = list();
    if (scan.cameras.empty()) {
      std::string message =
          "no depth camera found (back ends in this build: " + backendNames() + ")";
      for (const std::string& problem : scan.problems) message += "; " + problem;
      return Error{message};
    }
    return open(scan.cameras.front().spec(), options);
  }
  const std::size_t colon = spec.find(':');
  const std::string backendName = spec.substr(0, colon);
  const std::string id = colon == std::string::npos ? std::string{} : spec.substr(colon + 1);
  for (const auto* backend : compiledBackends()) {
    if (backendName == backend->name) return backend->open(id, options);
  }
  return Error{"camera '" + spec + "': unknown back end '" + backendName +
               "' (back ends in this build: " + backendNames() + ")"};
}

}  // namespace dynahand
