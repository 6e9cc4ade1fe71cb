// .pose output of TrackWriter and reading the JSON lines back (readTrackJsonl).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "dynahand/model_intel.h"
#include "dynahand/model_pose.h"
#include "dynahand/track_io.h"
#include "test_support.h"

namespace dynahand::io {
namespace {

track::TrackResult resultAt(const model::ArticulatedModel& hand, int frame, bool tracked) {
  model::JointAngles a = model::zeroAngles(hand);
  a.angles[3].x() = 0.3f + 0.05f * static_cast<float>(frame);
  model::clampToLimits(hand, a);
  a.root.p = Vec3(0.01f * static_cast<float>(frame), -0.02f, 0.4f);
  track::TrackResult r;
  r.frame = frame;
  track::HandResult h;
  h.tracked = tracked;
  h.pose = model::forwardKinematics(hand, a);
  h.keypoints21 = model::keypoints21(hand, h.pose);
  h.openxr26 = model::openxr26(hand, h.pose);
  h.simulation = track::StrategyKind::FingerFlip;
  h.error = 0.04f;
  track::Candidate c;
  c.kind = track::StrategyKind::Normal;
  c.ran = true;
  c.error = 0.06f;
  a.root.p.x() += 0.01f;
  c.pose = model::forwardKinematics(hand, a);
  h.candidates.push_back(c);
  r.hands.push_back(h);
  return r;
}

void expectSamePose(const model::ModelPose& a, const model::ModelPose& b, float tolerance) {
  ASSERT_EQ(a.bodies.size(), b.bodies.size());
  for (std::size_t i = 0; i < a.bodies.size(); ++i) {
    EXPECT_LT((a.bodies[i].p - b.bodies[i].p).norm(), tolerance) << "body " << i;
    EXPECT_GT(std::abs(a.bodies[i].q.dot(b.bodies[i].q)), 1.0f - tolerance) << "body " << i;
  }
}

// Until close() the frames go to PATH.part: a run that dies never leaves a partial file
// under the final name.
TEST(TrackWriter, WritesToAPartFileRenamedOnClose) {
  const auto hand = model::makeDefaultHand();
  const auto path = test::scratchDir("track_part") / "poses.jsonl";
  auto part = path;
  part += ".part";
  auto writer = TrackWriter::create(path, hand);
  ASSERT_TRUE(writer) << writer.message();
  ASSERT_TRUE((*writer)->write(resultAt(hand, 0, true)));
  EXPECT_TRUE(std::filesystem::exists(part));
  EXPECT_FALSE(std::filesystem::exists(path));
  ASSERT_TRUE((*writer)->close());
  EXPECT_FALSE(std::filesystem::exists(part));
  ASSERT_TRUE(std::filesystem::exists(path));
  EXPECT_TRUE((*writer)->close());  // once only
  const auto back = readTrackJsonl(path, hand);
  ASSERT_TRUE(back) << back.message();
  EXPECT_EQ(back->size(), 1u);
}

TEST(TrackWriter, PoseExtensionWritesOneLinePerFrameThatReadsBack) {
  const auto hand = model::makeDefaultHand();
  const auto path = test::scratchDir("track_pose") / "hand.pose";
  auto writer = TrackWriter::create(path, hand);
  ASSERT_TRUE(writer) << writer.message();
  EXPECT_EQ((*writer)->format(), TrackWriter::Format::IntelPose);
  // Lost at frames 0 and 3: frame 0 takes the first tracked pose, frame 3 repeats frame 2's.
  const bool tracked[] = {false, true, true, false, true};
  std::vector<track::TrackResult> results;
  for (int f = 0; f < 5; ++f) {
    results.push_back(resultAt(hand, f, tracked[f]));
    ASSERT_TRUE((*writer)->write(results.back()));
  }
  ASSERT_TRUE((*writer)->close());
  auto poses = model::loadIntelPoses(path, hand);
  ASSERT_TRUE(poses) << poses.message();
  ASSERT_EQ(poses->size(), 5u);
  expectSamePose((*poses)[0], results[1].hands[0].pose, 1e-5f);
  expectSamePose((*poses)[1], results[1].hands[0].pose, 1e-5f);
  expectSamePose((*poses)[2], results[2].hands[0].pose, 1e-5f);
  expectSamePose((*poses)[3], results[2].hands[0].pose, 1e-5f);
  expectSamePose((*poses)[4], results[4].hands[0].pose, 1e-5f);
}

TEST(TrackJsonRead, BodiesAndCandidatePosesReadBack) {
  const auto hand = model::makeDefaultHand();
  const auto path = test::scratchDir("track_read") / "poses.jsonl";
  JsonOptions o;
  o.candidates = true;
  o.candidatePoses = true;
  auto writer = TrackWriter::create(path, hand, o);
  ASSERT_TRUE(writer);
  const auto tracked = resultAt(hand, 2, true);
  ASSERT_TRUE((*writer)->write(tracked));
  ASSERT_TRUE((*writer)->write(resultAt(hand, 3, false)));
  ASSERT_TRUE((*writer)->close());
  auto frames = readTrackJsonl(path, hand);
  ASSERT_TRUE(frames) << frames.message();
  ASSERT_EQ(frames->size(), 2u);
  const TrackedFrame& f = (*frames)[0];
  EXPECT_EQ(f.frame, 2);
  ASSERT_EQ(f.hands.size(), 1u);
  EXPECT_TRUE(f.hands[0].tracked);
  EXPECT_EQ(f.hands[0].simulation, "finger_flip");
  expectSamePose(f.hands[0].pose, tracked.hands[0].pose, 1e-5f);
  ASSERT_EQ(f.hands[0].candidates.size(), 1u);
  EXPECT_EQ(f.hands[0].candidates[0].simulation, "normal");
  EXPECT_NEAR(f.hands[0].candidates[0].error, 0.06f, 1e-6f);
  expectSamePose(f.hands[0].candidates[0].pose, tracked.hands[0].candidates[0].pose, 1e-5f);
  EXPECT_FALSE((*frames)[1].hands[0].tracked);
  EXPECT_TRUE((*frames)[1].hands[0].pose.bodies.empty());
}

// "hand_size" in every line: the size the poses were tracked with, given or estimated.
TEST(TrackJsonRead, HandSizeReadsBack) {
  const auto hand = model::makeDefaultHand({0.17f, 0.078f});
  const auto dir = test::scratchDir("track_read_hand_size");
  HandSizeRecord estimated;
  estimated.dimensions = {0.17f, 0.078f};
  estimated.estimated = true;
  estimated.frames = 30;
  estimated.fitScore = 0.99f;
  for (const std::optional<HandSizeRecord>& record :
       {std::optional<HandSizeRecord>(estimated), std::optional<HandSizeRecord>(HandSizeRecord{}),
        std::optional<HandSizeRecord>()}) {
    JsonOptions o;
    o.handSize = record;
    const auto path = dir / "poses.jsonl";
    auto writer = TrackWriter::create(path, hand, o);
    ASSERT_TRUE(writer);
    ASSERT_TRUE((*writer)->write(resultAt(hand, 0, true)));
    ASSERT_TRUE((*writer)->close());
    auto frames = readTrackJsonl(path, hand);
    ASSERT_TRUE(frames) << frames.message();
    const auto& read = frames->front().handSize;
    ASSERT_EQ(read.has_value(), record.has_value());
    if (!record) continue;
    EXPECT_NEAR(read->dimensions.length, record->dimensions.length, 1e-6f);
    EXPECT_NEAR(read->dimensions.width, record->dimensions.width, 1e-6f);
    EXPECT_EQ(read->estimated, record->estimated);
    EXPECT_EQ(read->frames, record->frames);
    EXPECT_NEAR(read->fitScore, record->fitScore, 1e-6f);
  }
}

TEST(TrackJsonRead, ErrorsNameTheLine) {
  const auto hand = model::makeDefaultHand();
  const auto path = test::scratchDir("track_read_bad") / "poses.jsonl";
  std::ofstream(path)
      << "{\"frame\":0,\"hands\":[]}\n{\"frame\":1,\"hands\":[{\"tracked\":true}]}\n";
  auto frames = readTrackJsonl(path, hand);
  ASSERT_FALSE(frames);
  EXPECT_NE(frames.message().find("poses.jsonl:2:"), std::string::npos) << frames.message();
}

}  // namespace
}  // namespace dynahand::io
