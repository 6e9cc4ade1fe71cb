// The viewer stream's messages (docs/formats/viewer-stream.md) and the server's local
// behaviour; the stream end to end is viewer_stream_test.py, the page browser_test.mjs.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "dynahand/synth.h"
#include "dynahand/track_io.h"
#include "viewer_messages.h"
#include "viewer_server.h"

namespace dynahand::viewer {
namespace {

using nlohmann::json;

TEST(ViewerMessages, HelloCarriesEveryBodyHullWithValidFaces) {
  const model::ArticulatedModel hand = model::makeDefaultHand();
  HelloInfo info;
  info.source = "synth:\"quoted\"";
  info.intrinsics = {320, 240, 300.0f, 300.0f, 160.0f, 120.0f};
  info.models.push_back(&hand);
  const json j = json::parse(helloMessage(info));
  EXPECT_EQ(j["type"], "hello");
  EXPECT_EQ(j["version"], kStreamFormatVersion);
  EXPECT_EQ(j["source"], "synth:\"quoted\"");
  EXPECT_EQ(j["intrinsics"]["width"], 320);
  EXPECT_EQ(j["simulations"].size(), static_cast<std::size_t>(track::kStrategyCount));
  ASSERT_EQ(j["models"].size(), 1u);
  const json& bodies = j["models"][0]["bodies"];
  ASSERT_EQ(bodies.size(), hand.bodies().size());
  for (std::size_t b = 0; b < bodies.size(); ++b) {
    EXPECT_EQ(bodies[b]["name"], hand.bodies()[b].name);
    const std::size_t n = bodies[b]["vertices"].size();
    EXPECT_GE(n, 4u);
    EXPECT_GE(bodies[b]["faces"].size(), 4u);
    for (const json& face : bodies[b]["faces"]) {
      EXPECT_GE(face.size(), 3u);
      for (const json& index : face) EXPECT_LT(index.get<std::size_t>(), n);
    }
  }
}

TEST(ViewerMessages, FrameEmbedsTheTrackLineAndBoundedClouds) {
  synth::SynthOptions synthOptions;
  synthOptions.clip = "wave";
  synthOptions.frameCount = 2;
  auto seq = synth::SyntheticSequence::create(synthOptions);
  ASSERT_TRUE(seq) << seq.message();
  const synth::SyntheticFrame& f = seq->frame(0);
  track::TrackResult result;
  result.frame = 0;
  track::HandResult hand;
  hand.tracked = true;
  hand.pose = f.hands[0].pose;
  hand.keypoints21 = f.hands[0].keypoints;
  hand.candidates.push_back({track::StrategyKind::Normal, true, 0.01f, f.hands[0].pose});
  result.hands.push_back(hand);
  std::vector<Vec3> samples(5000, Vec3(0.0f, 0.0f, 0.5f));

  FrameInfo info;
  info.index = 7;
  info.result = &result;
  info.model = &seq->model(0);
  info.depth = &f.depth;
  info.intrinsics = &seq->intrinsics();
  info.samples = &samples;
  info.truth.push_back({model::Side::Right, f.hands[0].keypoints, f.hands[0].pose});
  const json j = json::parse(frameMessage(info));
  EXPECT_EQ(j["type"], "frame");
  EXPECT_EQ(j["index"], 7);
  io::JsonOptions options;
  options.candidates = true;
  options.candidatePoses = true;
  EXPECT_EQ(j["track"], json::parse(io::trackResultToJson(result, seq->model(0), options)));
  EXPECT_EQ(j["track"]["hands"][0]["candidates"][0]["bodies"].size(),
            f.hands[0].pose.bodies.size());
  const std::size_t cloud = j["cloud"].size();
  EXPECT_EQ(cloud % 3, 0u);
  EXPECT_GT(cloud, 300u);  // the hand and arm are in view
  EXPECT_LE(cloud / 3, static_cast<std::size_t>(info.maxCloudPoints));
  EXPECT_LE(j["samples"].size() / 3, static_cast<std::size_t>(info.maxSamplePoints));
  EXPECT_EQ(j["truth"][0]["keypoints21"].size(), 21u);
  EXPECT_EQ(j["truth"][0]["bodies"].size(), f.hands[0].pose.bodies.size());
}

TEST(ViewerMessages, SceneAndPosesForThePlayground) {
  const physics::ConvexShape box = physics::ConvexShape::box({0.1f, 0.2f, 0.3f});
  const json scene =
      json::parse(sceneMessage({{"crate", &box, "#aa8844"}, {"floor", &box, ""}}, "z"));
  EXPECT_EQ(scene["type"], "scene");
  EXPECT_EQ(scene["up"], "z");
  ASSERT_EQ(scene["bodies"].size(), 2u);
  EXPECT_EQ(scene["bodies"][0]["color"], "#aa8844");
  EXPECT_FALSE(scene["bodies"][1].contains("color"));
  EXPECT_EQ(scene["bodies"][0]["vertices"].size(), 8u);
  EXPECT_EQ(scene["bodies"][0]["faces"].size(), 6u);

  Pose moved;
  moved.p = Vec3(1.0f, 2.0f, 3.0f);
  const json poses = json::parse(scenePosesMessage(12, 0.2, {moved, Pose::identity()}));
  EXPECT_EQ(poses["type"], "scene_poses");
  EXPECT_EQ(poses["step"], 12);
  ASSERT_EQ(poses["poses"].size(), 2u);
  EXPECT_FLOAT_EQ(poses["poses"][0]["p"][2].get<float>(), 3.0f);
  EXPECT_FLOAT_EQ(poses["poses"][1]["q"][0].get<float>(), 1.0f);
}

TEST(ViewerServer, PublishWithoutClientsSendsNothing) {
  ServerOptions options;
  options.port = 0;
  std::string error;
  auto server = ViewerServer::start(options, &error);
  ASSERT_TRUE(server) << error;
  EXPECT_GT(server->port(), 0);
  EXPECT_FALSE(server->pageAvailable());
  EXPECT_FALSE(server->hasClients());
  server->publish("{\"type\":\"frame\"}");
  const ServerStats stats = server->stats();
  EXPECT_EQ(stats.framesPublished, 1u);
  EXPECT_EQ(stats.framesSent, 0u);
  EXPECT_TRUE(server->takeCommands().empty());
}

TEST(ViewerServer, ReportsAPortInUseAndABadHost) {
  ServerOptions options;
  options.port = 0;
  std::string error;
  auto first = ViewerServer::start(options, &error);
  ASSERT_TRUE(first) << error;
  options.port = first->port();
  EXPECT_FALSE(ViewerServer::start(options, &error));
  EXPECT_NE(error.find(std::to_string(options.port)), std::string::npos) << error;
  options.port = 0;
  options.host = "not-an-address";
  EXPECT_FALSE(ViewerServer::start(options, &error));
  EXPECT_NE(error.find("--host"), std::string::npos) << error;
}

}  // namespace
}  // namespace dynahand::viewer
