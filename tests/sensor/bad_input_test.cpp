// Bad input: every case gives an Error naming the file and the problem, never a crash.
#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <fstream>

#include "dynahand/sequence.h"
#include "test_support.h"

namespace dynahand {
namespace {

namespace fs = std::filesystem;

const Intrinsics kIntrinsics{64, 48, 60.0f, 60.0f, 31.5f, 23.5f};

// A canonical sequence of `frames` frames with a gradient, in a fresh folder.
fs::path writeSequence(const std::string& name, int frames = 2) {
  const fs::path seq = test::scratchDir("sensor-bad/" + name) / "seq";
  auto writer = SequenceWriter::create(seq, kIntrinsics, 0.001f);
  EXPECT_TRUE(writer) << writer.message();
  for (int i = 0; i < frames; ++i) {
    DepthFrame frame(kIntrinsics.width, kIntrinsics.height, 0.001f);
    for (std::size_t p = 0; p < frame.depth.size(); ++p)
      frame.depth[p] = static_cast<std::uint16_t>(400 + p % 300);
    EXPECT_TRUE(writer->write(frame));
  }
  return seq;
}

void writeText(const fs::path& file, const std::string& text) {
  std::ofstream out(file, std::ios::trunc);
  out << text;
}

// The error names the file and says what is wrong.
void expectError(const std::string& message, const fs::path& file, const std::string& problem) {
  EXPECT_NE(message.find(file.string()), std::string::npos) << "file not named: " << message;
  EXPECT_NE(message.find(problem), std::string::npos) << "problem not stated: " << message;
}

std::string openError(const fs::path& path) {
  auto reader = SequenceReader::open(path);
  EXPECT_FALSE(reader) << path << " opened although it is bad";
  return reader ? std::string{} : reader.message();
}

std::string frameError(const fs::path& seq, int index) {
  auto reader = SequenceReader::open(seq);
  EXPECT_TRUE(reader) << reader.message();
  if (!reader) return {};
  auto frame = reader->frame(index);
  EXPECT_FALSE(frame) << "frame " << index << " decoded although it is bad";
  return frame ? std::string{} : frame.message();
}

TEST(BadInput, MissingSequenceFolder) {
  const fs::path seq = test::scratchDir("sensor-bad/nofolder") / "does-not-exist";
  expectError(openError(seq), seq, "not found");
}

TEST(BadInput, MissingPngInTheMiddle) {
  const fs::path seq = writeSequence("missing-png", 3);
  fs::remove(seq / "depth" / "000001.png");
  expectError(openError(seq), seq / "depth" / "000001.png", "missing");
}

TEST(BadInput, PngRemovedAfterOpening) {
  const fs::path seq = writeSequence("removed-png", 2);
  auto reader = SequenceReader::open(seq);
  ASSERT_TRUE(reader) << reader.message();
  fs::remove(seq / "depth" / "000001.png");
  auto frame = reader->frame(1);
  ASSERT_FALSE(frame);
  expectError(frame.message(), seq / "depth" / "000001.png", "file not found");
}

TEST(BadInput, TruncatedPngData) {
  const fs::path seq = writeSequence("truncated-png");
  const fs::path png = seq / "depth" / "000000.png";
  fs::resize_file(png, fs::file_size(png) / 2);
  expectError(frameError(seq, 0), png, "truncated or corrupt");
}

TEST(BadInput, TruncatedPngHeader) {
  const fs::path seq = writeSequence("truncated-header");
  const fs::path png = seq / "depth" / "000000.png";
  fs::resize_file(png, 20);
  expectError(frameError(seq, 0), png, "truncated (header incomplete)");
}

TEST(BadInput, EmptyPngFile) {
  const fs::path seq = writeSequence("empty-png");
  const fs::path png = seq / "depth" / "000000.png";
  fs::resize_file(png, 0);
  expectError(frameError(seq, 0), png, "file is empty");
}

TEST(BadInput, NotAPng) {
  const fs::path seq = writeSequence("not-png");
  const fs::path png = seq / "depth" / "000000.png";
  writeText(png, "this is text, not an image");
  expectError(frameError(seq, 0), png, "not a PNG file");
}

TEST(BadInput, EightBitPngWhereSixteenBitIsExpected) {
  const fs::path seq = writeSequence("8bit");
  const fs::path png = seq / "depth" / "000000.png";
  ASSERT_TRUE(cv::imwrite(png.string(), cv::Mat(48, 64, CV_8UC1, cv::Scalar(100))));
  expectError(frameError(seq, 0), png, "PNG is 8-bit grey; a depth image must be 16-bit grey");
}

TEST(BadInput, RgbPngWhereSixteenBitIsExpected) {
  const fs::path seq = writeSequence("rgb");
  const fs::path png = seq / "depth" / "000000.png";
  ASSERT_TRUE(cv::imwrite(png.string(), cv::Mat(48, 64, CV_8UC3, cv::Scalar(1, 2, 3))));
  expectError(frameError(seq, 0), png, "PNG is 8-bit RGB; a depth image must be 16-bit grey");
}

TEST(BadInput, SixteenBitRgbPng) {
  const fs::path seq = writeSequence("rgb16");
  const fs::path png = seq / "depth" / "000000.png";
  ASSERT_TRUE(cv::imwrite(png.string(), cv::Mat(48, 64, CV_16UC3, cv::Scalar(1, 2, 3))));
  expectError(frameError(seq, 0), png, "PNG is 16-bit RGB");
}

TEST(BadInput, PngSizeDiffersFromCameraJson) {
  const fs::path seq = writeSequence("size-mismatch");
  const fs::path png = seq / "depth" / "000001.png";
  ASSERT_TRUE(cv::imwrite(png.string(), cv::Mat(24, 32, CV_16UC1, cv::Scalar(500))));
  expectError(frameError(seq, 1), png, "image is 32 x 24 but the camera description says 64 x 48");
}

TEST(BadInput, NonNumericIntrinsic) {
  const fs::path seq = writeSequence("non-numeric");
  writeText(
      seq / "camera.json",
      R"({"width":64,"height":48,"fx":"sixty","fy":60,"cx":31.5,"cy":23.5,"depth_scale":0.001})");
  expectError(openError(seq), seq / "camera.json",
              "\"fx\" is not a number (found string \"sixty\")");
}

TEST(BadInput, MissingIntrinsic) {
  const fs::path seq = writeSequence("missing-key");
  writeText(seq / "camera.json",
            R"({"width":64,"height":48,"fx":60,"cx":31.5,"cy":23.5,"depth_scale":0.001})");
  expectError(openError(seq), seq / "camera.json", "missing \"fy\"");
}

TEST(BadInput, NegativeFocalLength) {
  const fs::path seq = writeSequence("negative-fx");
  writeText(seq / "camera.json",
            R"({"width":64,"height":48,"fx":-60,"fy":60,"cx":31.5,"cy":23.5,"depth_scale":0.001})");
  expectError(openError(seq), seq / "camera.json", "bad intrinsics: fx");
}

TEST(BadInput, FractionalWidth) {
  const fs::path seq = writeSequence("fractional-width");
  writeText(
      seq / "camera.json",
      R"({"width":64.5,"height":48,"fx":60,"fy":60,"cx":31.5,"cy":23.5,"depth_scale":0.001})");
  expectError(openError(seq), seq / "camera.json", "\"width\" must be a whole number of pixels");
}

TEST(BadInput, ZeroDepthScale) {
  const fs::path seq = writeSequence("zero-scale");
  writeText(seq / "camera.json",
            R"({"width":64,"height":48,"fx":60,"fy":60,"cx":31.5,"cy":23.5,"depth_scale":0})");
  expectError(openError(seq), seq / "camera.json", "\"depth_scale\" must be in (0, 1]");
}

TEST(BadInput, NegativeNearRange) {
  const fs::path seq = writeSequence("negative-near-range");
  writeText(seq / "camera.json",
            R"({"width":64,"height":48,"fx":60,"fy":60,"cx":31.5,"cy":23.5,"depth_scale":0.001,)"
            R"("min_range_m":-0.2})");
  expectError(openError(seq), seq / "camera.json", "\"min_range_m\" must be in [0, 100]");
}

TEST(BadInput, CameraJsonNotJson) {
  const fs::path seq = writeSequence("not-json");
  writeText(seq / "camera.json", "{\"width\":64,");
  expectError(openError(seq), seq / "camera.json", "not valid JSON");
}

TEST(BadInput, CameraJsonMissing) {
  const fs::path seq = writeSequence("no-camera-json");
  fs::remove(seq / "camera.json");
  // Without camera.json the folder is no sequence: depth/ is a subfolder, not PNGs.
  expectError(openError(seq), seq, "no camera.json and no PNG files");
}

TEST(BadInput, CameraJsonFromTheFuture) {
  const fs::path seq = writeSequence("future-version");
  writeText(
      seq / "camera.json",
      R"({"version":99,"width":64,"height":48,"fx":60,"fy":60,"cx":31.5,"cy":23.5,"depth_scale":0.001})");
  expectError(openError(seq), seq / "camera.json", "format version 99 is newer");
}

TEST(BadInput, UnexpectedFileInDepthFolder) {
  const fs::path seq = writeSequence("stray-file");
  writeText(seq / "depth" / "notes.txt", "hello");
  expectError(openError(seq), seq / "depth" / "notes.txt", "unexpected file in depth/");
}

TEST(BadInput, GroundTruthLineWithTooFewKeypoints) {
  const fs::path seq = writeSequence("gt-short");
  writeText(seq / "groundtruth.jsonl",
            "{\"frame\":0,\"keypoints21\":null}\n{\"frame\":1,\"keypoints21\":[[0,0,1]]}\n");
  expectError(openError(seq), seq / "groundtruth.jsonl",
              "line 2: \"keypoints21\" must be null or an array of 21");
}

TEST(BadInput, GroundTruthPastTheLastFrame) {
  const fs::path seq = writeSequence("gt-past-end");
  writeText(seq / "groundtruth.jsonl", "{\"frame\":5,\"keypoints21\":null}\n");
  expectError(openError(seq), seq / "groundtruth.jsonl", "frame 5 is past the last frame");
}

TEST(BadInput, AllZeroFrameIsValid) {
  const fs::path seq = test::scratchDir("sensor-bad/zeros") / "seq";
  {
    auto writer = SequenceWriter::create(seq, kIntrinsics, 0.001f);
    ASSERT_TRUE(writer) << writer.message();
    ASSERT_TRUE(writer->write(DepthFrame(kIntrinsics.width, kIntrinsics.height, 0.001f)));
  }
  auto reader = SequenceReader::open(seq);
  ASSERT_TRUE(reader) << reader.message();
  auto frame = reader->frame(0);
  ASSERT_TRUE(frame) << frame.message();
  ASSERT_EQ(frame->depth.size(), static_cast<std::size_t>(64 * 48));
  for (std::uint16_t d : frame->depth) ASSERT_EQ(d, 0);  // "no hand", not an error
}

TEST(BadInput, RawRecordingSizeNotAMultipleOfTheFrameSize) {
  const fs::path dir = test::scratchDir("sensor-bad/rs-size");
  writeText(
      dir / "rec.json",
      R"({"dcamera":{"depth_scale":0.000125,"dims":[8,6],"focal":[5,5],"principal":[3.5,2.5]}})");
  std::ofstream(dir / "rec.rs", std::ios::binary) << std::string(8 * 6 * 2 * 3 + 5, '\1');
  expectError(openError(dir / "rec.rs"), dir / "rec.rs",
              "size 293 bytes is not a multiple of the frame size 8 x 6 x 2 = 96 bytes");
}

TEST(BadInput, RawRecordingWithoutItsJson) {
  const fs::path dir = test::scratchDir("sensor-bad/rs-nojson");
  std::ofstream(dir / "rec.rs", std::ios::binary) << std::string(96, '\1');
  expectError(openError(dir / "rec.rs"), dir / "rec.json", "file not found");
}

TEST(BadInput, RawRecordingJsonWithoutDcamera) {
  const fs::path dir = test::scratchDir("sensor-bad/rs-nodcamera");
  writeText(dir / "rec.json", R"({"camtype":"ivycam"})");
  std::ofstream(dir / "rec.rs", std::ios::binary) << std::string(96, '\1');
  expectError(openError(dir / "rec.rs"), dir / "rec.json", "missing \"dcamera\"");
}

TEST(BadInput, UnrecognisedPath) {
  const fs::path dir = test::scratchDir("sensor-bad/unknown");
  writeText(dir / "clip.mp4", "x");
  expectError(openError(dir / "clip.mp4"), dir / "clip.mp4", "unrecognised recording");
}

}  // namespace
}  // namespace dynahand
