// Frames/intrinsics geometry and the recordings dynahand reads besides its own.
#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <fstream>

#include "dynahand/sequence.h"
#include "sensor/camera_json.h"
#include "test_support.h"

namespace dynahand {
namespace {

namespace fs = std::filesystem;

TEST(Intrinsics, PlaneAtHalfAMetreDeprojectsToZHalfEverywhere) {
  const Intrinsics k{320, 240, 238.4f, 238.4f, 157.7f, 123.0f};
  DepthFrame frame(320, 240, 0.000125f);
  std::fill(frame.depth.begin(), frame.depth.end(),
            std::uint16_t{4000});  // 4000 * 0.125 mm = 0.5 m
  for (int v = 0; v < frame.height; v += 7) {
    for (int u = 0; u < frame.width; u += 5) {
      const Vec3 p = frame.point(k, u, v);
      ASSERT_FLOAT_EQ(p.z(), 0.5f);
      const Vec2 back = k.project(p);  // and projects back to its pixel
      ASSERT_NEAR(back.x(), static_cast<float>(u), 1e-3f);
      ASSERT_NEAR(back.y(), static_cast<float>(v), 1e-3f);
    }
  }
  // The principal point looks straight ahead; x grows to the right, y downwards.
  EXPECT_NEAR(k.deproject(157.7f, 123.0f, 0.5f).head<2>().norm(), 0.0f, 1e-6f);
  EXPECT_GT(frame.point(k, 319, 120).x(), 0.0f);
  EXPECT_GT(frame.point(k, 160, 239).y(), 0.0f);
}

TEST(Intrinsics, ZeroDepthIsNoData) {
  const Intrinsics k{4, 4, 3.0f, 3.0f, 1.5f, 1.5f};
  const DepthFrame frame(4, 4, 0.001f);
  EXPECT_EQ(frame.metres(2, 2), 0.0f);
  EXPECT_EQ(frame.point(k, 2, 2), Vec3::Zero());
}

TEST(Intrinsics, ProblemNamesTheBadField) {
  EXPECT_TRUE(Intrinsics({640, 480, 500.0f, 500.0f, 320.0f, 240.0f}).valid());
  EXPECT_NE(Intrinsics({0, 480, 500.0f, 500.0f, 320.0f, 240.0f}).problem().find("size"),
            std::string::npos);
  EXPECT_NE(Intrinsics({640, 480, 500.0f, 0.0f, 320.0f, 240.0f}).problem().find("fy"),
            std::string::npos);
  EXPECT_NE(Intrinsics({640, 480, 500.0f, 500.0f, NAN, 240.0f}).problem().find("cx"),
            std::string::npos);
  EXPECT_FALSE(Intrinsics{}.valid());
}

void writeRaw(const fs::path& file, const std::vector<std::uint16_t>& values) {
  std::ofstream out(file, std::ios::binary);
  for (std::uint16_t v : values) {
    const char bytes[2] = {static_cast<char>(v & 0xff),
                           static_cast<char>(v >> 8)};  // little endian
    out.write(bytes, 2);
  }
}

TEST(IntelRaw, ReadsFramesBackToBack) {
  const fs::path dir = test::scratchDir("sensor-formats/intel");
  std::ofstream(dir / "rec.json")
      << R"({"camtype":"ivycam","dcamera":{"depth_scale":0.000124987,"dims":[4,3],"focal":[3.5,3.25],)"
      << R"("principal":[1.5,1.25]},"hasir":false})";
  std::vector<std::uint16_t> values(4 * 3 * 3);
  for (std::size_t i = 0; i < values.size(); ++i)
    values[i] = static_cast<std::uint16_t>(i * 1999 + 1);
  writeRaw(dir / "rec.rs", values);

  for (const fs::path& path : {dir / "rec.rs", dir / "rec.json", dir / "rec"}) {
    auto reader = SequenceReader::open(path);
    ASSERT_TRUE(reader) << path << ": " << reader.message();
    const SequenceInfo& info = reader->info();
    EXPECT_EQ(info.format, "intel-rs");
    EXPECT_EQ(info.frameCount, 3);
    EXPECT_EQ(info.intrinsics.width, 4);
    EXPECT_EQ(info.intrinsics.height, 3);
    EXPECT_FLOAT_EQ(info.intrinsics.fx, 3.5f);
    EXPECT_FLOAT_EQ(info.intrinsics.fy, 3.25f);
    EXPECT_FLOAT_EQ(info.intrinsics.cx, 1.5f);
    EXPECT_FLOAT_EQ(info.intrinsics.cy, 1.25f);
    EXPECT_FLOAT_EQ(info.depthScale, 0.000124987f);
    for (int f = 0; f < 3; ++f) {
      auto frame = reader->frame(f);
      ASSERT_TRUE(frame) << frame.message();
      const std::vector<std::uint16_t> expected(values.begin() + f * 12,
                                                values.begin() + (f + 1) * 12);
      EXPECT_EQ(frame->depth, expected) << "frame " << f;
      EXPECT_FLOAT_EQ(frame->depthScale, 0.000124987f);
    }
  }
}

TEST(IntelRaw, ReadsTheAuthorsCameraDescription) {
  DYNAHAND_REQUIRE_SHARED_DATA(data);
  const fs::path file = data / "intel" / "hand_data_example.json";
  std::ifstream in(file);
  std::stringstream text;
  text << in.rdbuf();
  auto camera = sensor::parseIntelCameraJson(text.str(), file.string());
  ASSERT_TRUE(camera) << camera.message();
  EXPECT_EQ(camera->intrinsics.width, 320);
  EXPECT_EQ(camera->intrinsics.height, 240);
  EXPECT_FLOAT_EQ(camera->intrinsics.fx, 238.434f);
  EXPECT_FLOAT_EQ(camera->intrinsics.fy, 238.433f);
  EXPECT_FLOAT_EQ(camera->intrinsics.cx, 157.717f);
  EXPECT_FLOAT_EQ(camera->intrinsics.cy, 123.03f);
  EXPECT_FLOAT_EQ(camera->depthScale, 0.000124987f);
  // Its depth frames were not released: opening the recording says which file is missing.
  auto reader = SequenceReader::open(file);
  ASSERT_FALSE(reader);
  EXPECT_NE(reader.message().find("hand_data_example.rs"), std::string::npos) << reader.message();
}

TEST(NyuPng, UnpacksGreenTimes256PlusBlue) {
  const fs::path dir = test::scratchDir("sensor-formats/nyu");
  cv::Mat packed(480, 640, CV_8UC3, cv::Scalar(0, 0, 0));
  packed.at<cv::Vec3b>(10, 20) =
      cv::Vec3b(0x34, 0x03, 0x77);  // OpenCV order B, G, R: 3 * 256 + 0x34 = 820 mm
  packed.at<cv::Vec3b>(479, 639) = cv::Vec3b(0xff, 0xff, 0x00);
  ASSERT_TRUE(cv::imwrite((dir / "depth_1_0000001.png").string(), packed));
  ASSERT_TRUE(cv::imwrite((dir / "depth_1_0000002.png").string(),
                          cv::Mat(480, 640, CV_8UC3, cv::Scalar(0, 2, 0))));

  auto reader = SequenceReader::open(dir);
  ASSERT_TRUE(reader) << reader.message();
  EXPECT_EQ(reader->info().format, "nyu-png");
  EXPECT_EQ(reader->frameCount(), 2);
  EXPECT_FLOAT_EQ(reader->info().intrinsics.fx, 588.036865f);  // NYU's Kinect
  auto first = reader->frame(0);
  ASSERT_TRUE(first) << first.message();
  EXPECT_EQ(first->at(20, 10), 820);
  EXPECT_EQ(first->at(639, 479), 65535);
  EXPECT_EQ(first->at(0, 0), 0);
  EXPECT_FLOAT_EQ(first->metres(20, 10), 0.82f);
  auto second = reader->frame(1);
  ASSERT_TRUE(second) << second.message();
  EXPECT_EQ(second->at(5, 5), 512);

  SequenceOpenOptions options;
  options.intrinsics = Intrinsics{640, 480, 500.0f, 501.0f, 319.5f, 239.5f};
  auto overridden = SequenceReader::open(dir, options);
  ASSERT_TRUE(overridden) << overridden.message();
  EXPECT_FLOAT_EQ(overridden->info().intrinsics.fy, 501.0f);
}

TEST(PlainPngFolder, NeedsIntrinsicsAndReadsInNaturalOrder) {
  const fs::path dir = test::scratchDir("sensor-formats/png16");
  for (int i : {1, 2, 10}) {
    ASSERT_TRUE(cv::imwrite((dir / ("frame" + std::to_string(i) + ".png")).string(),
                            cv::Mat(24, 32, CV_16UC1, cv::Scalar(i * 100))));
  }
  auto withoutIntrinsics = SequenceReader::open(dir);
  ASSERT_FALSE(withoutIntrinsics);
  EXPECT_NE(withoutIntrinsics.message().find("needs the camera intrinsics"), std::string::npos);
  EXPECT_NE(withoutIntrinsics.message().find(dir.string()), std::string::npos);

  SequenceOpenOptions options;
  options.intrinsics = Intrinsics{32, 24, 30.0f, 30.0f, 15.5f, 11.5f};
  options.depthScale = 0.0001f;
  auto reader = SequenceReader::open(dir, options);
  ASSERT_TRUE(reader) << reader.message();
  EXPECT_EQ(reader->info().format, "png16");
  EXPECT_EQ(reader->frameCount(), 3);
  const int expected[3] = {100, 200, 1000};  // frame1, frame2, frame10
  for (int f = 0; f < 3; ++f) {
    auto frame = reader->frame(f);
    ASSERT_TRUE(frame) << frame.message();
    EXPECT_EQ(frame->at(3, 3), expected[f]) << "frame " << f;
    EXPECT_FLOAT_EQ(frame->depthScale, 0.0001f);
  }

  options.intrinsics->width = 64;  // intrinsics for another image size
  auto mismatched = SequenceReader::open(dir, options);
  ASSERT_FALSE(mismatched);
  EXPECT_NE(mismatched.message().find("image is 32 x 24 but the intrinsics are for 64 x 24"),
            std::string::npos)
      << mismatched.message();
}

TEST(Oni, GarbageRecordingIsAnError) {
  const fs::path dir = test::scratchDir("sensor-formats/oni");
  std::ofstream(dir / "clip.oni") << "not an OpenNI recording";
  auto reader = SequenceReader::open(dir / "clip.oni");
  ASSERT_FALSE(reader);
  EXPECT_NE(reader.message().find((dir / "clip.oni").string()), std::string::npos)
      << reader.message();
}

TEST(Formats, ListsWhatThisBuildReads) {
  const auto formats = sequenceFormats();
  for (const char* f : {"canonical", "intel-rs", "nyu-png", "png16"}) {
    EXPECT_NE(std::find(formats.begin(), formats.end(), f), formats.end()) << f;
  }
}

}  // namespace
}  // namespace dynahand
