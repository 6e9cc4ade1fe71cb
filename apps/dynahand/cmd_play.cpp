// dynahand play: runs a playground scene (docs/playground.md) driven by a tracked recording
// or a pose file, writing every scene body's pose per frame and optional rendered frames,
// and with --serve showing it live in the viewer page ("scene" + "scene_poses" messages).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <thread>

#include "dynahand/atomic_file.h"
#include "dynahand/command.h"
#include "dynahand/model_pose.h"
#include "dynahand/playground.h"
#include "dynahand/playground_io.h"
#include "dynahand/progress.h"
#include "dynahand/sequence.h"
#include "dynahand/tracker.h"
#include "serve_session.h"
#include "viewer_messages.h"
#include "viewer_server.h"

namespace dynahand::cli {
namespace {

struct PlayOptions {
  std::string scene, input, out, framesDir, init = "auto";
  HandModelOptions hand;  // built-in hand only (the virtual hand is built from it)
  float fps = 30.0f;
  int frames = -1, renderEvery = 1;
  std::vector<float> eye, target;
  // --serve: the viewer page and stream, paced at the input's rate unless fast.
  bool serve = false, fast = false, loop = false;
  viewer::ServerOptions server;
  std::string webRoot;
  std::vector<std::string> set;  // --set NAME=VALUE: the tracker's settings (recordings)
};

// Where the hand poses come from: a tracked recording or a pose file (camera frame).
class PoseSource {
 public:
  virtual ~PoseSource() = default;
  virtual int frameCount() const = 0;
  virtual float framesPerSecond() const = 0;
  virtual std::optional<Intrinsics> intrinsics() const { return std::nullopt; }
  // The hand pose of frame i, nullopt when the tracker lost the hand.
  virtual std::optional<model::ModelPose> pose(int i) = 0;
};

class PoseFileSource : public PoseSource {
 public:
  PoseFileSource(model::PoseSequence poses, float fps) : poses_(std::move(poses)), fps_(fps) {}
  int frameCount() const override { return static_cast<int>(poses_.frames.size()); }
  float framesPerSecond() const override { return fps_; }
  std::optional<model::ModelPose> pose(int i) override {
    return poses_.frames[static_cast<std::size_t>(i)];
  }

 private:
  model::PoseSequence poses_;
  float fps_;
};

class TrackedSource : public PoseSource {
 public:
  TrackedSource(SequenceReader reader, std::unique_ptr<track::Tracker> tracker)
      : reader_(std::move(reader)), tracker_(std::move(tracker)) {}
  int frameCount() const override { return reader_.info().frameCount; }
  float framesPerSecond() const override { return reader_.info().framesPerSecond; }
  std::optional<Intrinsics> intrinsics() const override { return reader_.info().intrinsics; }
  std::optional<model::ModelPose> pose(int i) override {
    auto frame = reader_.frame(i);
    if (!frame) throw UsageError(frame.message());  // a depth frame that does not decode
    const track::TrackResult& r = tracker_->track(*frame);
    if (r.hands.empty() || !r.hands.front().tracked) return std::nullopt;
    return r.hands.front().pose;
  }

 private:
  SequenceReader reader_;
  std::unique_ptr<track::Tracker> tracker_;
};

std::unique_ptr<PoseSource> openSource(const PlayOptions& o, const model::ArticulatedModel& hand) {
  if (o.input.rfind("camera:", 0) == 0)
    throw UsageError("live cameras: record with 'dynahand record' first, then play the recording");
  if (!std::filesystem::exists(o.input)) throw UsageError("input not found: " + o.input);
  if (std::filesystem::path(o.input).extension() == ".jsonl") {
    if (!o.set.empty())
      throw UsageError("--set goes with a recording (a pose file is not tracked)");
    auto poses = model::loadPoseSequence(o.input);
    if (!poses) throw UsageError(poses.message());
    const Status s = model::checkPoseSequence(*poses, hand);
    if (!s) throw UsageError(s.message());
    if (poses->frames.empty()) throw UsageError(o.input + " holds no pose");
    return std::make_unique<PoseFileSource>(std::move(*poses), o.fps);
  }
  auto reader = SequenceReader::open(o.input);
  if (!reader) throw UsageError(reader.message());
  track::TrackerSettings settings;
  applyTrackerSettings(o.set, settings);
  auto tracker = track::Tracker::create(hand, reader->info().intrinsics, settings);
  if (!tracker) {
    // DYNAHAND_DETECTOR's weights or --set's values
    if (detectorWeightsGiven("") || !o.set.empty()) throw UsageError(tracker.message());
    throw std::runtime_error(tracker.message());
  }
  if (o.init == "gt") {
    const auto gt = reader->groundTruth(0);
    if (!gt) throw UsageError("--init gt: " + o.input + " has no ground truth for frame 0");
    const Status s = (*tracker)->initializeFromKeypoints(*gt);
    if (!s) throw std::runtime_error("--init gt: " + s.message());
  } else if (o.init != "auto") {
    auto poses = model::loadPoseSequence(o.init);
    if (!poses || poses->frames.empty())
      throw UsageError("--init: " + (poses ? o.init + " holds no pose" : poses.message()));
    const Status s = model::checkPoseSequence(*poses, hand);
    if (!s) throw UsageError("--init: " + s.message());
    (*tracker)->initialize(poses->frames.front());
  }
  return std::make_unique<TrackedSource>(std::move(*reader), std::move(*tracker));
}

// The scene as the viewer draws it: the hand in the page's skin tone, static bodies grey,
// objects in turn from a palette.
std::vector<viewer::SceneBody> viewerBodies(const playground::Playground& pg) {
  // None of these passes for skin in the page tests (web/test/png.mjs isHandColour).
  static const char* const kPalette[] = {"#3c8cc8", "#5aaa50", "#aa5aaa",
                                         "#d2be3c", "#46bebe", "#c85050"};
  std::vector<viewer::SceneBody> bodies;
  int colour = 0;
  for (const playground::SceneBody& b : pg.bodies()) {
    std::string c = b.isHand ? "#e39a6f" : b.isStatic ? "#9ba0a5" : kPalette[colour++ % 6];
    bodies.push_back({b.name, &pg.world().bodyShape(b.id), std::move(c)});
  }
  return bodies;
}

std::string scenePoses(const playground::Playground& pg, int frame) {
  std::vector<Pose> poses;
  poses.reserve(pg.bodies().size());
  for (std::size_t i = 0; i < pg.bodies().size(); ++i)
    poses.push_back(pg.bodyPose(static_cast<int>(i)));
  return viewer::scenePosesMessage(frame, pg.time(), poses);
}

std::unique_ptr<viewer::ViewerServer> startViewer(PlayOptions o) {
  o.server.webRoot = viewer::findViewerPage(o.webRoot);
  std::string error;
  auto server = viewer::ViewerServer::start(o.server, &error);
  if (!server) {
    if (error.rfind("--host:", 0) == 0) throw UsageError(error);  // no address: bad input
    throw std::runtime_error(error);
  }
  viewer::printViewerAddress(o.server, *server, o.webRoot);
  return server;
}

// Frame timing while serving: the input's rate (unless fast) and the page's pause, resume
// and step buttons.
class ServedClock {
 public:
  using Clock = std::chrono::steady_clock;
  ServedClock(viewer::ViewerServer& server, float fps, bool fast)
      : server_(server),
        period_(std::chrono::duration_cast<Clock::duration>(
            std::chrono::duration<double>(1.0 / static_cast<double>(fps)))),
        fast_(fast) {}

  // Returns when the next frame may run; false when Ctrl-C came first.
  bool waitForNextFrame() {
    for (;;) {
      for (const viewer::ClientCommand c : server_.takeCommands()) {
        if (c == viewer::ClientCommand::Pause) paused_ = true;
        if (c == viewer::ClientCommand::Resume) paused_ = false;
        if (c == viewer::ClientCommand::Step) {
          paused_ = true;
          ++steps_;
        }
      }
      if (interrupted()) return false;
      if (!paused_ || steps_ > 0) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      due_ = Clock::now();
    }
    if (steps_ > 0) --steps_;
    if (!fast_) {
      due_ += period_;
      const auto now = Clock::now();
      if (due_ > now)
        std::this_thread::sleep_until(due_);
      else
        due_ = now;  // behind: no burst to catch up
    }
    return !interrupted();
  }

 private:
  viewer::ViewerServer& server_;
  Clock::duration period_;
  bool fast_;
  bool paused_ = false;
  int steps_ = 0;
  Clock::time_point due_ = Clock::now();
};

int runPlay(const PlayOptions& o) {
  checkTrackerSettings(o.set);  // a bad --set is reported before any input is opened
  if (!std::filesystem::exists(o.scene)) throw UsageError("scene not found: " + o.scene);
  auto scene = playground::loadScene(o.scene);
  if (!scene) throw UsageError(scene.message());
  const model::ArticulatedModel hand = handModel(o.hand);
  auto source = openSource(o, hand);

  playground::RenderView view;
  if (o.eye.size() == 3) view.eye = Vec3(o.eye[0], o.eye[1], o.eye[2]);
  if (o.target.size() == 3) view.target = Vec3(o.target[0], o.target[1], o.target[2]);
  if (!o.framesDir.empty()) std::filesystem::create_directories(o.framesDir);
  // --out goes to NAME.part, renamed when the first pass is complete.
  AtomicFileWriter outFile;
  if (!o.out.empty()) {
    if (!outFile.open(o.out)) throw UsageError("cannot write " + o.out);
  }
  std::ostream* out = o.out.empty() ? nullptr : &outFile.stream();
  std::unique_ptr<viewer::ViewerServer> server;
  std::optional<ServedClock> clock;
  if (o.serve) {
    server = startViewer(o);
    clock.emplace(*server, source->framesPerSecond(), o.fast);
    std::printf("%sCtrl-C stops\n", o.loop ? "the scene restarts when the input ends; " : "");
    std::fflush(stdout);
  }

  const int total = o.frames < 0 ? source->frameCount() : std::min(o.frames, source->frameCount());
  const float dt = 1.0f / source->framesPerSecond();
  installInterruptHandler();
  int lost = 0, done = 0;
  double simulated = 0.0;
  // One pass over the input; --serve --loop repeats it from a fresh scene (files are written
  // on the first pass only).
  for (int pass = 0; pass == 0 || (o.loop && !interrupted()); ++pass) {
    if (pass > 0) source = openSource(o, hand);
    auto pg = playground::Playground::create(*scene, hand);
    if (!pg) throw UsageError(pg.message());
    if (auto camera = source->intrinsics()) (*pg)->setCameraIntrinsics(*camera);
    if (server) server->setWelcome({viewer::sceneMessage(viewerBodies(**pg), "y")});
    if (pass == 0 && out != nullptr) *out << playground::playHeaderJson(**pg) << '\n';
    Progress progress("play", total);
    for (int i = 0; i < total && !interrupted(); ++i) {
      if (clock && !clock->waitForNextFrame()) break;
      const std::optional<model::ModelPose> pose = source->pose(i);
      if (i == 0 && pose) (*pg)->placeHand(*pose);
      (*pg)->step(pose, dt);
      if (server && server->hasClients()) server->publish(scenePoses(**pg, i));
      if (pass > 0) continue;
      lost += pose ? 0 : 1;
      if (out != nullptr) *out << playground::playFrameJson(**pg, i) << '\n';
      if (!o.framesDir.empty() && i % o.renderEvery == 0) {
        char name[32];
        std::snprintf(name, sizeof name, "%06d.png", i);
        const Status s =
            playground::renderPng(**pg, view, std::filesystem::path(o.framesDir) / name,
                                  scene->name + "  frame " + std::to_string(i));
        if (!s) throw std::runtime_error(s.message());
      }
      ++done;
      progress.update(done, pose ? "tracked" : "lost");
    }
    if (pass == 0) {
      simulated = (*pg)->time();
      progress.finish(interrupted() ? "(interrupted: everything up to here is written)" : "");
      if (out != nullptr) {
        const Status s = outFile.commit();
        if (!s) throw std::runtime_error(s.message());
      }
    }
    if (server && !o.loop && !interrupted()) {
      // Pages opened from now on see the final state too.
      server->setWelcome({viewer::sceneMessage(viewerBodies(**pg), "y"),
                          scenePoses(**pg, std::max(0, total - 1))});
      std::printf("input finished: the page keeps the last state; Ctrl-C stops\n");
      std::fflush(stdout);
      while (!interrupted()) std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
  }
  std::printf("frames %d  hand lost in %d  simulated %.2f s\n", done, lost, simulated);
  if (out != nullptr) std::printf("wrote %s\n", o.out.c_str());
  if (!o.framesDir.empty()) std::printf("wrote pictures to %s\n", o.framesDir.c_str());
  // Ctrl-C is how a served session ends, not an interruption of its output.
  if (server) return done == total ? kExitOk : 130;
  return interrupted() ? 130 : kExitOk;
}

const CommandRegistration kPlayCommand{Command{
    "play", "drive a physics playground scene with a tracked (or recorded) hand",
    [](CLI::App& sub) -> std::function<int()> {
      auto o = std::make_shared<PlayOptions>();
      sub.add_option("scene", o->scene, "scene file (JSON, docs/formats/scene.md)")->required();
      sub.add_option("input", o->input,
                     "recording to track (sequence folder, .rs/.json, PNG folder, .oni) or a "
                     "pose file (.jsonl, camera frame)")
          ->required();
      sub.add_option("-o,--out", o->out, "every scene body's pose per frame (JSON lines)");
      sub.add_option("--frames-dir", o->framesDir, "write a rendered PNG per frame here");
      sub.add_option("--render-every", o->renderEvery, "render every n-th frame")
          ->check(CLI::Range(1, 100000));
      sub.add_option("--eye", o->eye, "render camera position in the scene, m (x y z)")
          ->expected(3);
      sub.add_option("--look-at", o->target, "point the render camera looks at, m (x y z)")
          ->expected(3);
      sub.add_option("--init", o->init,
                     "recordings: gt (ground truth of frame 0), auto, or a pose JSONL file");
      sub.add_option("--fps", o->fps, "pose files: frames per second")
          ->check(CLI::Range(1.0f, 1000.0f));
      sub.add_option("--frames", o->frames, "number of frames (default: all)")
          ->check(CLI::Range(1, 100000000));
      addHandModelOptions(sub, o->hand, /*withModelFile=*/false);
      sub.add_flag("--serve", o->serve,
                   "show the scene live in the viewer page (dynahand serve's page and stream), "
                   "at the input's rate; Ctrl-C stops");
      sub.add_option("--port", o->server.port, "--serve: TCP port (0 = any free port)")
          ->check(CLI::Range(0, 65535));
      sub.add_option("--host", o->server.host, "--serve: address to listen on (127.0.0.1)");
      sub.add_flag("--loop", o->loop, "--serve: restart the scene when the input ends");
      sub.add_flag("--fast", o->fast, "--serve: run as fast as possible, not at the input's rate");
      sub.add_option("--web-root", o->webRoot,
                     "--serve: the page's folder instead of the built one");
      addTrackerSettingOption(sub, o->set);
      sub.footer(
          "Examples:\n"
          "  dynahand synth --motion reach-grasp-lift --frames 132 --out /tmp/g\n"
          "  dynahand play examples/scenes/grasp.json /tmp/g --init gt --out grasp.jsonl\n"
          "  dynahand play examples/scenes/barbell.json /tmp/g/poses.jsonl --frames-dir /tmp/pics\n"
          "  dynahand play examples/scenes/grasp.json /tmp/g/poses.jsonl --serve --loop\n"
          "  dynahand play examples/scenes/playground.json take01/ --frames-dir /tmp/pics "
          "--render-every 10 --eye 0 0.5 0.6 --look-at 0 0.05 -0.05");
      return [o] { return runPlay(*o); };
    }}};

}  // namespace
}  // namespace dynahand::cli
