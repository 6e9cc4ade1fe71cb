// Canonical sequence format: write then read gives identical data; real SR305 data.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "dynahand/sequence.h"
#include "test_support.h"

namespace dynahand {
namespace {

namespace fs = std::filesystem;

const Intrinsics kIntrinsics{64, 48, 57.25f, 57.5f, 31.75f, 23.5f};

DepthFrame rampFrame(int seed, float scale = 0.000125f) {
  DepthFrame frame(kIntrinsics.width, kIntrinsics.height, scale);
  for (int v = 0; v < frame.height; ++v) {
    for (int u = 0; u < frame.width; ++u) {
      // Covers the full uint16 range including 0 (no data) and 65535.
      frame.at(u, v) = static_cast<std::uint16_t>((u * 1031 + v * 7919 + seed * 104729) % 65536);
    }
  }
  return frame;
}

std::string readText(const fs::path& file) {
  std::ifstream in(file);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

Keypoints21 someKeypoints(int seed) {
  Keypoints21 k;
  for (int i = 0; i < 21; ++i) {
    k[static_cast<std::size_t>(i)] =
        Vec3(0.01f * i - 0.1f, 0.003f * seed - 0.02f * i, 0.4f + 0.001f * i / 3.0f);
  }
  return k;
}

TEST(SequenceFormat, WriteThenReadGivesIdenticalData) {
  const fs::path dir = test::scratchDir("sensor/roundtrip");
  const fs::path seq = dir / "seq";
  {
    auto writer = SequenceWriter::create(seq, kIntrinsics, 0.000125f, 15.0f);
    ASSERT_TRUE(writer) << writer.message();
    for (int i = 0; i < 4; ++i) {
      std::optional<Keypoints21> truth;
      if (i != 2) truth = someKeypoints(i);  // frame 2: no hand
      ASSERT_TRUE(writer->write(rampFrame(i), i == 0 ? std::nullopt : truth));
    }
    EXPECT_EQ(writer->framesWritten(), 4);
    ASSERT_TRUE(writer->close());
  }
  auto reader = SequenceReader::open(seq);
  ASSERT_TRUE(reader) << reader.message();
  const SequenceInfo& info = reader->info();
  EXPECT_EQ(info.format, "canonical");
  EXPECT_EQ(info.frameCount, 4);
  EXPECT_TRUE(info.hasGroundTruth);
  EXPECT_EQ(info.depthScale, 0.000125f);
  EXPECT_EQ(info.framesPerSecond, 15.0f);
  EXPECT_EQ(info.intrinsics.width, kIntrinsics.width);
  EXPECT_EQ(info.intrinsics.height, kIntrinsics.height);
  EXPECT_EQ(info.intrinsics.fx, kIntrinsics.fx);
  EXPECT_EQ(info.intrinsics.fy, kIntrinsics.fy);
  EXPECT_EQ(info.intrinsics.cx, kIntrinsics.cx);
  EXPECT_EQ(info.intrinsics.cy, kIntrinsics.cy);
  for (int i = 0; i < 4; ++i) {
    auto frame = reader->frame(i);
    ASSERT_TRUE(frame) << frame.message();
    EXPECT_EQ(frame->depth, rampFrame(i).depth) << "frame " << i;
    EXPECT_EQ(frame->depthScale, 0.000125f);
    EXPECT_DOUBLE_EQ(frame->timestamp, i / 15.0);
    const auto truth = reader->groundTruth(i);
    if (i == 0 || i == 2) {
      EXPECT_FALSE(truth.has_value()) << "frame " << i;
    } else {
      ASSERT_TRUE(truth.has_value()) << "frame " << i;
      for (int k = 0; k < 21; ++k) {
        EXPECT_EQ((*truth)[static_cast<std::size_t>(k)],
                  someKeypoints(i)[static_cast<std::size_t>(k)]);
      }
    }
  }
  EXPECT_FALSE(reader->groundTruth(4).has_value());
  auto outOfRange = reader->frame(4);
  ASSERT_FALSE(outOfRange);
  EXPECT_NE(outOfRange.message().find("out of range"), std::string::npos);
}

TEST(SequenceFormat, CameraJsonHasTheAgreedKeys) {
  const fs::path seq = test::scratchDir("sensor/keys") / "seq";
  auto writer = SequenceWriter::create(seq, kIntrinsics, 0.001f);
  ASSERT_TRUE(writer) << writer.message();
  const std::string text = readText(seq / "camera.json");
  for (const char* key :
       {"\"width\":64", "\"height\":48", "\"fx\":57.25", "\"fy\":57.5", "\"cx\":31.75",
        "\"cy\":23.5", "\"depth_scale\":0.001", "\"version\":1"}) {
    EXPECT_NE(text.find(key), std::string::npos) << key << " in " << text;
  }
}

// The camera's near range is optional: written and read back when given, absent (0) when not,
// refused when negative.
TEST(SequenceFormat, NearRangeRoundTripsThroughCameraJson) {
  const fs::path dir = test::scratchDir("sensor/nearrange");
  {
    auto writer = SequenceWriter::create(dir / "with", kIntrinsics, 0.001f, 30.0f, 0.5f);
    ASSERT_TRUE(writer) << writer.message();
    ASSERT_TRUE(writer->write(rampFrame(0, 0.001f)));
    auto without = SequenceWriter::create(dir / "without", kIntrinsics, 0.001f);
    ASSERT_TRUE(without) << without.message();
    ASSERT_TRUE(without->write(rampFrame(0, 0.001f)));
  }
  EXPECT_NE(readText(dir / "with" / "camera.json").find("\"min_range_m\":0.5"), std::string::npos);
  EXPECT_EQ(readText(dir / "without" / "camera.json").find("min_range_m"), std::string::npos);
  auto with = SequenceReader::open(dir / "with");
  ASSERT_TRUE(with) << with.message();
  EXPECT_EQ(with->info().minRangeM, 0.5f);
  auto without = SequenceReader::open(dir / "without");
  ASSERT_TRUE(without) << without.message();
  EXPECT_EQ(without->info().minRangeM, 0.0f);
  auto negative = SequenceWriter::create(dir / "negative", kIntrinsics, 0.001f, 30.0f, -0.1f);
  ASSERT_FALSE(negative);
  EXPECT_NE(negative.message().find("near range"), std::string::npos) << negative.message();
}

TEST(SequenceFormat, NoGroundTruthFileWhenNoneGiven) {
  const fs::path seq = test::scratchDir("sensor/nogt") / "seq";
  {
    auto writer = SequenceWriter::create(seq, kIntrinsics, 0.001f);
    ASSERT_TRUE(writer) << writer.message();
    ASSERT_TRUE(writer->write(rampFrame(0, 0.001f)));
  }  // destructor closes
  EXPECT_FALSE(fs::exists(seq / "groundtruth.jsonl"));
  auto reader = SequenceReader::open(seq);
  ASSERT_TRUE(reader) << reader.message();
  EXPECT_FALSE(reader->info().hasGroundTruth);
  EXPECT_EQ(reader->frameCount(), 1);
  EXPECT_FALSE(reader->groundTruth(0).has_value());
}

TEST(SequenceFormat, OpenedThroughItsCameraJson) {
  const fs::path seq = test::scratchDir("sensor/viajson") / "seq";
  {
    auto writer = SequenceWriter::create(seq, kIntrinsics, 0.001f);
    ASSERT_TRUE(writer) << writer.message();
    ASSERT_TRUE(writer->write(rampFrame(3, 0.001f)));
  }
  auto reader = SequenceReader::open(seq / "camera.json");
  ASSERT_TRUE(reader) << reader.message();
  EXPECT_EQ(reader->frameCount(), 1);
}

TEST(SequenceWriterErrors, RefusesAnExistingSequence) {
  const fs::path seq = test::scratchDir("sensor/exists") / "seq";
  ASSERT_TRUE(SequenceWriter::create(seq, kIntrinsics, 0.001f));
  auto again = SequenceWriter::create(seq, kIntrinsics, 0.001f);
  ASSERT_FALSE(again);
  EXPECT_NE(again.message().find("already holds a sequence"), std::string::npos) << again.message();
}

TEST(SequenceWriterErrors, RefusesAFrameOfAnotherSizeOrScale) {
  const fs::path seq = test::scratchDir("sensor/wrongframe") / "seq";
  auto writer = SequenceWriter::create(seq, kIntrinsics, 0.001f);
  ASSERT_TRUE(writer) << writer.message();
  auto wrongSize = writer->write(DepthFrame(32, 24, 0.001f));
  ASSERT_FALSE(wrongSize);
  EXPECT_NE(wrongSize.message().find("32 x 24"), std::string::npos) << wrongSize.message();
  auto wrongScale = writer->write(rampFrame(0, 0.0001f));
  ASSERT_FALSE(wrongScale);
  EXPECT_NE(wrongScale.message().find("depth scale"), std::string::npos) << wrongScale.message();
  EXPECT_EQ(writer->framesWritten(), 0);
}

TEST(SequenceWriterErrors, RefusesBadIntrinsics) {
  Intrinsics bad = kIntrinsics;
  bad.fx = -1.0f;
  auto writer = SequenceWriter::create(test::scratchDir("sensor/badk") / "seq", bad, 0.001f);
  ASSERT_FALSE(writer);
  EXPECT_NE(writer.message().find("fx"), std::string::npos) << writer.message();
}

// --- real data: Intel RealSense SR305 frames in the canonical layout ---------------

void expectSr305Folder(const fs::path& dir, int frames) {
  auto reader = SequenceReader::open(dir);
  ASSERT_TRUE(reader) << reader.message();
  const SequenceInfo& info = reader->info();
  EXPECT_EQ(info.format, "canonical");
  EXPECT_EQ(info.frameCount, frames);
  EXPECT_EQ(info.intrinsics.width, 640);
  EXPECT_EQ(info.intrinsics.height, 480);
  EXPECT_NEAR(info.intrinsics.fx, 476.007f, 1e-3f);
  EXPECT_NEAR(info.intrinsics.cy, 242.755f, 1e-3f);
  EXPECT_FLOAT_EQ(info.depthScale, 0.000125f);
  EXPECT_FALSE(info.hasGroundTruth);
  for (int i = 0; i < frames; ++i) {
    auto frame = reader->frame(i);
    ASSERT_TRUE(frame) << frame.message();
    ASSERT_EQ(frame->width, 640);
    ASSERT_EQ(frame->height, 480);
    int valid = 0;
    float nearest = 1e9f;
    float farthest = 0.0f;
    for (std::uint16_t d : frame->depth) {
      if (d == 0) continue;
      ++valid;
      const float z = d * frame->depthScale;
      nearest = std::min(nearest, z);
      farthest = std::max(farthest, z);
    }
    // A person at arm's length from a short-range camera (max range 1.5 m).
    EXPECT_GT(valid, 640 * 480 / 10) << "frame " << i;
    EXPECT_GT(nearest, 0.1f) << "frame " << i;
    EXPECT_LT(nearest, 0.8f) << "frame " << i;
    EXPECT_LT(farthest, 8.2f) << "frame " << i;
  }
}

TEST(Sr305Data, OpenPalmFolderHas8Frames) {
  DYNAHAND_REQUIRE_SHARED_DATA(data);
  expectSr305Folder(data / "sr305-hands" / "20210326-230536", 8);
}

TEST(Sr305Data, HandShapesFolderHas11Frames) {
  DYNAHAND_REQUIRE_SHARED_DATA(data);
  expectSr305Folder(data / "sr305-hands" / "20210326-231615", 11);
}

}  // namespace
}  // namespace dynahand
