// The soak benchmark behind `dynahand bench --suite soak`: tracks an input frame after frame
// on one thread for a given time, looping it, exactly as `dynahand track` does (or, with
// `serve`, through `dynahand serve`'s ServeSession with one WebSocket client connected and
// reading every message), and tells whether the process's resident memory and the frame
// time stay flat: resident memory at the end at most 5 % above the value after the warm-up, p99
// frame time of the last window at most 10 % above the first window's.
//
// Time line of a run of T seconds: a warm-up of W = min(60 s, T / 10); the first window
// [W, W + L] and the last window [T - L, T] with L = min(300 s, max(W, T / 10)). Only the
// two windows' frame times are kept (no growth from the measurement itself); resident
// memory (VmRSS of /proc/self/status) is sampled once a second.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "dynahand/core.h"

namespace dynahand::cli::soak {

struct SoakOptions {
  double seconds = 3600.0;
  // Track: "synth:CLIP[,CLIP...]" (clips rendered on the fly with the synthesiser, each
  // `clipFrames` frames, played one after the other, round and round) or a recording path
  // (read frame by frame as `dynahand track` reads it, looped). Serve: what `dynahand
  // serve` takes ("synth:CLIP" or a recording).
  std::string input = "synth:wave,open-close,pinch";
  std::string profile = "tof";  // sensor profile of synth: inputs
  int clipFrames = 300;         // frames per synthetic clip
  bool serve = false;           // through ServeSession with one connected client
  bool paced = false;           // serve: at the input's frame rate (default as fast as it can)
  bool detector = true;         // false: without the learned detector (--no-detector)
  std::function<bool()> stop;   // polled every frame: true ends the run early (Ctrl-C)
};

// Frame times of one window.
struct SoakWindow {
  double fromS = 0.0, toS = 0.0;  // planned span, s since the start
  int frames = 0;
  double p50Ms = 0.0, p99Ms = 0.0;        // wall time per frame
  double cpuP50Ms = 0.0, cpuP99Ms = 0.0;  // that thread's CPU time per frame
};

struct SoakReport {
  std::string mode;   // "track" or "serve"
  std::string input;  // as given, with the profile and frames per clip for synth: inputs
  std::string timed;  // what a frame time covers
  double plannedS = 0.0, elapsedS = 0.0, warmUpS = 0.0;
  bool interrupted = false;
  long long frames = 0, trackedFrames = 0;
  SoakWindow first, last;
  double rssStartMb = 0.0;          // after setting up, before the first frame
  double rssWarmMb = 0.0;           // at the end of the warm-up
  double rssEndMb = 0.0;            // after the last frame
  double rssPeakMb = 0.0;           // largest sample
  double rssHwmMb = 0.0;            // VmHWM: the kernel's high-water mark over the whole process
  std::vector<double> rssAtTenths;  // at 0 %, 10 %, ..., 100 % of the run (MB)
  // serve: the stream as the server and the client saw it.
  // publish() calls, frames queued to the client, frames it skipped when behind (a frame
  // superseded by a newer one before the server's thread took it is neither).
  unsigned long long framesPublished = 0, framesSent = 0, framesDropped = 0;
  unsigned long long framesReceived = 0, messagesReceived = 0;  // by the client
  double megabytesReceived = 0.0;
  int clientsAtEnd = 0;

  static constexpr double kRssTolerance = 0.05;  // the criteria
  static constexpr double kP99Tolerance = 0.10;
  double rssChange() const;     // (end - warm) / warm
  double p99Change() const;     // (last - first) / first, wall time
  double cpuP99Change() const;  // the same for CPU time (a loaded machine moves it less)
  bool rssOk() const;
  bool p99Ok() const;
  // Both windows hold frames and do not overlap (a run stopped early may not get there).
  bool measured() const;
  bool pass() const { return measured() && rssOk() && p99Ok(); }
};

// Runs the soak; progress lines go to stdout every 10 % of the time. Errors: a bad input.
Result<SoakReport> runSoak(const SoakOptions& options);

// The report as a plain-text table (ends with the PASS/FAIL line) and as a Markdown section
// ("## Soak: track" ...) for `--markdown`.
std::string soakText(const SoakReport& report);
std::string soakMarkdown(const SoakReport& report);

}  // namespace dynahand::cli::soak
