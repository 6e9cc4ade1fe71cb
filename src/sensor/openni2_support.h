// Pieces shared by the OpenNI2 camera back end and the .oni reader. Only
// included when DYNAHAND_HAVE_OPENNI2.
#pragma once

#include <OpenNI.h>

#include <string>

#include "dynahand/depth_frame.h"

namespace dynahand::sensor {

// Metres per unit of an OpenNI depth pixel format, or 0 for a non-depth format.
float openniDepthScale(openni::PixelFormat format);

// Pinhole intrinsics of a started depth stream from its fields of view (OpenNI's
// own deprojection puts the principal point at (width / 2, height / 2)). Devices
// that do not report fields of view get a Kinect v1's (58.6 x 45.6 degrees) and a
// warning naming `where`.
Intrinsics openniIntrinsics(openni::VideoStream& stream, const std::string& where);

// Copies a depth frame (row stride honoured) into `frame`, reusing its buffer.
Status copyOpenNIFrame(const openni::VideoFrameRef& source, float depthScale, DepthFrame& frame,
                       const std::string& where);

// The last OpenNI error as text ("" when none).
std::string openniError();

}  // namespace dynahand::sensor
