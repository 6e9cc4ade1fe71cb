// The viewer stream's messages (docs/formats/viewer-stream.md) and the server's local
// behaviour (who may open the WebSocket included); the stream end to end is
// viewer_stream_test.py, the page browser_test.mjs.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>
#include <nlohmann/json.hpp>

#include <cctype>
#include <chrono>
#include <thread>

#include "dynahand/synth.h"
#include "dynahand/track_io.h"
#include "viewer_client_input.h"
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

// One WebSocket opening handshake by hand (the RFC 6455 sample key): what the server answers
// and whether it then closes the connection.
struct Handshake {
  std::string status;   // the response's first line, e.g. "HTTP/1.1 101 Switching Protocols"
  bool closed = false;  // the server closed the connection after its answer
};

Handshake handshake(const std::string& address, int port, const std::string& target,
                    const std::string& origin) {
  Handshake result;
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  if (fd < 0) return result;
  timeval timeout{5, 0};
  ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof timeout);
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_port = htons(static_cast<std::uint16_t>(port));
  ::inet_pton(AF_INET, address.c_str(), &to.sin_addr);
  if (::connect(fd, reinterpret_cast<const sockaddr*>(&to), sizeof to) != 0) {
    ::close(fd);
    return result;
  }
  std::string request =
      "GET " + target + " HTTP/1.1\r\nHost: " + address + ":" + std::to_string(port) +
      "\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
      "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n";
  if (!origin.empty()) request += "Origin: " + origin + "\r\n";
  request += "\r\n";
  if (::send(fd, request.data(), request.size(), 0) != static_cast<ssize_t>(request.size())) {
    ::close(fd);
    return result;
  }
  std::string answer;
  char buffer[4096];
  for (;;) {
    const ssize_t n = ::recv(fd, buffer, sizeof buffer, 0);
    if (n <= 0) {
      result.closed = n == 0;
      break;
    }
    answer.append(buffer, static_cast<std::size_t>(n));
    // A 101 keeps the connection open: stop at the end of its head.
    if (answer.rfind("HTTP/1.1 101", 0) == 0 && answer.find("\r\n\r\n") != std::string::npos) {
      break;
    }
  }
  result.status = answer.substr(0, answer.find("\r\n"));
  ::close(fd);
  return result;
}

bool accepted(const Handshake& h) {
  return h.status.rfind("HTTP/1.1 101", 0) == 0;
}
bool forbidden(const Handshake& h) {
  return h.status.rfind("HTTP/1.1 403", 0) == 0 && h.closed;
}

std::unique_ptr<ViewerServer> startOnAnyPort(const std::string& host = "127.0.0.1") {
  ServerOptions options;
  options.host = host;
  options.port = 0;
  std::string error;
  auto server = ViewerServer::start(options, &error);
  EXPECT_TRUE(server) << error;
  return server;
}

TEST(ViewerServer, TokenIs128RandomBitsInHex) {
  auto first = startOnAnyPort();
  auto second = startOnAnyPort();
  ASSERT_TRUE(first && second);
  EXPECT_EQ(first->token().size(), 32u);
  for (const char c : first->token()) EXPECT_TRUE(std::isxdigit(static_cast<unsigned char>(c)));
  EXPECT_NE(first->token(), second->token());
}

TEST(ViewerServer, RefusesAWebSocketFromAnotherOrigin) {
  auto server = startOnAnyPort();
  ASSERT_TRUE(server);
  const int port = server->port();
  const std::string own = std::to_string(port);
  for (const std::string& origin :
       {std::string("http://evil.example.com"), "http://evil.example.com:" + own,
        std::string("http://127.0.0.1:1"), "https://127.0.0.1:" + own,
        "http://127.0.0.1:" + own + ".evil.example.com", std::string("null")}) {
    const Handshake h = handshake("127.0.0.1", port, "/", origin);
    EXPECT_TRUE(forbidden(h)) << origin << ": " << h.status;
    EXPECT_FALSE(accepted(h)) << origin;
  }
  EXPECT_FALSE(server->hasClients());
  EXPECT_EQ(server->stats().connectionsRefused, 6u);
}

TEST(ViewerServer, AcceptsThePagesOwnOrigin) {
  auto server = startOnAnyPort();
  ASSERT_TRUE(server);
  const std::string own = std::to_string(server->port());
  for (const std::string& origin : {"http://127.0.0.1:" + own, "http://localhost:" + own}) {
    const Handshake h = handshake("127.0.0.1", server->port(), "/", origin);
    EXPECT_TRUE(accepted(h)) << origin << ": " << h.status;
  }
  EXPECT_EQ(server->stats().connectionsRefused, 0u);
}

TEST(ViewerServer, AcceptsTheOriginOfTheHostItWasGiven) {
  ServerOptions options;
  options.host = "127.0.0.2";  // Linux answers on all of 127/8
  options.port = 0;
  std::string error;
  auto server = ViewerServer::start(options, &error);
  if (!server) GTEST_SKIP() << "cannot listen on 127.0.0.2: " << error;
  const std::string own = std::to_string(server->port());
  EXPECT_TRUE(accepted(handshake("127.0.0.2", server->port(), "/", "http://127.0.0.2:" + own)));
  EXPECT_TRUE(accepted(handshake("127.0.0.2", server->port(), "/", "http://127.0.0.1:" + own)));
  EXPECT_TRUE(forbidden(handshake("127.0.0.2", server->port(), "/", "http://127.0.0.3:" + own)));
}

TEST(ViewerServer, ClientsWithoutTheOriginNeedTheToken) {
  auto server = startOnAnyPort();
  ASSERT_TRUE(server);
  const int port = server->port();
  const std::string token = server->token();
  std::string wrong = token;
  wrong[0] = wrong[0] == '0' ? '1' : '0';
  EXPECT_TRUE(forbidden(handshake("127.0.0.1", port, "/", "")));
  EXPECT_TRUE(forbidden(handshake("127.0.0.1", port, "/?token=", "")));
  EXPECT_TRUE(forbidden(handshake("127.0.0.1", port, "/?token=" + wrong, "")));
  EXPECT_TRUE(forbidden(handshake("127.0.0.1", port, "/?token=" + token + "0", "")));
  EXPECT_TRUE(
      forbidden(handshake("127.0.0.1", port, "/?token=" + wrong, "http://evil.example.com")));
  EXPECT_EQ(server->stats().connectionsRefused, 5u);
  EXPECT_TRUE(accepted(handshake("127.0.0.1", port, "/?token=" + token, "")));
  EXPECT_TRUE(accepted(handshake("127.0.0.1", port, "/?x=1&token=" + token, "")));
  // The token lets a page served elsewhere in (what the page's own ?token= is for).
  EXPECT_TRUE(
      accepted(handshake("127.0.0.1", port, "/?token=" + token, "http://evil.example.com")));
  EXPECT_EQ(server->stats().connectionsRefused, 5u);
}

TEST(ViewerServer, AnAcceptedClientIsCounted) {
  auto server = startOnAnyPort();
  ASSERT_TRUE(server);
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_port = htons(static_cast<std::uint16_t>(server->port()));
  to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(::connect(fd, reinterpret_cast<const sockaddr*>(&to), sizeof to), 0);
  const std::string request =
      "GET /?token=" + server->token() +
      " HTTP/1.1\r\nHost: 127.0.0.1\r\nUpgrade: websocket\r\n"
      "Connection: Upgrade\r\nSec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n"
      "Sec-WebSocket-Version: 13\r\n\r\n";
  ASSERT_EQ(::send(fd, request.data(), request.size(), 0), static_cast<ssize_t>(request.size()));
  for (int i = 0; i < 200 && !server->hasClients(); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_TRUE(server->hasClients());
  ::close(fd);
}

// What clients send, parsed apart from the network (also fuzz/fuzz_viewer_messages.cpp).
TEST(ViewerClientInput, CommandsAreAcceptedAndEverythingElseRefused) {
  const ClientMessage step = parseClientMessage(R"({"type":"control","action":"step"})");
  EXPECT_TRUE(step.ok);
  EXPECT_EQ(step.command, ClientCommand::Step);
  EXPECT_EQ(parseClientMessage(R"({"action":"resume","type":"control"})").command,
            ClientCommand::Resume);
  const ClientMessage malformed = parseClientMessage("{\"type\":");
  EXPECT_FALSE(malformed.ok);
  EXPECT_TRUE(malformed.close);
  EXPECT_FALSE(parseClientMessage("[1]").ok);
  for (const char* unknown : {R"({"type":"hello"})", R"({"type":"control","action":"rewind"})",
                              R"({"type":"control","action":1})"}) {
    const ClientMessage m = parseClientMessage(unknown);
    EXPECT_FALSE(m.ok) << unknown;
    EXPECT_FALSE(m.close) << unknown;
    EXPECT_FALSE(m.refusal.empty()) << unknown;
  }
  EXPECT_EQ(queryToken("/?x=1&token=abc&y"), "abc");
  EXPECT_EQ(queryToken("/token=abc"), "");
  EXPECT_TRUE(safeResource("assets/viewer.js"));
  for (const char* unsafe : {"", "/etc/passwd", "../x", "a/../../b", "a%2e%2e", "a\\b"})
    EXPECT_FALSE(safeResource(unsafe)) << unsafe;
}

}  // namespace
}  // namespace dynahand::viewer
