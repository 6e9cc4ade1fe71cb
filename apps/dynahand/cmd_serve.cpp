// dynahand serve: tracks an input and serves a live viewer page plus a WebSocket stream of
// the poses (docs/formats/viewer-stream.md) on localhost.
#include <chrono>
#include <cstdio>
#include <memory>
#include <thread>

#include "dynahand/command.h"
#include "dynahand/progress.h"
#include "serve_session.h"
#include "viewer_server.h"

namespace dynahand::cli {
namespace {

struct ServeCommandOptions {
  viewer::ServeOptions serve;
  viewer::ServerOptions server;
  std::string webRoot;
  bool fast = false;
  int stopAfter = 0;             // frames; 0 = until Ctrl-C
  std::vector<std::string> set;  // --set NAME=VALUE: the tracker's settings
};

int runServe(ServeCommandOptions o) {
  applyTrackerSettings(o.set, o.serve.settings);
  auto session = viewer::ServeSession::open(o.serve);
  if (!session) throw UsageError(session.message());
  o.server.webRoot = viewer::findViewerPage(o.webRoot);
  std::string error;
  auto server = viewer::ViewerServer::start(o.server, &error);
  if (!server) {
    std::fprintf(stderr, "dynahand serve: %s\n", error.c_str());
    // A --host that is no address is bad input; a port in use is not.
    return error.rfind("--host:", 0) == 0 ? kExitUsage : kExitFailure;
  }
  server->setWelcome({(*session)->hello()});
  viewer::printViewerAddress(o.server, *server, o.webRoot);
  std::printf("Ctrl-C stops\n");
  std::fflush(stdout);

  installInterruptHandler();
  using Clock = std::chrono::steady_clock;
  const bool paced = !o.fast && !(*session)->live();
  const auto period = std::chrono::duration_cast<Clock::duration>(
      std::chrono::duration<double>(1.0 / static_cast<double>((*session)->framesPerSecond())));
  auto due = Clock::now();
  bool paused = false;
  int steps = 0;
  while (!interrupted() && (o.stopAfter == 0 || (*session)->framesTracked() < o.stopAfter)) {
    for (const viewer::ClientCommand c : server->takeCommands()) {
      if (c == viewer::ClientCommand::Pause) paused = true;
      if (c == viewer::ClientCommand::Resume) paused = false;
      if (c == viewer::ClientCommand::Step) {
        paused = true;
        ++steps;
      }
    }
    if (paused && steps == 0) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      due = Clock::now();
      continue;
    }
    if (steps > 0) --steps;
    const Status s = (*session)->step(server.get(), paused);
    if (!s) {
      std::fprintf(stderr, "dynahand serve: %s\n", s.message().c_str());
      // A recording's frame that does not decode is bad input; a camera that stops is not.
      return (*session)->live() ? kExitFailure : kExitUsage;
    }
    if (paced) {
      due += period;
      const auto now = Clock::now();
      if (due > now) {
        std::this_thread::sleep_until(due);
      } else {
        due = now;  // behind: do not try to catch up with a burst
      }
    }
  }
  const viewer::ServerStats stats = server->stats();
  std::printf(
      "frames %d  sent %llu  dropped for slow clients %llu  rejected messages %llu  refused "
      "connections %llu\n",
      (*session)->framesTracked(), static_cast<unsigned long long>(stats.framesSent),
      static_cast<unsigned long long>(stats.framesDropped),
      static_cast<unsigned long long>(stats.messagesRejected),
      static_cast<unsigned long long>(stats.connectionsRefused));
  return interrupted() ? 130 : kExitOk;
}

const CommandRegistration kServeCommand{Command{
    "serve", "track an input and show it live in the browser (and stream the poses)",
    [](CLI::App& sub) -> std::function<int()> {
      auto o = std::make_shared<ServeCommandOptions>();
      sub.add_option("input", o->serve.input,
                     "synth:CLIP (a synthetic clip, see 'dynahand synth --list'), a recording "
                     "(looped), or camera[:SPEC]")
          ->required();
      sub.add_option("--port", o->server.port, "TCP port (0 = any free port)")
          ->check(CLI::Range(0, 65535));
      sub.add_option("--host", o->server.host,
                     "address to listen on (default 127.0.0.1: this machine only)");
      sub.add_option("--init", o->serve.init, "auto, or gt (ground truth at every loop start)")
          ->check(CLI::IsMember({"auto", "gt"}));
      sub.add_option("--synth-frames", o->serve.synthFrames, "synth: frames per loop")
          ->check(CLI::Range(2, 100000));
      sub.add_option("--profile", o->serve.synthProfile, "synth: sensor profile");
      sub.add_flag("!--no-cloud", o->serve.cloud, "do not send the point clouds");
      sub.add_flag("--fast", o->fast, "track as fast as possible instead of at the input's rate");
      sub.add_option("--stop-after", o->stopAfter, "stop after this many frames")
          ->check(CLI::Range(1, 100000000));
      sub.add_option("--max-client-queue", o->server.maxQueuedBytesPerClient,
                     "bytes waiting for one client before it skips frames")
          ->check(CLI::Range(std::size_t{1024}, std::size_t{1} << 30));
      sub.add_option("--web-root", o->webRoot, "serve the page from this folder instead");
      addTrackerSettingOption(sub, o->set);
      sub.footer(
          "Open the printed address in a browser. Other programs can read the stream: see\n"
          "docs/formats/viewer-stream.md and examples/python/dynahand_client.py. The stream\n"
          "opens only for the page's own origin or with the token printed at start\n"
          "(?token=...).\n"
          "Examples:\n"
          "  dynahand serve synth:wave\n"
          "  dynahand serve synth:pinch --init gt --port 9000\n"
          "  dynahand serve clip/ --host 0.0.0.0\n"
          "  dynahand serve camera:openni2");
      return [o] { return runServe(*o); };
    }}};

}  // namespace
}  // namespace dynahand::cli
