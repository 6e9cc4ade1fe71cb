#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "dynahand/keypoint_io.h"
#include "dynahand/model_pose.h"
#include "dynahand/track_io.h"
#include "test_support.h"

namespace dynahand::io {
namespace {

track::TrackResult sampleResult(const model::ArticulatedModel& hand, int frame, bool tracked) {
  model::JointAngles a = model::zeroAngles(hand);
  model::clampToLimits(hand, a);
  a.root.p = Vec3(0.01f * frame, 0, 0.4f);
  track::TrackResult r;
  r.frame = frame;
  r.timeMs = 1.5;
  track::HandResult h;
  h.tracked = tracked;
  h.pose = model::forwardKinematics(hand, a);
  h.keypoints21 = model::keypoints21(hand, h.pose);
  h.openxr26 = model::openxr26(hand, h.pose);
  h.error = 0.05f;
  h.simulation = track::StrategyKind::GraspBias;
  track::Candidate c;
  c.kind = track::StrategyKind::Normal;
  c.ran = true;
  c.error = 0.07f;
  h.candidates.push_back(c);
  r.hands.push_back(h);
  return r;
}

TEST(TrackJson, HasTheDocumentedFields) {
  const auto hand = model::makeDefaultHand();
  const auto r = sampleResult(hand, 3, true);
  JsonOptions o;
  o.candidates = true;
  const auto j = nlohmann::json::parse(trackResultToJson(r, hand, o));
  EXPECT_EQ(j["version"], kTrackFormatVersion);
  EXPECT_EQ(j["frame"], 3);
  ASSERT_EQ(j["hands"].size(), 1u);
  const auto& h = j["hands"][0];
  EXPECT_EQ(h["side"], "right");
  EXPECT_EQ(h["tracked"], true);
  ASSERT_EQ(h["keypoints21"].size(), 21u);
  EXPECT_NEAR(h["keypoints21"][8][0].get<float>(), r.hands[0].keypoints21[8].x(), 1e-5f);
  ASSERT_EQ(h["openxr26"].size(), 26u);
  EXPECT_EQ(h["openxr26"][0]["q"].size(), 4u);
  EXPECT_GE(h["openxr26"][0]["q"][0].get<float>(), 0.0f);  // w first, non-negative
  ASSERT_EQ(h["bodies"].size(), 17u);
  EXPECT_EQ(h["bodies"][1]["name"], hand.bodies()[1].name);
  EXPECT_EQ(h["simulation"], "grasp_bias");
  EXPECT_NEAR(h["error"].get<float>(), 0.05f, 1e-6f);
  ASSERT_EQ(h["candidates"].size(), 1u);
  EXPECT_EQ(h["candidates"][0]["simulation"], "normal");
  EXPECT_FALSE(j.contains("hand_size"));  // only when the writer is told the size
}

// A tracker started at input frame 100 (dynahand track --start 100) numbers its frames from 0;
// the file numbers them as the input does.
TEST(TrackJson, FramesAreNumberedAsInTheInput) {
  const auto hand = model::makeDefaultHand();
  JsonOptions o;
  o.firstFrame = 100;
  const auto j = nlohmann::json::parse(trackResultToJson(sampleResult(hand, 3, true), hand, o));
  EXPECT_EQ(j["frame"], 103);
}

TEST(TrackJson, EstimatedHandSizeHasItsSourceFramesFitAndMetacarpals) {
  const auto hand = model::makeDefaultHand();
  JsonOptions o;
  o.handSize = HandSizeRecord{{0.17f, 0.078f}, true, 30, 0.99f, {1.05f, 0.95f, 1.0f, 1.0f, 0.9f}};
  const auto j = nlohmann::json::parse(trackResultToJson(sampleResult(hand, 0, true), hand, o));
  ASSERT_TRUE(j.contains("hand_size"));
  EXPECT_NEAR(j["hand_size"]["length"].get<float>(), 0.17f, 1e-6f);
  EXPECT_NEAR(j["hand_size"]["width"].get<float>(), 0.078f, 1e-6f);
  EXPECT_EQ(j["hand_size"]["source"], "estimated");
  EXPECT_EQ(j["hand_size"]["frames"], 30);
  EXPECT_NEAR(j["hand_size"]["fit"].get<float>(), 0.99f, 1e-6f);
  EXPECT_EQ(j["hand_size"]["metacarpals"], nlohmann::json::parse("[1.05, 0.95, 1, 1, 0.9]"));
  EXPECT_EQ(j["hands"].size(), 1u);
}

TEST(TrackJson, LostHandHasNullKeypoints) {
  const auto hand = model::makeDefaultHand();
  const auto j = nlohmann::json::parse(trackResultToJson(sampleResult(hand, 0, false), hand));
  EXPECT_EQ(j["hands"][0]["tracked"], false);
  EXPECT_TRUE(j["hands"][0]["keypoints21"].is_null());
  EXPECT_FALSE(j["hands"][0].contains("bodies"));
}

TEST(TrackWriter, JsonLinesReadBackByEvalAndCsvHasAColumnPerCoordinate) {
  const auto hand = model::makeDefaultHand();
  const auto dir = test::scratchDir("track_writer");
  auto jsonl = TrackWriter::create(dir / "poses.jsonl", hand);
  auto csv = TrackWriter::create(dir / "poses.csv", hand);
  ASSERT_TRUE(jsonl.ok() && csv.ok());
  for (int f = 0; f < 4; ++f) {
    const auto r = sampleResult(hand, f, f != 2);
    ASSERT_TRUE((*jsonl)->write(r).ok());
    ASSERT_TRUE((*csv)->write(r).ok());
  }
  ASSERT_TRUE((*jsonl)->close().ok());
  ASSERT_TRUE((*csv)->close().ok());
  auto back = eval::readKeypointsJsonl(dir / "poses.jsonl");
  ASSERT_TRUE(back.ok()) << back.message();
  ASSERT_EQ(back->frames.size(), 4u);
  EXPECT_TRUE(back->frames[0].has_value());
  EXPECT_FALSE(back->frames[2].has_value());
  EXPECT_NEAR((*back->frames[3])[0].x(), sampleResult(hand, 3, true).hands[0].keypoints21[0].x(),
              1e-5f);

  std::ifstream in(dir / "poses.csv");
  std::string header, line;
  std::getline(in, header);
  EXPECT_EQ(std::count(header.begin(), header.end(), ','), 6 + 63 - 1);
  int rows = 0;
  while (std::getline(in, line)) {
    ++rows;
    EXPECT_EQ(std::count(line.begin(), line.end(), ','), 6 + 63 - 1) << line;
  }
  EXPECT_EQ(rows, 4);
}

TEST(TrackWriter, RejectsUnknownExtension) {
  const auto hand = model::makeDefaultHand();
  auto w = TrackWriter::create(test::scratchDir("track_writer_bad") / "poses.txt", hand);
  ASSERT_FALSE(w.ok());
  EXPECT_NE(w.message().find(".txt"), std::string::npos);
}

// Found by fuzz/fuzz_track_jsonl.cpp (what render and play read back): a float or too large
// "frame" (or hand_size "frames") converted to int was undefined behaviour; a hand_size that is
// no number, or far from a hand's, crashed render building the default hand at that size;
// positions too large for a float came back infinite.
TEST(TrackRead, BadNumbersAreErrorsNamingLineAndField) {
  const auto hand = model::makeDefaultHand();
  const auto dir = test::scratchDir("track_read_bad");
  const std::string pose = R"({"name":"palm","p":[1e39,0,0.4],"q":[1,0,0,0]})";
  struct Case {
    std::string line, expected;
  };
  const Case cases[] = {
      {R"({"frame":1e30,"hands":[]})", "frame: 1e+30 is not a whole number"},
      {R"({"frame":2147483648,"hands":[]})", "frame: 2147483648 is not a whole number"},
      {R"({"frame":0,"hand_size":{"length":0.19,"width":0.08,"frames":1e20},"hands":[]})",
       "hand_size.frames: 1e+20 is not a whole number"},
      {R"({"version":2,"frame":0,"hands":[]})",
       "\"version\" 2 is newer than this dynahand understands (1)"},
      {R"({"frame":0,"hand_size":{"length":"x","width":0.08},"hands":[]})",
       "hand_size.length: \"x\" is not in [0.05, 0.6] m"},
      {R"({"frame":0,"hand_size":{"length":0.19,"width":1e-30},"hands":[]})",
       "hand_size.width: 1e-30 is not in [0.025, 0.26] m"},
      {R"({"frame":0,"hand_size":{"length":0.19,"width":0.08,"metacarpals":[1,1,1,1]},"hands":[]})",
       "hand_size.metacarpals: not an array of 5 numbers"},
      {R"({"frame":0,"hand_size":{"length":0.19,"width":0.08,"metacarpals":[1,1,9,1,1]},"hands":[]})",
       "hand_size.metacarpals[2]: 9 is not in [0.5, 1.5]"},
      {R"({"frame":0,"hand_size":{"length":0.19,"width":0.08,"metacarpals":[1,1,"x",1,1]},"hands":[]})",
       "hand_size.metacarpals[2]: \"x\" is not in [0.5, 1.5]"},
      {R"({"frame":0,"hands":[{"side":"right","tracked":false,"candidates":[{"simulation":"normal","error":0.1,"bodies":[)" +
           [&] {
             std::string bodies;
             for (std::size_t b = 0; b < hand.bodies().size(); ++b) bodies += (b ? "," : "") + pose;
             return bodies;
           }() +
           "]}]}]}",
       "expected [x, y, z] of finite numbers"},
  };
  for (const Case& c : cases) {
    std::ofstream(dir / "bad.jsonl") << c.line << "\n";
    const auto frames = readTrackJsonl(dir / "bad.jsonl", hand);
    ASSERT_FALSE(frames.ok()) << c.line;
    EXPECT_NE(frames.message().find("bad.jsonl:1: " + c.expected), std::string::npos)
        << frames.message() << " / expected " << c.expected;
  }
  // What the writer writes still reads back, hand size included.
  JsonOptions o;
  o.handSize = HandSizeRecord{{0.17f, 0.078f}, true, 30, 0.99f, {1.05f, 0.95f, 1.0f, 1.0f, 0.9f}};
  std::ofstream(dir / "good.jsonl")
      << trackResultToJson(sampleResult(hand, 5, true), hand, o) << "\n";
  const auto good = readTrackJsonl(dir / "good.jsonl", hand);
  ASSERT_TRUE(good.ok()) << good.message();
  EXPECT_EQ(good->front().frame, 5);
  ASSERT_TRUE(good->front().handSize.has_value());
  EXPECT_EQ(good->front().handSize->frames, 30);
  EXPECT_NEAR(good->front().handSize->dimensions.length, 0.17f, 1e-6f);
  EXPECT_EQ(good->front().handSize->metacarpals, o.handSize->metacarpals);
  EXPECT_EQ(good->front().handSize->shape().boneLength[4][0], 0.9f);
}

}  // namespace
}  // namespace dynahand::io
