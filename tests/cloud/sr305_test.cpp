// The pipeline on real frames (Intel RealSense SR305, third-person view with torso and
// arm): the segmented cloud must be the hand, hand-sized, on every frame.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <vector>

#include "dynahand/cloud.h"
#include "test_support.h"

namespace dynahand {
namespace {

namespace fs = std::filesystem;

struct RealFrame {
  std::string name;
  DepthFrame frame;
};

struct RealSequence {
  Intrinsics k;
  std::vector<RealFrame> frames;
};

// Reads camera.json and depth/*.png with OpenCV (the canonical reader lives in the
// sensor module; this test only needs the pixels).
RealSequence readSequence(const fs::path& dir) {
  RealSequence seq;
  std::ifstream file(dir / "camera.json");
  const nlohmann::json camera = nlohmann::json::parse(file);
  seq.k.width = camera.at("width").get<int>();
  seq.k.height = camera.at("height").get<int>();
  seq.k.fx = camera.at("fx").get<float>();
  seq.k.fy = camera.at("fy").get<float>();
  seq.k.cx = camera.at("cx").get<float>();
  seq.k.cy = camera.at("cy").get<float>();
  const float scale = camera.at("depth_scale").get<float>();
  std::vector<fs::path> pngs;
  for (const auto& entry : fs::directory_iterator(dir / "depth")) pngs.push_back(entry.path());
  std::sort(pngs.begin(), pngs.end());
  for (const fs::path& png : pngs) {
    const cv::Mat image = cv::imread(png.string(), cv::IMREAD_UNCHANGED);
    EXPECT_EQ(image.type(), CV_16UC1) << png;
    EXPECT_EQ(image.cols, seq.k.width) << png;
    if (image.type() != CV_16UC1 || image.cols != seq.k.width || image.rows != seq.k.height) {
      continue;
    }
    DepthFrame frame(image.cols, image.rows, scale);
    for (int v = 0; v < image.rows; ++v) {
      std::copy_n(image.ptr<std::uint16_t>(v), image.cols, frame.depth.begin() + v * image.cols);
    }
    seq.frames.push_back({dir.filename().string() + "/" + png.filename().string(), frame});
  }
  return seq;
}

std::vector<RealSequence> readAll(const fs::path& data) {
  std::vector<RealSequence> all;
  for (const char* name : {"20210326-230536", "20210326-231615"}) {
    all.push_back(readSequence(data / "sr305-hands" / name));
  }
  return all;
}

TEST(CloudSr305, SegmentedCloudIsTheHandOnEveryFrame) {
  DYNAHAND_REQUIRE_SHARED_DATA(data);
  if (!fs::is_directory(data / "sr305-hands")) GTEST_SKIP() << "sr305-hands not present";
  int frames = 0;
  for (const RealSequence& seq : readAll(data)) {
    CloudPipeline pipeline(seq.k);
    CloudFrame out;
    const float radius = pipeline.config().segmentation.handRadiusM;
    for (const RealFrame& f : seq.frames) {
      SCOPED_TRACE(f.name);
      ASSERT_TRUE(pipeline.process(f.frame, out).ok());
      ASSERT_TRUE(out.segment.found);
      ++frames;
      // Extent: bounding box of the cloud.
      Vec3 lo = out.points.front();
      Vec3 hi = out.points.front();
      for (const Vec3& p : out.points) {
        lo = lo.cwiseMin(p);
        hi = hi.cwiseMax(p);
      }
      const Vec3 extent = hi - lo;
      // A hand (with at most a forearm stub) spans 0.08 - 0.36 m in its largest
      // dimension and never a torso (0.4+ m wide) — the radius cut makes 2 x 0.18 the
      // hard limit, so require clearly less in the image plane.
      EXPECT_GT(extent.head<2>().maxCoeff(), 0.08f);
      EXPECT_LT(extent.head<2>().maxCoeff(), 2.0f * radius);
      // Depth range of a hand: the torso behind it must not be included.
      EXPECT_LT(extent.z(), 0.2f);
      // Visible area of a hand plus a forearm stub: 0.004 - 0.04 m^2 (a torso disc cut at
      // the radius would be ~0.1 m^2).
      EXPECT_GT(out.segment.areaM2, 0.004f);
      EXPECT_LT(out.segment.areaM2, 0.04f);
      EXPECT_GT(out.pointCount(), 100u);
      EXPECT_EQ(out.droppedPoints, 0);
      // The filtered box holds the whole region: it was cut by the radius, not the box.
      const PixelBox& fb = out.filterBox;
      const PixelBox& sb = out.segmentBox;
      EXPECT_TRUE(sb.x0 > fb.x0 || fb.x0 == 0);
      EXPECT_TRUE(sb.y0 > fb.y0 || fb.y0 == 0);
      EXPECT_TRUE(sb.x1 < fb.x1 || fb.x1 == seq.k.width);
      EXPECT_TRUE(sb.y1 < fb.y1 || fb.y1 == seq.k.height);
      // The arm leaves the hand in every frame of these recordings.
      EXPECT_GT(out.segment.cutPixelCount, 0);
      // Every point is inside the boundary planes.
      for (const BoundaryPlane& plane : out.planes) {
        for (const Vec3& p : out.points) ASSERT_LE(plane.signedDistance(p), 1e-6f);
      }
      std::cout << f.name << ": " << out.pointCount() << " points, area " << out.segment.areaM2
                << " m^2, extent " << extent.transpose() << " m, nearest "
                << out.segment.nearestPoint.z() << " m, arm ("
                << out.segment.armDirectionImage.transpose() << "), " << out.planes.size()
                << " planes\n";
    }
  }
  EXPECT_EQ(frames, 19);
}

}  // namespace
}  // namespace dynahand
