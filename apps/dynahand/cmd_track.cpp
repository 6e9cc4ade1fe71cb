// dynahand track: tracks a recording and writes poses (JSON lines / CSV / BVH).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <memory>
#include <optional>

#include "dynahand/atomic_file.h"
#include "dynahand/camera.h"
#include "dynahand/command.h"
#include "dynahand/hand_size.h"
#include "dynahand/metrics.h"
#include "dynahand/model_pose.h"
#include "dynahand/progress.h"
#include "dynahand/sequence.h"
#include "dynahand/track_io.h"
#include "dynahand/tracker.h"

namespace dynahand::cli {
namespace {

struct TrackOptions {
  std::string input, out, csv, bvh, init = "auto";
  HandModelOptions hand;
  std::string handSize = "given";  // or "auto": estimateHandSize over the first frames
  int handSizeFrames = 30;
  bool sizeOnly = false;  // --hand-size auto without the metacarpals
  int hands = 1, threads = 1, start = 0, frames = -1;
  bool perFrame = false, candidates = false;
  bool behindUser = false;  // --behind-user: two hands, camera worn or behind the user
  std::vector<std::string> disable;
  bool noDetector = false;       // --no-detector
  std::string detector;          // --detector FILE (empty: the shipped weights)
  std::vector<std::string> set;  // --set NAME=VALUE, applied last
};

// camera:N opens the N-th camera DepthCamera::list() finds; camera:BACKEND[:ID] a given one.
std::unique_ptr<DepthCamera> openCamera(const std::string& input) {
  const std::string what = input.substr(std::string("camera:").size());
  std::string spec = what;
  const bool isIndex = !what.empty() && std::all_of(what.begin(), what.end(),
                                                    [](char c) { return c >= '0' && c <= '9'; });
  std::string backends;
  for (const auto& b : cameraBackends()) backends += (backends.empty() ? "" : ", ") + b;
  if (backends.empty()) backends = "none compiled in";
  if (isIndex) {
    const CameraScan scan = DepthCamera::list();
    const std::size_t index = std::stoul(what);
    if (index >= scan.cameras.size()) {
      std::string problems;
      for (const auto& p : scan.problems) problems += "; " + p;
      throw std::runtime_error(input + ": " + std::to_string(scan.cameras.size()) +
                               " depth camera(s) found (tried back ends: " + backends + problems +
                               ")");
    }
    spec = scan.cameras[index].spec();
  }
  auto camera = DepthCamera::open(spec);
  if (!camera) {
    // An unknown back end is bad input; a known one that does not open is not.
    const std::string backend = spec.substr(0, spec.find(':'));
    const auto known = cameraBackends();
    if (!spec.empty() && std::find(known.begin(), known.end(), backend) == known.end())
      throw UsageError(input + ": " + camera.message());
    throw std::runtime_error(input + ": " + camera.message() + " (tried back ends: " + backends +
                             ")");
  }
  return std::move(*camera);
}

// Where frames come from: a recording (random access, maybe ground truth) or a live camera.
struct FrameInput {
  std::optional<SequenceReader> reader;
  std::unique_ptr<DepthCamera> camera;
  SequenceInfo info;
  DepthFrame live;
};

FrameInput openInput(const TrackOptions& o) {
  FrameInput in;
  if (o.input.rfind("camera:", 0) == 0) {
    if (o.init == "gt") throw UsageError("--init gt: a live camera has no ground truth");
    in.camera = openCamera(o.input);
    in.info.intrinsics = in.camera->intrinsics();
    in.info.framesPerSecond = 30.0f;
    in.info.frameCount = std::numeric_limits<int>::max();  // until Ctrl-C
    std::printf("tracking %s (%s) live; Ctrl-C stops\n", in.camera->info().name.c_str(),
                in.camera->info().spec().c_str());
    return in;
  }
  if (!std::filesystem::exists(o.input)) throw UsageError("input not found: " + o.input);
  auto reader = SequenceReader::open(o.input);
  if (!reader) throw UsageError(reader.message());
  in.reader.emplace(std::move(*reader));
  in.info = in.reader->info();
  return in;
}

// Frame f of the recording, or the camera's next frame.
void readFrame(FrameInput& in, const TrackOptions& o, int f, DepthFrame& out) {
  if (in.camera) {
    const Status s = in.camera->grab(out);
    if (!s) throw std::runtime_error(o.input + ": " + s.message());
    return;
  }
  auto recorded = in.reader->frame(f);
  if (!recorded) throw UsageError(recorded.message());  // a frame that does not decode
  out = std::move(*recorded);
}

track::TrackerSettings trackerSettings(const TrackOptions& o, const SequenceInfo& info) {
  track::TrackerSettings settings;
  settings.hands = o.hands;
  if (o.behindUser) settings.split.placement = CameraPlacement::kBehindUser;
  settings.perFrame = o.perFrame;
  settings.threads = o.threads;
  settings.keepCandidates = o.candidates;
  settings.detector.enabled = !o.noDetector;
  settings.detector.weights = o.detector;
  if (info.minRangeM > 0.0f) settings.cloud.segmentation.sensorMinRangeM = info.minRangeM;
  if (o.noDetector && !o.detector.empty())
    throw UsageError("--detector and --no-detector are exclusive");
  disableSimulations(o.disable, settings);
  applyTrackerSettings(o.set, settings);
  return settings;
}

// The start: ground truth keypoints, or a pose file's first pose (its keypoints too, for a
// model of another size), or none (automatic acquisition).
struct Start {
  std::optional<Keypoints21> keypoints;
  std::optional<model::ModelPose> pose;
};

Start startFrom(const TrackOptions& o, const FrameInput& in, const model::ArticulatedModel& hand,
                int first) {
  Start start;
  if (o.init == "gt") {
    start.keypoints = in.reader->groundTruth(first);
    if (!start.keypoints)
      throw UsageError("--init gt: " + o.input + " has no ground truth for frame " +
                       std::to_string(first));
  } else if (o.init != "auto") {
    auto poses = model::loadPoseSequence(o.init);
    if (!poses) throw UsageError("--init: " + poses.message());
    if (poses->frames.empty()) throw UsageError("--init: " + o.init + " holds no pose");
    const Status s = model::checkPoseSequence(*poses, hand);
    if (!s) throw UsageError("--init: " + s.message());
    start.pose = poses->frames.front();
    start.keypoints = model::keypoints21(hand, *start.pose);
  }
  return start;
}

// --hand-size auto: reads the first frames ahead into `head` (tracked before any other),
// estimates the hand's size from them and makes `hand` that size. Returns the size record the
// outputs carry (given, or estimated).
std::optional<io::HandSizeRecord> sizeHand(const TrackOptions& o, FrameInput& in,
                                           const track::TrackerSettings& settings,
                                           const Start& start, int first, int last,
                                           std::vector<DepthFrame>& head,
                                           std::optional<model::ArticulatedModel>& hand) {
  std::optional<io::HandSizeRecord> handSize;
  if (o.hand.modelFile.empty()) handSize = io::HandSizeRecord{{o.hand.length, o.hand.width}};
  if (o.handSize != "auto") return handSize;
  if (o.hand.lengthGiven() && o.hand.widthGiven() && o.sizeOnly) {
    std::printf(
        "--hand-size auto --hand-size-only: --hand-length and --hand-width given, nothing to "
        "estimate\n");
    return handSize;
  }
  const int count = std::min(o.handSizeFrames, last - first);
  head.resize(static_cast<std::size_t>(std::max(count, 0)));
  for (int i = 0; i < count; ++i) readFrame(in, o, first + i, head[static_cast<std::size_t>(i)]);
  track::HandSizeOptions hs;
  hs.tracker = settings;
  hs.threads = o.threads;
  if (o.hand.lengthGiven()) hs.length = o.hand.length;
  if (o.hand.widthGiven()) hs.width = o.hand.width;
  hs.metacarpals = !o.sizeOnly;
  std::printf("hand size: estimating from frames %d-%d...\n", first, first + count - 1);
  std::fflush(stdout);
  const auto started = std::chrono::steady_clock::now();
  auto estimate = track::estimateHandSize(head, in.info.intrinsics, start.keypoints, hs);
  if (!estimate) throw std::runtime_error("--hand-size auto: " + estimate.message());
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  const io::HandSizeRecord record = io::HandSizeRecord::fromEstimate(*estimate);
  std::printf(
      "hand size estimate: length %.4f m  width %.4f m  (%d frames, %d candidate models, fit "
      "%.3f, %.1f s)\n",
      static_cast<double>(estimate->dimensions.length),
      static_cast<double>(estimate->dimensions.width), estimate->framesUsed, estimate->candidates,
      static_cast<double>(estimate->fitScore), seconds);
  if (!hs.metacarpals) {
    std::printf("hand shape: the built-in proportions (--hand-size-only)\n");
  } else if (estimate->shape.identity()) {
    std::printf("hand shape: the built-in proportions (too few frames show the palm)\n");
  } else {
    std::printf(
        "hand shape estimate: metacarpals (thumb..pinky) %.3f %.3f %.3f %.3f %.3f\n",
        static_cast<double>(record.metacarpals[0]), static_cast<double>(record.metacarpals[1]),
        static_cast<double>(record.metacarpals[2]), static_cast<double>(record.metacarpals[3]),
        static_cast<double>(record.metacarpals[4]));
  }
  hand = model::makeDefaultHand(estimate->dimensions, model::Side::Right, record.shape());
  return record;
}

// The files written as frames are tracked (JSON lines, CSV) and at the end (BVH).
struct Outputs {
  std::unique_ptr<io::TrackWriter> writer, csv;
  std::optional<io::BvhWriter> bvh;
  model::ModelPose lastPose;  // the BVH repeats the last tracked pose while the hand is lost

  Status write(const track::TrackResult& r) {
    for (io::TrackWriter* w : {writer.get(), csv.get()}) {
      if (w == nullptr) continue;
      if (Status s = w->write(r); !s) return s;
    }
    const auto& h = r.hands.front();
    if (bvh) {
      if (h.tracked) lastPose = h.pose;
      if (!lastPose.bodies.empty()) bvh->add(lastPose);
    }
    return Ok{};
  }
  Status close(const std::string& bvhPath) {
    for (io::TrackWriter* w : {writer.get(), csv.get()}) {
      if (w == nullptr) continue;
      if (Status s = w->close(); !s) return s;
    }
    if (bvh) return bvh->save(bvhPath);
    return Ok{};
  }
};

Outputs openOutputs(const TrackOptions& o, const model::ArticulatedModel& hand,
                    const std::optional<io::HandSizeRecord>& handSize, float framesPerSecond,
                    int firstFrame) {
  io::JsonOptions json;
  json.firstFrame = firstFrame;  // the files number frames as the input does
  json.handSize = handSize;
  json.candidates = o.candidates;
  json.candidatePoses = o.candidates;
  Outputs out;
  if (!o.out.empty()) {
    auto w = io::TrackWriter::create(o.out, hand, json);
    if (!w) throw UsageError(w.message());
    out.writer = std::move(*w);
  }
  if (!o.csv.empty()) {
    auto w = io::TrackWriter::create(o.csv, hand, json);
    if (!w) throw UsageError(w.message());
    out.csv = std::move(*w);
  }
  if (!o.bvh.empty()) {
    // Written at the end: find out now whether it can be (a path below a file, say).
    AtomicFileWriter probe;
    if (!probe.open(o.bvh)) throw UsageError(o.bvh + ": cannot write");
    std::error_code ec;
    std::filesystem::remove(probe.part(), ec);
    out.bvh.emplace(hand, framesPerSecond);
  }
  return out;
}

// What the frame loop measured.
struct TrackTally {
  std::vector<double> times;  // ms per frame
  eval::SequenceKeypoints accuracy;
  int trackedFrames = 0;
  int done = 0;
};

TrackTally trackFrames(const TrackOptions& o, FrameInput& in, track::Tracker& tracker,
                       const std::vector<DepthFrame>& head, int first, int last, Outputs& outputs) {
  installInterruptHandler();
  Progress progress("track", in.camera ? 0 : last - first);
  TrackTally tally;
  tally.accuracy.fps = in.info.framesPerSecond;
  for (int f = first; f < last && !interrupted(); ++f) {
    const std::size_t ahead = static_cast<std::size_t>(f - first);
    DepthFrame recorded;
    const DepthFrame* depth = nullptr;
    if (ahead < head.size()) {
      depth = &head[ahead];
    } else {
      DepthFrame& target = in.camera ? in.live : recorded;
      readFrame(in, o, f, target);
      depth = &target;
    }
    const track::TrackResult& r = tracker.track(*depth);
    tally.times.push_back(r.timeMs);
    const auto& h = r.hands.front();
    tally.trackedFrames += h.tracked ? 1 : 0;
    if (Status s = outputs.write(r); !s) throw std::runtime_error(s.message());
    if (in.info.hasGroundTruth) {
      tally.accuracy.groundTruth.push_back(in.reader->groundTruth(f));
      tally.accuracy.predicted.push_back(h.tracked ? std::optional<Keypoints21>(h.keypoints21)
                                                   : std::nullopt);
    }
    ++tally.done;
    char extra[64];
    std::snprintf(extra, sizeof extra, "%s err %.0f mm", h.tracked ? "tracked" : "lost",
                  1000.0 * static_cast<double>(h.error));
    progress.update(tally.done, extra);
  }
  progress.finish(interrupted() ? "(interrupted: everything up to here is written)" : "");
  return tally;
}

void printSummary(const TrackOptions& o, const std::optional<io::HandSizeRecord>& handSize,
                  int first, const TrackTally& tally, bool hasGroundTruth) {
  if (handSize) {
    const std::string frames =
        "from frames " + std::to_string(first) + "-" + std::to_string(first + handSize->frames - 1);
    // Both dimensions given with --hand-size auto: only the metacarpals were estimated.
    const bool sizeGiven = o.hand.lengthGiven() && o.hand.widthGiven();
    const std::string source = !handSize->estimated ? "given"
                               : sizeGiven          ? "given; metacarpals estimated " + frames
                                                    : "estimated " + frames;
    std::printf("hand size  length %.4f m  width %.4f m  (%s)\n",
                static_cast<double>(handSize->dimensions.length),
                static_cast<double>(handSize->dimensions.width), source.c_str());
  }
  const int done = tally.done;
  std::printf("frames %d  tracked %d (%.1f%%)\n", done, tally.trackedFrames,
              done ? 100.0 * tally.trackedFrames / done : 0.0);
  const double p50 = eval::percentile(tally.times, 0.5);
  std::printf("time per frame  p50 %.2f ms  p99 %.2f ms  (%.0f frames/s at p50)\n", p50,
              eval::percentile(tally.times, 0.99), p50 > 0 ? 1000.0 / p50 : 0.0);
  if (hasGroundTruth && done > 0) {
    auto m = eval::computeKeypointMetrics(tally.accuracy);
    if (m) {
      std::printf(
          "21-keypoint error vs ground truth  mean %.2f mm  median %.2f mm  p95 %.2f mm  "
          "max-joint<=30mm %.1f%% of frames\n",
          m->meanMm, m->medianMm, m->p95Mm, 100.0 * m->successFraction[2]);
    }
  }
  for (const auto* path : {&o.out, &o.csv, &o.bvh}) {
    if (!path->empty()) std::printf("wrote %s\n", path->c_str());
  }
}

int runTrack(const TrackOptions& o) {
  checkTrackerSettings(o.set);  // a bad --set is reported before any input is opened
  FrameInput in = openInput(o);
  const SequenceInfo& info = in.info;
  if (o.sizeOnly && o.handSize != "auto")
    throw UsageError("--hand-size-only goes with --hand-size auto");
  if (o.handSize == "auto" && !o.hand.modelFile.empty())
    throw UsageError("--hand-size auto sizes the built-in hand; it does not go with --model");
  std::optional<model::ArticulatedModel> hand = handModel(o.hand);
  const track::TrackerSettings settings = trackerSettings(o, info);
  const int first = std::clamp(o.start, 0, info.frameCount);
  const int last = o.frames < 0 ? info.frameCount : std::min(info.frameCount, first + o.frames);
  const Start start = startFrom(o, in, *hand, first);
  std::vector<DepthFrame> head;  // frames read ahead for the hand-size estimate
  const std::optional<io::HandSizeRecord> handSize =
      sizeHand(o, in, settings, start, first, last, head, hand);

  auto tracker = track::Tracker::create(*hand, info.intrinsics, settings);
  if (!tracker) {
    // The hand model is checked already (handModel); what is left is the detector's weights
    // and the settings --set gave.
    if (detectorWeightsGiven(o.detector) || !o.set.empty()) throw UsageError(tracker.message());
    throw std::runtime_error(tracker.message());
  }
  if (start.pose && !(handSize && handSize->estimated)) {
    (*tracker)->initialize(*start.pose);
  } else if (start.keypoints) {  // a pose of another model size starts from its keypoints
    const Status s = (*tracker)->initializeFromKeypoints(*start.keypoints);
    if (!s) throw std::runtime_error("--init " + o.init + ": " + s.message());
  }

  Outputs outputs = openOutputs(o, *hand, handSize, info.framesPerSecond, first);
  const TrackTally tally = trackFrames(o, in, **tracker, head, first, last, outputs);
  if (Status s = outputs.close(o.bvh); !s) throw std::runtime_error(s.message());
  printSummary(o, handSize, first, tally, info.hasGroundTruth);
  return interrupted() ? 130 : kExitOk;
}

const CommandRegistration kTrackCommand{Command{
    "track", "track hands in a depth recording and write their poses",
    [](CLI::App& sub) -> std::function<int()> {
      auto o = std::make_shared<TrackOptions>();
      sub.add_option("input", o->input,
                     "sequence folder (canonical layout), .rs/.json recording, PNG folder, .oni, "
                     "or camera:N (the N-th camera 'dynahand cameras' lists, live until Ctrl-C)")
          ->required();
      sub.add_option("-o,--out", o->out,
                     "poses as JSON lines (.jsonl), CSV (.csv) or the original authors' .pose");
      sub.add_option("--csv", o->csv, "also write the 21 keypoints as CSV");
      sub.add_option("--bvh", o->bvh, "also write a BVH skeleton animation");
      addHandModelOptions(sub, o->hand);
      sub.add_option("--hand-size", o->handSize,
                     "given (--hand-length / --hand-width, default 0.19 / 0.085), or auto: "
                     "estimate the built-in hand's size from the first --hand-size-frames frames "
                     "(13 candidate models tracked over them; seen from behind, the learned "
                     "detector's palm; a given --hand-length or --hand-width is kept, both "
                     "given: only the metacarpals) and, from the frames that show the palm, each "
                     "digit's metacarpal length (12 more per step, two steps), then track with "
                     "it; the size and the metacarpals go into the output")
          ->check(CLI::IsMember({"given", "auto"}));
      sub.add_flag("--hand-size-only", o->sizeOnly,
                   "with --hand-size auto: the size alone, the built-in hand's metacarpals");
      sub.add_option("--hand-size-frames", o->handSizeFrames,
                     "frames --hand-size auto estimates from (default 30, 1 s at 30 fps)")
          ->check(CLI::Range(10, 600));
      sub.add_option("--init", o->init,
                     "gt (ground truth of the first frame), auto, or a pose JSONL file");
      sub.add_option("--hands", o->hands, "hands to track")->check(CLI::IsMember({1, 2}));
      sub.add_flag("--behind-user", o->behindUser,
                   "two hands: the camera looks along the user's view (worn on the head, or "
                   "behind them), so their left hand is on the image's left (default: the "
                   "camera faces the user)");
      sub.add_option(
             "--threads", o->threads,
             "threads the simulations of a frame (and --hand-size auto's candidate models) run on "
             "(results are identical for any count)")
          ->check(CLI::Range(1, 64));
      sub.add_option("--start", o->start, "first frame")->check(CLI::NonNegativeNumber);
      sub.add_option("--frames", o->frames, "number of frames (default: all)")
          ->check(CLI::Range(1, 100000000));
      sub.add_flag("--per-frame", o->perFrame,
                   "acquire every frame afresh (frames far apart in time)");
      sub.add_flag("--candidates", o->candidates,
                   "write every simulation's error and pose into the JSON lines (for render)");
      sub.add_option("--disable", o->disable,
                     "simulations to switch off: normal, gross_motion, grasp_bias, finger_flip, "
                     "feature_detection, detector_fit");
      sub.add_option("--detector", o->detector,
                     "learned keypoint detector weights (ONNX; default: the shipped "
                     "models/detector/detector.onnx, or $DYNAHAND_DETECTOR)");
      sub.add_flag("--no-detector", o->noDetector,
                   "track without the learned detector (the paper's simulations only)");
      addTrackerSettingOption(sub, o->set);
      sub.footer(
          "Examples:\n"
          "  dynahand track clip/ --out poses.jsonl\n"
          "  dynahand track clip/ --init gt --out poses.jsonl --bvh hand.bvh\n"
          "  dynahand track clip/ --hand-size auto --out poses.jsonl\n"
          "  dynahand track clip/ --init gt --set detector.selectionWeight=0\n"
          "  dynahand track clip/ --out hand.pose\n"
          "  dynahand track camera:0 --out live.jsonl\n"
          "  dynahand track ../shared/data/sr305-hands/20210326-230536 --per-frame --out "
          "fits.jsonl");
      return [o] { return runTrack(*o); };
    }}};

}  // namespace
}  // namespace dynahand::cli
