/// @file
/// Live depth cameras behind one interface. Back ends are chosen at configure time:
/// OpenNI2 (Kinect-class, Asus Xtion, Orbbec; and its test device "Dummy"),
/// libfreenect (Kinect v1) and librealsense2 (Intel RealSense), each only when its
/// library was found. cameraBackends() says which ones this build has.
///
///   auto camera = DepthCamera::open("");          // the first camera found
///   DepthFrame frame;
///   while (camera->grab(frame)) { ... }            // blocks until the next frame
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "dynahand/core.h"
#include "dynahand/depth_frame.h"

namespace dynahand {

/// One camera as a back end lists it.
struct CameraInfo {
  std::string backend;  ///< "openni2", "freenect" or "realsense2"
  std::string id;       ///< back-end address: OpenNI URI, Kinect or RealSense serial
  std::string name;     ///< human-readable vendor and model
  /// What DepthCamera::open takes to open exactly this camera: "BACKEND:ID".
  std::string spec() const { return backend + ":" + id; }
};

/// Result of scanning every back end: the cameras found, and one line per back end
/// that could not be asked (e.g. "freenect: cannot initialise USB").
struct CameraScan {
  std::vector<CameraInfo> cameras;    ///< every camera found
  std::vector<std::string> problems;  ///< one line per back end that could not be asked
};

/// Requested stream; a back end picks its closest supported mode (see intrinsics()).
struct CameraOptions {
  int width = 640;   ///< pixels
  int height = 480;  ///< pixels
  int fps = 30;      ///< frames per second
};

/// An open live depth camera; each back end implements it.
class DepthCamera {
 public:
  virtual ~DepthCamera() = default;
  DepthCamera(const DepthCamera&) = delete;
  DepthCamera& operator=(const DepthCamera&) = delete;

  /// Every camera of every compiled back end, in back-end order, then as listed.
  static CameraScan list();
  /// spec: "" = the first camera found; "BACKEND" = that back end's first camera;
  /// "BACKEND:ID" = a given camera (CameraInfo::spec()).
  static Result<std::unique_ptr<DepthCamera>> open(const std::string& spec,
                                                   const CameraOptions& options = {});

  virtual const CameraInfo& info() const = 0;        ///< which camera this is
  virtual const Intrinsics& intrinsics() const = 0;  ///< of the depth stream as delivered
  virtual float depthScale() const = 0;              ///< metres per depth unit
  /// Waits up to timeoutSeconds for the next frame and stores it in `frame`, reusing
  /// its buffer (no allocation per frame once sized). Timestamps are seconds since
  /// the first frame. Error on timeout or a disconnected camera.
  virtual Status grab(DepthFrame& frame, double timeoutSeconds = 2.0) = 0;

 protected:
  DepthCamera() = default;
};

/// Back ends compiled into this build, e.g. {"openni2", "freenect"}.
std::vector<std::string> cameraBackends();

/// True once a camera driver was loaded whose threads keep running until the process ends
/// (OpenNI's, which cannot be shut down safely): a program should then end with std::_Exit
/// after flushing its output, since running static destructors under those threads can crash.
bool cameraDriverThreadsOutliveCameras();

}  // namespace dynahand
