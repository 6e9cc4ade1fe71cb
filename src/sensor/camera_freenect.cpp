// libfreenect back end: Microsoft Kinect v1 (Xbox 360 / Kinect for Windows),
// depth in millimetres at 640 x 480, 30 Hz.
#include <libfreenect.h>
#include <libfreenect_registration.h>
#include <sys/time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>

#include "core/log.h"
#include "sensor/camera_backends.h"

namespace dynahand::sensor {
namespace {

constexpr int kWidth = 640;   // FREENECT_RESOLUTION_MEDIUM, pixels
constexpr int kHeight = 480;  // pixels

// A libfreenect context limited to the camera sub-device; closes itself.
struct FreenectContext {
  freenect_context* context = nullptr;
  ~FreenectContext() {
    if (context != nullptr) freenect_shutdown(context);
  }
  Status init() {
    if (freenect_init(&context, nullptr) < 0) {
      context = nullptr;
      return Error{"freenect: cannot initialise libfreenect (USB access?)"};
    }
    freenect_set_log_level(context, FREENECT_LOG_ERROR);
    freenect_select_subdevices(context, FREENECT_DEVICE_CAMERA);
    return Ok{};
  }
};

std::vector<std::string> listSerials(freenect_context* context) {
  std::vector<std::string> serials;
  freenect_device_attributes* attributes = nullptr;
  if (freenect_list_device_attributes(context, &attributes) < 0) return serials;
  for (const freenect_device_attributes* a = attributes; a != nullptr; a = a->next) {
    serials.emplace_back(a->camera_serial != nullptr ? a->camera_serial : "");
  }
  freenect_free_device_attributes(attributes);
  return serials;
}

class FreenectCamera final : public DepthCamera {
 public:
  FreenectCamera() = default;
  ~FreenectCamera() override {
    if (device_ != nullptr) {
      if (streaming_) freenect_stop_depth(device_);
      freenect_close_device(device_);
    }
  }

  Status start(const std::string& serial) {
    if (auto ok = context_.init(); !ok) return ok;
    const std::vector<std::string> serials = listSerials(context_.context);
    if (serials.empty()) return Error{"freenect: no Kinect connected"};
    info_ = {"freenect", serial.empty() ? serials.front() : serial, "Microsoft Kinect v1"};
    if (freenect_open_device_by_camera_serial(context_.context, &device_, info_.id.c_str()) < 0) {
      device_ = nullptr;
      return Error{info_.spec() + ": cannot open the Kinect (connected? permissions?)"};
    }
    const freenect_frame_mode mode =
        freenect_find_depth_mode(FREENECT_RESOLUTION_MEDIUM, FREENECT_DEPTH_MM);
    if (!mode.is_valid || freenect_set_depth_mode(device_, mode) < 0) {
      return Error{info_.spec() + ": the Kinect refused 640x480 millimetre depth"};
    }
    // Focal length from the factory calibration: libfreenect deprojects with
    // x = (u - w/2) * z * 2 * pixelSize / referenceDistance at this resolution.
    freenect_registration registration = freenect_copy_registration(device_);
    const float distance = registration.zero_plane_info.reference_distance;     // mm
    const float pixelSize = registration.zero_plane_info.reference_pixel_size;  // mm
    freenect_destroy_registration(&registration);
    float focal = 580.0f;  // typical Kinect v1 depth focal length, pixels
    if (std::isfinite(distance) && std::isfinite(pixelSize) && distance > 0.0f &&
        pixelSize > 0.0f) {
      focal = distance / (2.0f * pixelSize);
    } else {
      log::warn("{}: no factory calibration; assuming a focal length of {} px", info_.spec(),
                focal);
    }
    intrinsics_ = {kWidth, kHeight, focal, focal, 0.5f * kWidth, 0.5f * kHeight};
    latest_.resize(static_cast<std::size_t>(kWidth) * kHeight);
    freenect_set_user(device_, this);
    freenect_set_depth_callback(device_, &FreenectCamera::onDepth);
    if (freenect_start_depth(device_) < 0)
      return Error{info_.spec() + ": cannot start the depth stream"};
    streaming_ = true;
    return Ok{};
  }

  const CameraInfo& info() const override { return info_; }
  const Intrinsics& intrinsics() const override { return intrinsics_; }
  float depthScale() const override { return 0.001f; }

  Status grab(DepthFrame& frame, double timeoutSeconds) override {
    using Clock = std::chrono::steady_clock;
    const auto deadline =
        Clock::now() + std::chrono::duration<double>(std::max(0.0, timeoutSeconds));
    fresh_ = false;
    while (!fresh_) {
      const auto left =
          std::chrono::duration_cast<std::chrono::microseconds>(deadline - Clock::now());
      if (left.count() <= 0) {
        return Error{info_.spec() + ": no depth frame within " + std::to_string(timeoutSeconds) +
                     " s"};
      }
      timeval wait{static_cast<time_t>(left.count() / 1000000),
                   static_cast<suseconds_t>(left.count() % 1000000)};
      if (freenect_process_events_timeout(context_.context, &wait) < 0) {
        return Error{info_.spec() + ": USB error while streaming (disconnected?)"};
      }
    }
    frame.width = kWidth;
    frame.height = kHeight;
    frame.depthScale = 0.001f;
    frame.depth.assign(latest_.begin(), latest_.end());
    // Kinect timestamps count a 60 MHz clock and wrap at 32 bits (about 71 s).
    if (!haveFirst_) {
      previousTicks_ = latestTicks_;
      haveFirst_ = true;
    }
    elapsedTicks_ += static_cast<std::uint32_t>(latestTicks_ - previousTicks_);
    previousTicks_ = latestTicks_;
    frame.timestamp = static_cast<double>(elapsedTicks_) / 60e6;
    return Ok{};
  }

 private:
  static void onDepth(freenect_device* device, void* depth, std::uint32_t timestamp) {
    auto* self = static_cast<FreenectCamera*>(freenect_get_user(device));
    std::memcpy(self->latest_.data(), depth, self->latest_.size() * sizeof(std::uint16_t));
    self->latestTicks_ = timestamp;
    self->fresh_ = true;
  }

  FreenectContext context_;
  freenect_device* device_ = nullptr;
  bool streaming_ = false;
  CameraInfo info_;
  Intrinsics intrinsics_;
  std::vector<std::uint16_t> latest_;  // (480 x 640) mm, filled by onDepth
  std::uint32_t latestTicks_ = 0;
  std::uint32_t previousTicks_ = 0;
  std::uint64_t elapsedTicks_ = 0;
  bool fresh_ = false;
  bool haveFirst_ = false;
};

void listFreenect(CameraScan& scan) {
  FreenectContext context;
  if (auto ok = context.init(); !ok) {
    scan.problems.push_back(ok.message());
    return;
  }
  for (const std::string& serial : listSerials(context.context)) {
    scan.cameras.push_back({"freenect", serial, "Microsoft Kinect v1"});
  }
}

Result<std::unique_ptr<DepthCamera>> openFreenect(const std::string& id,
                                                  const CameraOptions& options) {
  if (options.width != kWidth || options.height != kHeight) {
    log::warn("freenect: the Kinect v1 streams depth at 640x480 only; ignoring {}x{}",
              options.width, options.height);
  }
  auto camera = std::make_unique<FreenectCamera>();
  if (auto ok = camera->start(id); !ok) return ok.error();
  return std::unique_ptr<DepthCamera>(std::move(camera));
}

}  // namespace

const CameraBackend kFreenectBackend{"freenect", &listFreenect, &openFreenect};

}  // namespace dynahand::sensor
