// librealsense2 back end: Intel RealSense D400 / SR300-series depth cameras.
// Built only when librealsense2 is installed (it is not packaged in Debian 12).
#include <librealsense2/rs.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "sensor/camera_backends.h"

namespace dynahand::sensor {
namespace {

class RealSenseCamera final : public DepthCamera {
 public:
  RealSenseCamera() = default;
  ~RealSenseCamera() override {
    if (!started_) return;
    try {
      pipeline_.stop();
    } catch (const rs2::error&) {
      // Stopping an unplugged camera throws; nothing is left to release.
    }
  }

  Status start(const std::string& serial, const std::string& name, const CameraOptions& options) {
    info_ = {"realsense2", serial, name};
    try {
      rs2::config config;
      config.enable_device(serial);
      config.enable_stream(RS2_STREAM_DEPTH, options.width, options.height, RS2_FORMAT_Z16,
                           options.fps);
      rs2::pipeline_profile profile;
      if (config.can_resolve(pipeline_)) {
        profile = pipeline_.start(config);
      } else {  // the requested mode is not offered: take the device's default depth mode
        rs2::config fallback;
        fallback.enable_device(serial);
        fallback.enable_stream(RS2_STREAM_DEPTH, RS2_FORMAT_Z16);
        profile = pipeline_.start(fallback);
      }
      started_ = true;
      const auto stream = profile.get_stream(RS2_STREAM_DEPTH).as<rs2::video_stream_profile>();
      const rs2_intrinsics k = stream.get_intrinsics();
      intrinsics_ = {k.width, k.height, k.fx, k.fy, k.ppx, k.ppy};
      depthScale_ = profile.get_device().first<rs2::depth_sensor>().get_depth_scale();
    } catch (const rs2::error& e) {
      return Error{info_.spec() + ": cannot start the depth stream (" + e.what() + ")"};
    }
    if (!intrinsics_.valid() || !(depthScale_ > 0.0f)) {
      return Error{info_.spec() + ": the camera reports unusable intrinsics or depth scale"};
    }
    return Ok{};
  }

  const CameraInfo& info() const override { return info_; }
  const Intrinsics& intrinsics() const override { return intrinsics_; }
  float depthScale() const override { return depthScale_; }

  Status grab(DepthFrame& frame, double timeoutSeconds) override {
    try {
      rs2::frameset frames;
      const auto timeoutMs =
          static_cast<unsigned>(std::lround(std::max(0.0, timeoutSeconds) * 1000.0));
      if (!pipeline_.try_wait_for_frames(&frames, timeoutMs)) {
        return Error{info_.spec() + ": no depth frame within " + std::to_string(timeoutSeconds) +
                     " s"};
      }
      const rs2::depth_frame depth = frames.get_depth_frame();
      const int w = depth.get_width();
      const int h = depth.get_height();
      const int stride = depth.get_stride_in_bytes();
      if (w != intrinsics_.width || h != intrinsics_.height || stride < w * 2) {
        return Error{info_.spec() + ": frame size changed while streaming"};
      }
      frame.width = w;
      frame.height = h;
      frame.depthScale = depthScale_;
      frame.depth.resize(static_cast<std::size_t>(w) * h);
      const auto* bytes = static_cast<const std::uint8_t*>(depth.get_data());
      for (int v = 0; v < h; ++v) {
        std::memcpy(&frame.at(0, v), bytes + static_cast<std::ptrdiff_t>(v) * stride,
                    static_cast<std::size_t>(w) * 2);
      }
      const double millis = depth.get_timestamp();
      if (!haveFirst_) {
        firstMillis_ = millis;
        haveFirst_ = true;
      }
      frame.timestamp = (millis - firstMillis_) * 1e-3;
    } catch (const rs2::error& e) {
      return Error{info_.spec() + ": streaming failed (" + e.what() + ")"};
    }
    return Ok{};
  }

 private:
  rs2::pipeline pipeline_;
  bool started_ = false;
  CameraInfo info_;
  Intrinsics intrinsics_;
  float depthScale_ = 0.001f;
  double firstMillis_ = 0.0;
  bool haveFirst_ = false;
};

void listRealSense(CameraScan& scan) {
  try {
    rs2::context context;
    for (auto&& device : context.query_devices()) {
      scan.cameras.push_back({"realsense2", device.get_info(RS2_CAMERA_INFO_SERIAL_NUMBER),
                              std::string("Intel ") + device.get_info(RS2_CAMERA_INFO_NAME)});
    }
  } catch (const rs2::error& e) {
    scan.problems.push_back(std::string("realsense2: cannot list cameras (") + e.what() + ")");
  }
}

Result<std::unique_ptr<DepthCamera>> openRealSense(const std::string& id,
                                                   const CameraOptions& options) {
  CameraScan scan;
  listRealSense(scan);
  if (!scan.problems.empty()) return Error{scan.problems.front()};
  const auto found = std::find_if(scan.cameras.begin(), scan.cameras.end(),
                                  [&](const CameraInfo& c) { return id.empty() || c.id == id; });
  if (found == scan.cameras.end()) {
    return Error{id.empty() ? "realsense2: no RealSense camera connected"
                            : "realsense2:" + id + ": no RealSense camera with that serial number"};
  }
  auto camera = std::make_unique<RealSenseCamera>();
  if (auto ok = camera->start(found->id, found->name, options); !ok) return ok.error();
  return std::unique_ptr<DepthCamera>(std::move(camera));
}

}  // namespace

const CameraBackend kRealSenseBackend{"realsense2", &listRealSense, &openRealSense};

}  // namespace dynahand::sensor
