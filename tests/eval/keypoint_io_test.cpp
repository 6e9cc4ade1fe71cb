#include <gtest/gtest.h>

#include <fstream>

#include "dynahand/keypoint_io.h"
#include "test_support.h"

namespace dynahand::eval {
namespace {

std::string keypointsJson(float x) {
  std::string s = "[";
  for (int j = 0; j < 21; ++j) {
    s += "[" + std::to_string(x) + "," + std::to_string(0.01 * j) + ",0.5]";
    s += j < 20 ? "," : "]";
  }
  return s;
}

std::filesystem::path writeFile(const std::string& name, const std::string& text) {
  const auto dir = test::scratchDir("keypoint_io");
  std::ofstream(dir / name) << text;
  return dir / name;
}

TEST(KeypointIo, ReadsGroundTruthWithNullFrames) {
  const auto path = writeFile("gt.jsonl", "{\"frame\":0,\"keypoints21\":" + keypointsJson(0.1f) +
                                              "}\n{\"frame\":1,\"keypoints21\":null}\n");
  auto seq = readKeypointsJsonl(path);
  ASSERT_TRUE(seq.ok()) << seq.message();
  ASSERT_EQ(seq->frames.size(), 2u);
  ASSERT_TRUE(seq->frames[0].has_value());
  EXPECT_FLOAT_EQ((*seq->frames[0])[20].y(), 0.2f);
  EXPECT_FALSE(seq->frames[1].has_value());
}

TEST(KeypointIo, ReadsTrackerOutputBySideAndTrackedFlag) {
  const std::string line0 =
      "{\"frame\":0,\"hands\":[{\"side\":\"left\",\"tracked\":true,"
      "\"keypoints21\":" +
      keypointsJson(-0.1f) +
      "},{\"side\":\"right\",\"tracked\":true,\"keypoints21\":" + keypointsJson(0.1f) + "}]}\n";
  const std::string line1 =
      "{\"frame\":1,\"hands\":[{\"side\":\"right\",\"tracked\":false,"
      "\"keypoints21\":" +
      keypointsJson(0.1f) + "}]}\n";
  const auto path = writeFile("pred.jsonl", line0 + line1);
  auto right = readKeypointsJsonl(path, "right");
  ASSERT_TRUE(right.ok()) << right.message();
  ASSERT_EQ(right->frames.size(), 2u);
  EXPECT_FLOAT_EQ((*right->frames[0])[0].x(), 0.1f);
  EXPECT_FALSE(right->frames[1].has_value());  // tracked:false = lost
  auto left = readKeypointsJsonl(path, "left");
  ASSERT_TRUE(left.ok());
  EXPECT_FLOAT_EQ((*left->frames[0])[0].x(), -0.1f);
}

TEST(KeypointIo, RefusesANewerTrackFormatVersion) {
  const auto path = writeFile("v2.jsonl",
                              "{\"version\":1,\"frame\":0,\"keypoints21\":null}\n"
                              "{\"version\":2,\"frame\":1,\"keypoints21\":null}\n");
  auto seq = readKeypointsJsonl(path);
  ASSERT_FALSE(seq.ok());
  EXPECT_NE(seq.message().find("v2.jsonl:2: \"version\" 2 is newer"), std::string::npos)
      << seq.message();
}

TEST(KeypointIo, ErrorsNameFileAndLine) {
  auto bad =
      readKeypointsJsonl(writeFile("bad.jsonl", "{\"frame\":0,\"keypoints21\":null}\nnot json\n"));
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.message().find("bad.jsonl:2: not a JSON object"), std::string::npos)
      << bad.message();
  auto shortK = readKeypointsJsonl(writeFile("short.jsonl", "{\"keypoints21\":[[0,0,0]]}\n"));
  ASSERT_FALSE(shortK.ok());
  EXPECT_NE(shortK.message().find("21"), std::string::npos);
  auto missing = readKeypointsJsonl("/nonexistent/file.jsonl");
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.message().find("/nonexistent/file.jsonl"), std::string::npos);
  auto empty = readKeypointsJsonl(writeFile("empty.jsonl", ""));
  ASSERT_FALSE(empty.ok());
}

// Found by fuzz/fuzz_track_jsonl.cpp: frame numbers up to 10 million were accepted, and
// frames are indexed, so this one line made eval allocate 2.5 GB; a frame number past the
// int range wrapped (4294967296 read as frame 0).
TEST(KeypointIo, FrameNumbersAreBounded) {
  auto huge =
      readKeypointsJsonl(writeFile("huge.jsonl", "{\"frame\":9999999,\"keypoints21\":null}\n"));
  ASSERT_FALSE(huge.ok());
  EXPECT_NE(huge.message().find("huge.jsonl:1: frame number out of range"), std::string::npos)
      << huge.message();
  for (const char* frame : {"4294967296", "18446744073709551615", "-1"}) {
    auto wide = readKeypointsJsonl(
        writeFile("wide.jsonl", std::string("{\"frame\":") + frame + ",\"keypoints21\":null}\n"));
    ASSERT_FALSE(wide.ok()) << frame;
    EXPECT_NE(wide.message().find("frame number out of range"), std::string::npos) << frame;
  }
  auto last =
      readKeypointsJsonl(writeFile("last.jsonl", "{\"frame\":999999,\"keypoints21\":null}\n"));
  ASSERT_TRUE(last.ok()) << last.message();
  EXPECT_EQ(last->frames.size(), 1'000'000u);
}

}  // namespace
}  // namespace dynahand::eval
