#include "serve_session.h"

#include <chrono>
#include <cstdio>
#include <deque>
#include <filesystem>
#include <optional>

#include "dynahand/camera.h"
#include "dynahand/sequence.h"
#include "dynahand/synth.h"

namespace dynahand::viewer {

struct ServeSession::Impl {
  ServeOptions options;
  // Exactly one source is set.
  std::optional<synth::SyntheticSequence> synthetic;
  std::optional<SequenceReader> recording;
  std::unique_ptr<DepthCamera> camera;

  Intrinsics intrinsics;
  float fps = 30.0f;
  int frameCount = 0;  // 0 = live
  bool hasTruth = false;
  std::optional<model::ArticulatedModel> hand;  // has no default constructor
  std::unique_ptr<track::Tracker> tracker;

  DepthFrame cameraFrame;
  DepthFrame recordingFrame;
  int next = 0;  // next frame index
  int loop = 0;
  int tracked = 0;
  const track::TrackResult* last = nullptr;                  // owned by the tracker
  std::deque<std::chrono::steady_clock::time_point> recent;  // frame times of the last second

  // The next frame and its ground truth (empty when none).
  Result<const DepthFrame*> grab(int index, std::vector<TruthHand>& truth) {
    truth.clear();
    if (synthetic) {
      const synth::SyntheticFrame& f = synthetic->frame(index);
      for (const synth::HandTruth& h : f.hands) truth.push_back({h.side, h.keypoints, h.pose});
      return &f.depth;
    }
    if (recording) {
      auto f = recording->frame(index);
      if (!f) return Error{f.message()};
      recordingFrame = std::move(*f);
      if (hasTruth) truth.push_back({model::Side::Right, recording->groundTruth(index), {}});
      return &recordingFrame;
    }
    const Status s = camera->grab(cameraFrame, 2.0);
    if (!s) return Error{s.message()};
    return &cameraFrame;
  }

  void initializeFromTruth(const std::vector<TruthHand>& truth) {
    for (const TruthHand& t : truth) {
      if (!t.pose.bodies.empty()) {
        tracker->initialize(t.pose, t.side);
      } else if (t.keypoints) {
        (void)tracker->initializeFromKeypoints(*t.keypoints, t.side);
      }
    }
  }
};

std::filesystem::path findViewerPage(const std::string& webRoot) {
  if (!webRoot.empty()) return webRoot;
  std::error_code ec;
  const auto exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    const auto installed = exe.parent_path().parent_path() / "share/dynahand/viewer";
    if (std::filesystem::exists(installed / "index.html")) return installed;
  }
  const std::filesystem::path built = DYNAHAND_VIEWER_BUILD_DIR;
  if (std::filesystem::exists(built / "index.html")) return built;
  return {};
}

ServeSession::ServeSession(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
ServeSession::~ServeSession() = default;

Result<std::unique_ptr<ServeSession>> ServeSession::open(const ServeOptions& o) {
  auto impl = std::make_unique<Impl>();
  Impl& s = *impl;
  s.options = o;
  track::TrackerSettings settings = o.settings;
  settings.keepCandidates = true;  // the viewer draws the losing simulations
  const model::HandDimensions dims{o.handLength, o.handWidth};
  if (o.input.rfind("synth:", 0) == 0) {
    synth::SynthOptions so;
    so.clip = o.input.substr(6);
    so.profile = o.synthProfile;
    so.frameCount = o.synthFrames;
    so.hand = dims;
    auto seq = synth::SyntheticSequence::create(so);
    if (!seq) return Error{seq.message()};
    s.synthetic.emplace(std::move(*seq));
    s.intrinsics = s.synthetic->intrinsics();
    s.fps = so.framesPerSecond;
    s.frameCount = s.synthetic->frameCount();
    s.hasTruth = true;
    s.hand = s.synthetic->model(0);
    settings.hands = s.synthetic->handCount();
    settings.cloud.segmentation.sensorMinRangeM = s.synthetic->profile().minRange;
  } else if (o.input == "camera" || o.input.rfind("camera:", 0) == 0) {
    const std::string spec = o.input.size() > 7 ? o.input.substr(7) : "";
    auto cam = DepthCamera::open(spec);
    if (!cam) return Error{cam.message()};
    s.camera = std::move(*cam);
    s.intrinsics = s.camera->intrinsics();
    s.hand = model::makeDefaultHand(dims);
  } else {
    if (!std::filesystem::exists(o.input)) return Error{"input not found: " + o.input};
    auto reader = SequenceReader::open(o.input);
    if (!reader) return Error{reader.message()};
    s.recording.emplace(std::move(*reader));
    const SequenceInfo& info = s.recording->info();
    if (info.frameCount <= 0) return Error{o.input + ": holds no frames"};
    s.intrinsics = info.intrinsics;
    s.fps = info.framesPerSecond;
    s.frameCount = info.frameCount;
    s.hasTruth = info.hasGroundTruth;
    s.hand = model::makeDefaultHand(dims);
    if (info.minRangeM > 0.0f) settings.cloud.segmentation.sensorMinRangeM = info.minRangeM;
  }
  if (o.init != "auto" && o.init != "gt") return Error{"--init: expected auto or gt"};
  if (o.init == "gt" && !s.hasTruth) return Error{"--init gt: " + o.input + " has no ground truth"};
  auto tracker = track::Tracker::create(*s.hand, s.intrinsics, settings);
  if (!tracker) return Error{tracker.message()};
  s.tracker = std::move(*tracker);
  return std::unique_ptr<ServeSession>(new ServeSession(std::move(impl)));
}

std::string ServeSession::hello() const {
  const Impl& s = *impl_;
  HelloInfo info;
  info.source = s.options.input;
  info.framesPerSecond = s.fps;
  info.frameCount = s.frameCount;
  info.intrinsics = s.intrinsics;
  info.groundTruth = s.hasTruth;
  info.models.push_back(&s.tracker->model(model::Side::Right));
  if (s.tracker->settings().hands == 2) info.models.push_back(&s.tracker->model(model::Side::Left));
  return helloMessage(info);
}

float ServeSession::framesPerSecond() const {
  return impl_->fps;
}
bool ServeSession::live() const {
  return impl_->camera != nullptr;
}
const track::TrackResult* ServeSession::lastResult() const {
  return impl_->last;
}
int ServeSession::framesTracked() const {
  return impl_->tracked;
}

Status ServeSession::step(ViewerServer* server, bool paused) {
  Impl& s = *impl_;
  if (s.frameCount > 0 && s.next >= s.frameCount) {
    s.next = 0;
    ++s.loop;
  }
  const int index = s.next++;
  FrameInfo frame;
  auto depth = s.grab(index, frame.truth);
  if (!depth) return Error{depth.message()};
  if (index == 0 && s.frameCount > 0) {
    // A loop restarts the motion: forget the end of the previous pass.
    s.tracker->reset();
    if (s.options.init == "gt") s.initializeFromTruth(frame.truth);
  }
  const track::TrackResult& result = s.tracker->track(**depth);
  s.last = &result;
  ++s.tracked;

  const auto now = std::chrono::steady_clock::now();
  s.recent.push_back(now);
  while (s.recent.size() > 1 && now - s.recent.front() > std::chrono::seconds(1)) {
    s.recent.pop_front();
  }
  if (server == nullptr || !server->hasClients()) return Ok{};

  double fps = 0.0;
  if (s.recent.size() > 1) {
    const double span = std::chrono::duration<double>(s.recent.back() - s.recent.front()).count();
    if (span > 0.0) fps = static_cast<double>(s.recent.size() - 1) / span;
  }
  frame.index = index;
  frame.loop = s.loop;
  frame.trackingFps = fps;
  frame.paused = paused;
  frame.result = &result;
  frame.model = &s.tracker->model(model::Side::Right);
  if (s.options.cloud) {
    frame.depth = *depth;
    frame.intrinsics = &s.intrinsics;
    frame.samples = &s.tracker->lastCloud().points;
  }
  server->publish(frameMessage(frame));
  return Ok{};
}

void printViewerAddress(const ServerOptions& options, const ViewerServer& server,
                        const std::string& webRoot) {
  const std::string address = options.host + ":" + std::to_string(server.port());
  const std::string query = "?token=" + server.token();
  if (server.pageAvailable()) {
    std::printf("viewer at http://%s/%s  stream at ws://%s/%s\n", address.c_str(), query.c_str(),
                address.c_str(), query.c_str());
  } else {
    const std::string why =
        webRoot.empty()
            ? "this build had no web/node_modules; run scripts/install-deps.sh and rebuild"
            : "no index.html in " + webRoot;
    std::printf("stream at ws://%s/%s  (viewer page unavailable: %s)\n", address.c_str(),
                query.c_str(), why.c_str());
  }
  std::fflush(stdout);
}

}  // namespace dynahand::viewer
