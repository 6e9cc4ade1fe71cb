// The back ends behind DepthCamera (include/dynahand/camera.h). Each compiled back
// end provides a lister and an opener; camera.cpp keeps the table.
#pragma once

#include <memory>
#include <string>

#include "dynahand/camera.h"

namespace dynahand::sensor {

struct CameraBackend {
  const char* name;
  void (*list)(CameraScan& scan);  // appends cameras or one problem line
  // id empty = the back end's first camera.
  Result<std::unique_ptr<DepthCamera>> (*open)(const std::string& id, const CameraOptions& options);
};

// Records that a driver with never-ending threads was loaded (see camera.h).
void noteDriverThreadsOutliveCameras();

#ifdef DYNAHAND_HAVE_OPENNI2
extern const CameraBackend kOpenNI2Backend;
// OpenNI::initialize once per process; Error with OpenNI's reason when it fails.
Status initializeOpenNI();
#endif
#ifdef DYNAHAND_HAVE_FREENECT
extern const CameraBackend kFreenectBackend;
#endif
#ifdef DYNAHAND_HAVE_REALSENSE2
extern const CameraBackend kRealSenseBackend;
#endif

// Focal length (pixels) of a pinhole camera whose `pixels`-wide image spans `fov` rad.
float focalFromFieldOfView(int pixels, float fovRadians);

}  // namespace dynahand::sensor
