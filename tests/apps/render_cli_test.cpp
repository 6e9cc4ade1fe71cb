// dynahand render through the command: a short synthetic clip tracked with --candidates,
// drawn to PNG frames, an MP4 and a contact sheet; the winner's model must be drawn where
// the hand is and nowhere far from it.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#ifdef DYNAHAND_HAVE_VIDEOIO
#include <opencv2/videoio.hpp>
#endif

#include "dynahand/keypoint_io.h"
#include "dynahand/model.h"
#include "dynahand/model_intel.h"
#include "dynahand/sequence.h"
#include "dynahand/track_io.h"
#include "test_support.h"

namespace dynahand {
namespace {

constexpr int kFrames = 10;

int run(const std::string& arguments) {
  const std::string command = std::string(DYNAHAND_CLI) + " " + arguments + " > /dev/null";
  return std::system(command.c_str());
}

// The winner is drawn in magenta, a colour the turbo depth map never produces: red and
// blue both high, green well below them.
bool isModelColour(const cv::Vec3b& bgr) {
  const int b = bgr[0], g = bgr[1], r = bgr[2];
  return r > 140 && b > 140 && g + 30 < std::min(r, b);
}

class RenderCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    // One folder per test process: CTest runs these tests in parallel processes.
    dir_ = new std::filesystem::path(
        test::scratchDir("render_cli_" + std::to_string(static_cast<long>(::getpid()))));
    const std::string d = dir_->string();
    ASSERT_EQ(run("synth --motion pinch --profile tof --frames " + std::to_string(kFrames) +
                  " --out " + d + "/clip"),
              0);
    ASSERT_EQ(run("track " + d + "/clip --init gt --candidates --out " + d + "/poses.jsonl"), 0);
  }
  static void TearDownTestSuite() { delete dir_; }
  static std::filesystem::path* dir_;
};
std::filesystem::path* RenderCli::dir_ = nullptr;

TEST_F(RenderCli, CandidatePosesAreWrittenWithTheFlag) {
  auto frames = io::readTrackJsonl(*dir_ / "poses.jsonl", model::makeDefaultHand());
  ASSERT_TRUE(frames) << frames.message();
  ASSERT_EQ(frames->size(), static_cast<std::size_t>(kFrames));
  const auto& hand = frames->back().hands.at(0);
  ASSERT_GE(hand.candidates.size(), 2u);
  for (const auto& c : hand.candidates) EXPECT_EQ(c.pose.bodies.size(), 17u) << c.simulation;
}

TEST_F(RenderCli, PngFramesShowTheModelWhereTheHandIs) {
  const auto out = *dir_ / "frames";
  ASSERT_EQ(run("render " + (*dir_ / "poses.jsonl").string() + " " + (*dir_ / "clip").string() +
                " --out " + out.string() + " --sheet " + (*dir_ / "sheet.png").string() +
                " --sheet-tiles 4"),
            0);
  auto reader = SequenceReader::open(*dir_ / "clip");
  ASSERT_TRUE(reader) << reader.message();
  const Intrinsics& k = reader->info().intrinsics;
  const auto hand = model::makeDefaultHand();
  auto truth = model::loadPoseSequence(*dir_ / "clip" / "poses.jsonl");
  ASSERT_TRUE(truth) << truth.message();
  int pngs = 0;
  for (const auto& e : std::filesystem::directory_iterator(out))
    pngs += e.path().extension() == ".png";
  EXPECT_EQ(pngs, kFrames);
  for (int f : {0, kFrames / 2, kFrames - 1}) {
    char name[32];
    std::snprintf(name, sizeof name, "frame_%06d.png", f);
    const cv::Mat image = cv::imread((out / name).string());
    ASSERT_FALSE(image.empty()) << name;
    ASSERT_EQ(image.cols, 2 * k.width);  // depth view | side view
    ASSERT_EQ(image.rows, k.height);
    // Where the hand is: the true model's bodies (the clip's poses.jsonl) projected.
    ASSERT_LT(static_cast<std::size_t>(f), truth->frames.size());
    int x0 = k.width, y0 = k.height, x1 = 0, y1 = 0;
    for (int b = 0; b < hand.bodyCount(); ++b) {
      const Pose& pose =
          truth->frames[static_cast<std::size_t>(f)].bodies[static_cast<std::size_t>(b)];
      for (const Vec3& v : hand.bodies()[static_cast<std::size_t>(b)].shape.vertices()) {
        const Vec3 p = pose.transform(v);
        if (p.z() <= 0) continue;
        const Vec2 uv = k.project(p);
        x0 = std::min(x0, static_cast<int>(uv.x()));
        y0 = std::min(y0, static_cast<int>(uv.y()));
        x1 = std::max(x1, static_cast<int>(uv.x()));
        y1 = std::max(y1, static_cast<int>(uv.y()));
      }
    }
    const int margin = 6;  // pixels: the tracked model is within a few mm of the truth
    int inside = 0, outside = 0, side = 0;
    for (int y = 0; y < image.rows; ++y) {
      for (int x = 0; x < image.cols; ++x) {
        if (!isModelColour(image.at<cv::Vec3b>(y, x))) continue;
        if (x >= k.width) {
          ++side;
        } else if (x >= x0 - margin && x <= x1 + margin && y >= y0 - margin && y <= y1 + margin) {
          ++inside;
        } else {
          ++outside;
        }
      }
    }
    EXPECT_GT(inside, 200) << name;
    EXPECT_LT(outside, inside / 50 + 1) << name << ": model pixels away from the hand";
    EXPECT_GT(side, 100) << name;
  }
  const cv::Mat sheet = cv::imread((*dir_ / "sheet.png").string());
  ASSERT_FALSE(sheet.empty());
  EXPECT_EQ(sheet.cols, 4 * 480);  // 4 tiles of (240 depth + 240 side) in one row
  EXPECT_EQ(sheet.rows, 240);
}

TEST_F(RenderCli, Mp4HasEveryFrame) {
#ifndef DYNAHAND_HAVE_VIDEOIO
  GTEST_SKIP() << "built without OpenCV videoio (libopencv-videoio-dev)";
#else
  const auto video = *dir_ / "tracked.mp4";
  ASSERT_EQ(run("render " + (*dir_ / "poses.jsonl").string() + " " + (*dir_ / "clip").string() +
                " --out " + video.string()),
            0);
  ASSERT_TRUE(std::filesystem::exists(video));
  EXPECT_GT(std::filesystem::file_size(video), 1000u);
  cv::VideoCapture capture(video.string());
  ASSERT_TRUE(capture.isOpened());
  int frames = 0;
  cv::Mat image;
  while (capture.read(image)) {
    EXPECT_EQ(image.cols, 640);
    EXPECT_EQ(image.rows, 240);
    ++frames;
  }
  EXPECT_EQ(frames, kFrames);
#endif
}

TEST(TrackCli, PoseOutputMatchesTheJsonLines) {
  const auto dir = test::scratchDir("track_pose_cli");
  const std::string d = dir.string();
  ASSERT_EQ(run("synth --motion wave --profile tof --frames 4 --out " + d + "/clip"), 0);
  ASSERT_EQ(run("track " + d + "/clip --init gt --out " + d + "/poses.jsonl"), 0);
  ASSERT_EQ(run("track " + d + "/clip --init gt --out " + d + "/hand.pose"), 0);
  const auto hand = model::makeDefaultHand();
  auto json = io::readTrackJsonl(dir / "poses.jsonl", hand);
  ASSERT_TRUE(json) << json.message();
  auto pose = model::loadIntelPoses(dir / "hand.pose", hand);
  ASSERT_TRUE(pose) << pose.message();
  ASSERT_EQ(pose->size(), json->size());
  for (std::size_t f = 0; f < pose->size(); ++f) {
    const auto& expected = (*json)[f].hands.at(0).pose;
    ASSERT_EQ(expected.bodies.size(), (*pose)[f].bodies.size());
    for (std::size_t b = 0; b < expected.bodies.size(); ++b) {
      // The JSON lines keep 6 significant digits; tracking is deterministic.
      EXPECT_LT((expected.bodies[b].p - (*pose)[f].bodies[b].p).norm(), 1e-5f);
    }
  }
}

}  // namespace
}  // namespace dynahand
