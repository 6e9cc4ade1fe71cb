// OpenNI2 back end: Kinect-class cameras (PrimeSense, Asus Xtion, Orbbec) and
// OpenNI's test device "Dummy" (320 x 240, a moving disc at about 1 m).
#include <OpenNI.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>

#include "core/log.h"
#include "sensor/camera_backends.h"
#include "sensor/openni2_support.h"

namespace dynahand::sensor {
namespace {

// "Vendor Model", without stray spaces when either is empty.
std::string deviceName(const openni::DeviceInfo& device) {
  std::string name = std::string(device.getVendor()) + " " + device.getName();
  while (!name.empty() && name.back() == ' ') name.pop_back();
  while (!name.empty() && name.front() == ' ') name.erase(name.begin());
  return name.empty() ? "OpenNI device" : name;
}

// Kinect v1 depth camera fields of view, for devices that do not report theirs.
constexpr float kFallbackHorizontalFov = 1.0226f;  // rad, 58.6 degrees
constexpr float kFallbackVerticalFov = 0.7959f;    // rad, 45.6 degrees

class OpenNI2Camera final : public DepthCamera {
 public:
  OpenNI2Camera() = default;
  ~OpenNI2Camera() override {
    stream_.stop();
    stream_.destroy();
    device_.close();
  }

  Status start(const std::string& uri, const CameraOptions& options) {
    const std::string where = "openni2:" + uri;
    if (device_.open(uri.c_str()) != openni::STATUS_OK) {
      return Error{where + ": cannot open the device (" + openniError() + ")"};
    }
    info_ = {"openni2", uri, deviceName(device_.getDeviceInfo())};
    if (!device_.hasSensor(openni::SENSOR_DEPTH))
      return Error{where + ": the device has no depth sensor"};
    if (stream_.create(device_, openni::SENSOR_DEPTH) != openni::STATUS_OK) {
      return Error{where + ": cannot create the depth stream (" + openniError() + ")"};
    }
    chooseVideoMode(options);
    if (stream_.start() != openni::STATUS_OK) {
      return Error{where + ": cannot start the depth stream (" + openniError() + ")"};
    }
    depthScale_ = openniDepthScale(stream_.getVideoMode().getPixelFormat());
    if (depthScale_ <= 0.0f)
      return Error{where + ": the depth stream does not deliver depth pixels"};
    intrinsics_ = openniIntrinsics(stream_, where);
    return Ok{};
  }

  const CameraInfo& info() const override { return info_; }
  const Intrinsics& intrinsics() const override { return intrinsics_; }
  float depthScale() const override { return depthScale_; }

  Status grab(DepthFrame& frame, double timeoutSeconds) override {
    openni::VideoStream* streams[] = {&stream_};
    int ready = -1;
    const int timeoutMs = static_cast<int>(std::lround(std::max(0.0, timeoutSeconds) * 1000.0));
    const openni::Status waited = openni::OpenNI::waitForAnyStream(streams, 1, &ready, timeoutMs);
    if (waited == openni::STATUS_TIME_OUT) {
      return Error{info_.spec() + ": no depth frame within " + std::to_string(timeoutSeconds) +
                   " s"};
    }
    openni::VideoFrameRef source;
    if (waited != openni::STATUS_OK || stream_.readFrame(&source) != openni::STATUS_OK) {
      return Error{info_.spec() + ": reading a depth frame failed (" + openniError() + ")"};
    }
    if (source.getWidth() != intrinsics_.width || source.getHeight() != intrinsics_.height) {
      return Error{info_.spec() + ": frame size changed while streaming"};
    }
    if (auto ok = copyOpenNIFrame(source, depthScale_, frame, info_.spec()); !ok) return ok;
    const std::uint64_t micros = source.getTimestamp();
    if (!haveFirstTimestamp_) {
      firstTimestamp_ = micros;
      haveFirstTimestamp_ = true;
    }
    frame.timestamp = static_cast<double>(micros - std::min(micros, firstTimestamp_)) * 1e-6;
    return Ok{};
  }

 private:
  // The supported depth mode closest to the request (size first, then rate).
  void chooseVideoMode(const CameraOptions& options) {
    const openni::SensorInfo& sensor = stream_.getSensorInfo();
    const auto& modes = sensor.getSupportedVideoModes();
    int best = -1;
    long bestCost = 0;
    for (int i = 0; i < modes.getSize(); ++i) {
      if (openniDepthScale(modes[i].getPixelFormat()) <= 0.0f) continue;
      const long cost = 1000L * (std::labs(modes[i].getResolutionX() - options.width) +
                                 std::labs(modes[i].getResolutionY() - options.height)) +
                        std::labs(modes[i].getFps() - options.fps);
      if (best < 0 || cost < bestCost) {
        best = i;
        bestCost = cost;
      }
    }
    if (best < 0) return;
    const openni::VideoMode current = stream_.getVideoMode();
    if (current.getResolutionX() == modes[best].getResolutionX() &&
        current.getResolutionY() == modes[best].getResolutionY() &&
        current.getFps() == modes[best].getFps() &&
        current.getPixelFormat() == modes[best].getPixelFormat()) {
      return;
    }
    if (stream_.setVideoMode(modes[best]) != openni::STATUS_OK) {
      log::warn("{}: could not select {}x{} depth; using the device default", info_.spec(),
                modes[best].getResolutionX(), modes[best].getResolutionY());
    }
  }

  openni::Device device_;
  openni::VideoStream stream_;
  CameraInfo info_;
  Intrinsics intrinsics_;
  float depthScale_ = 0.001f;
  std::uint64_t firstTimestamp_ = 0;
  bool haveFirstTimestamp_ = false;
};

void listOpenNI2(CameraScan& scan) {
  if (auto ok = initializeOpenNI(); !ok) {
    scan.problems.push_back(ok.message());
    return;
  }
  openni::Array<openni::DeviceInfo> devices;
  openni::OpenNI::enumerateDevices(&devices);
  for (int i = 0; i < devices.getSize(); ++i) {
    scan.cameras.push_back({"openni2", devices[i].getUri(), deviceName(devices[i])});
  }
}

Result<std::unique_ptr<DepthCamera>> openOpenNI2(const std::string& id,
                                                 const CameraOptions& options) {
  if (auto ok = initializeOpenNI(); !ok) return ok.error();
  std::string uri = id;
  if (uri.empty()) {
    CameraScan scan;
    listOpenNI2(scan);
    if (scan.cameras.empty()) return Error{"openni2: no OpenNI2 device connected"};
    uri = scan.cameras.front().id;
  }
  auto camera = std::make_unique<OpenNI2Camera>();
  if (auto ok = camera->start(uri, options); !ok) return ok.error();
  return std::unique_ptr<DepthCamera>(std::move(camera));
}

}  // namespace

const CameraBackend kOpenNI2Backend{"openni2", &listOpenNI2, &openOpenNI2};

Status initializeOpenNI() {
  // OpenNI keeps global state; initialise once and leave it for the process.
  static const std::string failure = [] {
    // No OpenNI::shutdown() at exit: it unloads drivers whose threads may still run
    // (the Dummy device's never stops), which crashes the process on the way out.
    if (openni::OpenNI::initialize() == openni::STATUS_OK) {
      noteDriverThreadsOutliveCameras();
      return std::string{};
    }
    return "openni2: OpenNI could not be initialised (" + openniError() + ")";
  }();
  if (!failure.empty()) return Error{failure};
  return Ok{};
}

std::string openniError() {
  std::string text = openni::OpenNI::getExtendedError();
  while (!text.empty() && (text.back() == '\n' || text.back() == ' ')) text.pop_back();
  while (!text.empty() && (text.front() == '\t' || text.front() == ' ')) text.erase(text.begin());
  return text;
}

float openniDepthScale(openni::PixelFormat format) {
  switch (format) {
    case openni::PIXEL_FORMAT_DEPTH_1_MM:
      return 0.001f;
    case openni::PIXEL_FORMAT_DEPTH_100_UM:
      return 0.0001f;
    default:
      return 0.0f;
  }
}

Intrinsics openniIntrinsics(openni::VideoStream& stream, const std::string& where) {
  const openni::VideoMode mode = stream.getVideoMode();
  float hfov = stream.getHorizontalFieldOfView();
  float vfov = stream.getVerticalFieldOfView();
  if (!std::isfinite(hfov) || !std::isfinite(vfov) || hfov <= 0.0f || vfov <= 0.0f ||
      hfov >= 3.1f || vfov >= 3.1f) {
    log::warn("{}: the device reports no field of view; assuming a Kinect v1's (58.6 x 45.6 deg)",
              where);
    hfov = kFallbackHorizontalFov;
    vfov = kFallbackVerticalFov;
  }
  const int w = mode.getResolutionX();
  const int h = mode.getResolutionY();
  return {w,
          h,
          focalFromFieldOfView(w, hfov),
          focalFromFieldOfView(h, vfov),
          0.5f * static_cast<float>(w),
          0.5f * static_cast<float>(h)};
}

Status copyOpenNIFrame(const openni::VideoFrameRef& source, float depthScale, DepthFrame& frame,
                       const std::string& where) {
  const int w = source.getWidth();
  const int h = source.getHeight();
  const int stride = source.getStrideInBytes();
  const auto rowBytes = static_cast<std::size_t>(w) * sizeof(std::uint16_t);
  if (w <= 0 || h <= 0 || stride < static_cast<int>(rowBytes) || source.getData() == nullptr ||
      source.getDataSize() < stride * (h - 1) + static_cast<int>(rowBytes)) {
    return Error{where + ": OpenNI delivered a malformed depth frame"};
  }
  frame.width = w;
  frame.height = h;
  frame.depthScale = depthScale;
  frame.depth.resize(static_cast<std::size_t>(w) * h);
  const auto* bytes = static_cast<const std::uint8_t*>(source.getData());
  for (int v = 0; v < h; ++v) {
    std::memcpy(&frame.at(0, v), bytes + static_cast<std::ptrdiff_t>(v) * stride, rowBytes);
  }
  return Ok{};
}

}  // namespace dynahand::sensor

// OpenNI and its drivers keep allocations for the life of the process (see
// initializeOpenNI), which LeakSanitizer reports at exit. Suppress exactly those
// libraries in sanitizer builds; weak, so an application's own list wins.
#if defined(__SANITIZE_ADDRESS__)
#define DYNAHAND_LSAN_SUPPRESSIONS 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define DYNAHAND_LSAN_SUPPRESSIONS 1
#endif
#endif
#ifdef DYNAHAND_LSAN_SUPPRESSIONS
extern "C" __attribute__((weak)) const char* __lsan_default_suppressions() {
  return "leak:libOpenNI2.so\nleak:/OpenNI2/Drivers/\n";
}
#endif
