// What `dynahand serve` does, as a library for the command and the benchmark: opens an
// input (a synthetic clip "synth:CLIP", a recording, or a live camera "camera:SPEC"),
// tracks it frame by frame (recordings loop), and publishes each frame to a ViewerServer
// when somebody is watching.
#pragma once

#include <filesystem>
#include <memory>
#include <string>

#include "dynahand/core.h"
#include "dynahand/tracker.h"
#include "viewer_messages.h"
#include "viewer_server.h"

namespace dynahand::viewer {

struct ServeOptions {
  std::string input;      // "synth:CLIP", a recording path, or "camera:SPEC"/"camera"
  int synthFrames = 150;  // frames per loop of a synthetic clip
  std::string synthProfile = "tof";
  std::string init = "auto";  // "auto" or "gt" (ground truth at every loop start)
  bool cloud = true;          // send the scene cloud and the tracker's sample points
  float handLength = 0.19f;   // the built-in hand, m
  float handWidth = 0.085f;
  track::TrackerSettings settings;
};

// The viewer page's folder for ServerOptions::webRoot: `webRoot` when given, else the
// installed copy beside the program (bin/../share/dynahand/viewer), else the build tree's;
// empty when there is none (the server then streams without its page).
std::filesystem::path findViewerPage(const std::string& webRoot = {});
// The line a command prints once its server listens: the page's and the stream's address
// with the run's token ("?token=..."), or why the page is unavailable (webRoot: what the
// user passed with --web-root, or empty).
void printViewerAddress(const ServerOptions& options, const ViewerServer& server,
                        const std::string& webRoot);

class ServeSession {
 public:
  // Opens the input and makes the tracker. Errors name what is wrong with the input.
  static Result<std::unique_ptr<ServeSession>> open(const ServeOptions& options);
  ~ServeSession();

  // The "hello" message (body shapes and stream facts) for ViewerServer::setWelcome.
  std::string hello() const;
  float framesPerSecond() const;  // of the source
  bool live() const;              // a camera: frames come at their own pace

  // Grabs, tracks and (when `server` has clients) publishes the next frame. Recordings and
  // clips wrap around to their first frame.
  Status step(ViewerServer* server, bool paused = false);
  // The last frame's result (nullptr before the first step); valid until the next step.
  const track::TrackResult* lastResult() const;
  int framesTracked() const;

 private:
  struct Impl;
  explicit ServeSession(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace dynahand::viewer
