// What a connected viewer costs the tracking loop of `dynahand serve`: frames per second of
// ServeSession::step (render a synthetic frame, track it, and - when a client is connected -
// build the frame message and hand it to the server) with no client and with one client that
// reads everything, over loopback. Target: with one viewer >= 90% of the frames per second
// without (docs/performance.md).
#include <arpa/inet.h>
#include <benchmark/benchmark.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <thread>

#include "serve_session.h"
#include "viewer_server.h"

namespace dynahand::viewer {
namespace {

// A viewer that reads and discards everything (a browser tab that keeps up).
class DrainingClient {
 public:
  DrainingClient(int port, const std::string& token) {
    fd_ = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_port = htons(static_cast<std::uint16_t>(port));
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (::connect(fd_, reinterpret_cast<const sockaddr*>(&address), sizeof address) != 0) return;
    // The RFC 6455 sample key; the client never needs to check the server's answer here.
    // Not the page, so it presents the server's token.
    const std::string request =
        "GET /?token=" + token +
        " HTTP/1.1\r\nHost: 127.0.0.1\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
        "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n";
    if (::send(fd_, request.data(), request.size(), 0) != static_cast<ssize_t>(request.size())) {
      return;
    }
    reader_ = std::thread([this] {
      char buffer[1 << 16];
      pollfd p{fd_, POLLIN, 0};
      while (!stop_) {
        if (::poll(&p, 1, 50) <= 0) continue;
        const ssize_t n = ::recv(fd_, buffer, sizeof buffer, 0);
        if (n <= 0) break;
        bytes_ += static_cast<std::uint64_t>(n);
      }
    });
  }
  ~DrainingClient() {
    stop_ = true;
    if (reader_.joinable()) reader_.join();
    ::close(fd_);
  }
  std::uint64_t bytes() const { return bytes_; }

 private:
  int fd_ = -1;
  std::atomic<bool> stop_{false};
  std::atomic<std::uint64_t> bytes_{0};
  std::thread reader_;
};

void BM_TrackAndServe(benchmark::State& state) {
  const bool withViewer = state.range(0) == 1;
  ServeOptions options;
  options.input = "synth:wave";
  options.synthFrames = 300;
  options.init = "gt";
  auto session = ServeSession::open(options);
  if (!session) {
    state.SkipWithError(session.message().c_str());
    return;
  }
  ServerOptions serverOptions;
  serverOptions.port = 0;
  std::string error;
  auto server = ViewerServer::start(serverOptions, &error);
  if (!server) {
    state.SkipWithError(error.c_str());
    return;
  }
  server->setWelcome({(*session)->hello()});
  std::unique_ptr<DrainingClient> client;
  if (withViewer) {
    client = std::make_unique<DrainingClient>(server->port(), server->token());
    for (int i = 0; i < 200 && !server->hasClients(); ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    if (!server->hasClients()) {
      state.SkipWithError("the viewer did not connect");
      return;
    }
  }
  for (int i = 0; i < 5; ++i) (void)(*session)->step(server.get());  // acquire, warm caches
  for (auto _ : state) {
    const Status s = (*session)->step(server.get());
    if (!s) state.SkipWithError(s.message().c_str());
  }
  state.counters["fps"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
  const ServerStats stats = server->stats();
  state.counters["sent"] = static_cast<double>(stats.framesSent);
  state.counters["dropped"] = static_cast<double>(stats.framesDropped);
  if (client) state.counters["MB_read"] = static_cast<double>(client->bytes()) / 1e6;
}
// Interleaved repetitions so both cases see the same machine load.
BENCHMARK(BM_TrackAndServe)
    ->ArgName("viewers")
    ->Arg(0)
    ->Arg(1)
    ->Iterations(150)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace dynahand::viewer
