// Live cameras: the back-end table, error paths, and (when OpenNI2 is built in)
// OpenNI's test device "Dummy" streaming through DepthCamera. (A recording of the
// dummy is no .oni test: Debian 12's libOniFile crashes seeking in one.)
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "dynahand/camera.h"
#include "test_support.h"

namespace dynahand {
namespace {

bool hasBackend(const std::string& name) {
  const auto names = cameraBackends();
  return std::find(names.begin(), names.end(), name) != names.end();
}

TEST(Cameras, ListingNeverFailsAndNamesBackEnds) {
  const CameraScan scan = DepthCamera::list();
  for (const CameraInfo& camera : scan.cameras) {
    EXPECT_TRUE(hasBackend(camera.backend)) << camera.spec();
    EXPECT_FALSE(camera.id.empty()) << camera.spec();
  }
  for (const std::string& problem : scan.problems) EXPECT_FALSE(problem.empty());
}

TEST(Cameras, UnknownBackEndIsAnError) {
  auto camera = DepthCamera::open("webcam:0");
  ASSERT_FALSE(camera);
  EXPECT_NE(camera.message().find("unknown back end 'webcam'"), std::string::npos)
      << camera.message();
}

TEST(Cameras, BadOptionsAreAnError) {
  CameraOptions options;
  options.fps = 0;
  auto camera = DepthCamera::open("openni2:Dummy", options);
  ASSERT_FALSE(camera);
  EXPECT_NE(camera.message().find("must be positive"), std::string::npos) << camera.message();
}

TEST(Cameras, OpenNI2MissingDeviceIsAnError) {
  if (!hasBackend("openni2")) GTEST_SKIP() << "built without OpenNI2";
  auto camera = DepthCamera::open("openni2:no-such-device");
  ASSERT_FALSE(camera);
  EXPECT_NE(camera.message().find("openni2:no-such-device: cannot open the device"),
            std::string::npos)
      << camera.message();
}

TEST(Cameras, OpenNI2DummyDeviceStreamsDepth) {
  if (!hasBackend("openni2")) GTEST_SKIP() << "built without OpenNI2";
  auto camera = DepthCamera::open("openni2:Dummy");
  ASSERT_TRUE(camera) << camera.message();
  const Intrinsics& k = (*camera)->intrinsics();
  EXPECT_EQ(k.width, 320);
  EXPECT_EQ(k.height, 240);
  EXPECT_FLOAT_EQ(k.cx, 160.0f);
  EXPECT_FLOAT_EQ(k.cy, 120.0f);
  // The dummy reports no field of view: a Kinect v1's 58.6 degrees is assumed.
  EXPECT_NEAR(k.fx, 160.0f / std::tan(0.5f * 1.0226f), 0.01f);
  EXPECT_FLOAT_EQ((*camera)->depthScale(), 0.001f);
  DepthFrame frame;
  double previous = -1.0;
  for (int i = 0; i < 3; ++i) {
    ASSERT_TRUE((*camera)->grab(frame, 2.0));
    ASSERT_EQ(frame.width, 320);
    ASSERT_EQ(frame.height, 240);
    EXPECT_FLOAT_EQ(frame.metres(100, 0), 2.0f);  // the dummy paints its top row at 2000 mm
    EXPECT_GT(frame.timestamp, previous);
    previous = frame.timestamp;
  }
  EXPECT_NEAR(previous, 0.066, 1e-9);  // the dummy stamps frames 33 ms apart
}

}  // namespace
}  // namespace dynahand
