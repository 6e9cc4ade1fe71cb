// `import dynahand`: Tracker and its per-hand results (docs/python.md).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "dynahand/hand_size.h"
#include "dynahand/model.h"
#include "dynahand/model_pose.h"
#include "dynahand/track_io.h"
#include "dynahand/tracker.h"
#include "module_util.h"

namespace dynahand::python {
namespace {

// ---- tracker -------------------------------------------------------------------------------

// One hand of one frame, as Python sees it.
struct HandOut {
  std::string side;
  bool tracked = false;
  F32Array keypoints21, skeletonKeypoints21, openxr26, bodies, bodyError, detectorKeypoints21,
      detectorConfidence;
  float error = 0, fitError = 0, occlusionError = 0, detectorDisagreement = 0;
  float dataNearModel = 0, modelOnHand = 0;
  int fingertipsOffHand = 0, disagreeingFrames = 0, points = 0;
  std::string simulation;
  bool acquired = false, detected = false;
};

HandOut handOut(const track::HandResult& h) {
  HandOut o;
  o.side = h.side == model::Side::Right ? "right" : "left";
  o.tracked = h.tracked;
  o.keypoints21 = keypointsArray(h.keypoints21, h.tracked);
  o.skeletonKeypoints21 = keypointsArray(h.skeletonKeypoints21, h.tracked);
  o.openxr26 = F32Array({26, 8});
  {
    auto m = o.openxr26.mutable_unchecked<2>();
    for (py::ssize_t j = 0; j < 26; ++j) {
      const model::XrJoint& joint = h.openxr26[static_cast<std::size_t>(j)];
      putPose(m, j, joint.pose, h.tracked);
      m(j, 7) = h.tracked ? joint.radius : std::numeric_limits<float>::quiet_NaN();
    }
  }
  const auto bodyCount = static_cast<py::ssize_t>(h.pose.bodies.size());
  o.bodies = F32Array({bodyCount, py::ssize_t{7}});
  {
    auto m = o.bodies.mutable_unchecked<2>();
    for (py::ssize_t b = 0; b < bodyCount; ++b)
      putPose(m, b, h.pose.bodies[static_cast<std::size_t>(b)], h.tracked);
  }
  o.bodyError = F32Array(static_cast<py::ssize_t>(h.bodyError.size()));
  std::copy(h.bodyError.begin(), h.bodyError.end(), o.bodyError.mutable_data());
  o.error = h.error;
  o.fitError = h.fitError;
  o.occlusionError = h.occlusionError;
  o.dataNearModel = h.quality.dataNearModel;
  o.modelOnHand = h.quality.modelOnHand;
  o.fingertipsOffHand = h.quality.fingertipsOffHand;
  o.simulation = track::strategyName(h.simulation);
  o.acquired = h.acquired;
  o.detected = h.detected;
  o.detectorKeypoints21 = keypointsArray(h.detectorKeypoints21, h.detected);
  o.detectorConfidence = F32Array(21);
  std::copy(h.detectorConfidence.begin(), h.detectorConfidence.end(),
            o.detectorConfidence.mutable_data());
  o.detectorDisagreement = h.detectorDisagreement;
  o.disagreeingFrames = h.disagreeingFrames;
  o.points = h.pointCount;
  return o;
}

// ---- hand size -----------------------------------------------------------------------------

constexpr int kMinSizeFrames = 10, kMaxSizeFrames = 600;  // as --hand-size-frames
constexpr int kDefaultSizeFrames = 30;

// The first `count` frames of `frames` as the tracker's frames: an (N, H, W) uint16 array, or
// any iterable (a Sequence, a SyntheticClip, a list, a generator) of (H, W) uint16 arrays or of
// (depth, depth_scale, ...) tuples as a Sequence's iteration gives them. Frame i is stamped
// i / fps, as a recording's frames are (and as Tracker.track stamps them); a bare array's depth
// scale is `depthScale`. Reads no further than `count` items.
std::vector<DepthFrame> headFrames(const py::handle& frames, int count, const Intrinsics& k,
                                   double fps, float depthScale) {
  std::vector<DepthFrame> out;
  auto add = [&](const py::handle& depth, float scale) {
    const std::string what = "frames: frame " + std::to_string(out.size());
    if (!(scale > 0.0f && std::isfinite(scale)))
      throw py::value_error(what + ": depth_scale must be a positive number (metres per unit)");
    py::array_t<std::uint16_t, py::array::c_style> pixels;
    try {
      pixels = depthInput(depth, k.width, k.height);
    } catch (const py::value_error& e) {
      throw py::value_error(what + ": " + e.what());
    }
    DepthFrame f(k.width, k.height, scale);
    std::memcpy(f.depth.data(), pixels.data(), f.depth.size() * sizeof(std::uint16_t));
    f.timestamp = static_cast<double>(out.size()) / fps;
    out.push_back(std::move(f));
  };
  if (py::isinstance<py::array>(frames)) {
    const auto a = py::reinterpret_borrow<py::array>(frames);
    if (a.ndim() != 3)
      throw py::value_error("frames: an array of frames must have shape (N, H, W) (got " +
                            std::to_string(a.ndim()) + " dimensions)");
    for (py::ssize_t i = 0; i < std::min<py::ssize_t>(a.shape(0), count); ++i)
      add(a[py::int_(i)], depthScale);
    return out;
  }
  if (py::isinstance<py::str>(frames) || py::isinstance<py::bytes>(frames) ||
      !py::hasattr(frames, "__iter__"))
    throw py::value_error(
        "frames must be a Sequence, a SyntheticClip, an (N, H, W) uint16 array or an iterable "
        "of (H, W) uint16 arrays or (depth, depth_scale) tuples (got " +
        typeName(frames) + ")");
  const py::iterator it = py::iter(frames);
  for (int i = 0; i < count; ++i) {
    // Items one at a time: a generator is read no further than needed.
    PyObject* next = PyIter_Next(it.ptr());
    if (next == nullptr) {
      if (PyErr_Occurred()) throw py::error_already_set();  // e.g. a corrupt frame: OSError
      break;
    }
    const auto item = py::reinterpret_steal<py::object>(next);
    if (py::isinstance<py::tuple>(item)) {
      const auto t = py::reinterpret_borrow<py::tuple>(item);
      if (t.size() < 2)
        throw py::value_error("frames: frame " + std::to_string(i) +
                              ": a tuple must be (depth, depth_scale, ...)");
      float scale = 0.0f;
      try {
        scale = t[1].cast<float>();
      } catch (const py::cast_error&) {
        throw py::value_error("frames: frame " + std::to_string(i) +
                              ": depth_scale must be a number (got " + typeName(t[1]) + ")");
      }
      add(t[0], scale);
    } else {
      add(item, depthScale);
    }
  }
  return out;
}

// estimateHandSize (hand_size.h) over the first `count` frames, as `dynahand track
// --hand-size auto --hand-size-frames COUNT` runs it: the candidate trackers have the tracker's
// settings (hands, per-frame; the detector is left out of their scores) and run on `threads`.
track::HandSizeEstimate estimateSize(const py::handle& frames, const Intrinsics& k, double fps,
                                     float depthScale,
                                     const std::optional<track::Keypoints21>& start, int count,
                                     const track::HandSizeOptions& options) {
  const std::vector<DepthFrame> head = headFrames(frames, count, k, fps, depthScale);
  auto estimate = [&] {
    py::gil_scoped_release nogil;
    return track::estimateHandSize(head, k, start, options);
  }();
  if (!estimate) throw py::value_error(estimate.message());
  return *estimate;
}

void checkLength(float length, const char* what) {
  if (!(length >= 0.10f && length <= 0.30f))
    throw py::value_error(std::string(what) + " must be in [0.10, 0.30] m");
}
void checkWidth(float width, const char* what) {
  if (!(width >= 0.05f && width <= 0.15f))
    throw py::value_error(std::string(what) + " must be in [0.05, 0.15] m");
}
void checkSizeFrames(int count, const char* what) {
  if (count < kMinSizeFrames || count > kMaxSizeFrames)
    throw py::value_error(std::string(what) + " must be in " + std::to_string(kMinSizeFrames) +
                          ".." + std::to_string(kMaxSizeFrames) + " (got " + std::to_string(count) +
                          ")");
}

// Whether a Tracker's `camera` argument holds frames too (a Sequence, a SyntheticClip).
bool hasFrames(const py::handle& obj) {
  return py::hasattr(obj, "camera") && py::hasattr(obj, "__iter__") && py::hasattr(obj, "fps");
}

track::HandSizeEstimate estimateHandSizePy(const py::object& frames, const py::object& camera,
                                           const py::object& startKeypoints, int framesUsed,
                                           int threads, std::optional<float> length,
                                           std::optional<float> width, int hands, bool perFrame,
                                           double depthScale, std::optional<double> fps,
                                           bool metacarpals) {
  if (camera.is_none() && !py::hasattr(frames, "camera"))
    throw py::value_error(
        "camera: needed unless frames is a Sequence or SyntheticClip (which carry theirs)");
  const CameraSpec spec = cameraSpec(camera.is_none() ? frames : camera);
  // The frame rate: given, else the camera's, else the frames' own (a Sequence's), else 30.
  double rate = fps ? *fps : spec.fps.value_or(30.0);
  if (!fps && !spec.fps && hasFrames(frames)) rate = frames.attr("fps").cast<double>();
  if (!(rate > 0.0 && std::isfinite(rate))) throw py::value_error("fps must be > 0");
  checkSizeFrames(framesUsed, "frames_used");
  if (threads < 1 || threads > 64) throw py::value_error("threads must be 1..64");
  if (hands != 1 && hands != 2) throw py::value_error("hands must be 1 or 2");
  const auto scale = static_cast<float>(depthScale);
  if (!(scale > 0.0f && std::isfinite(scale)))
    throw py::value_error("depth_scale must be a positive number (metres per unit)");
  if (length) checkLength(*length, "length");
  if (width) checkWidth(*width, "width");
  if (length && width && !metacarpals)
    throw py::value_error("length and width both given and metacarpals=False: nothing to estimate");
  const auto start = keypointsInput(startKeypoints, "start_keypoints");
  track::HandSizeOptions options;
  options.tracker.hands = hands;
  options.tracker.threads = threads;
  options.tracker.perFrame = perFrame;
  options.threads = threads;
  options.length = length;
  options.width = width;
  options.metacarpals = metacarpals;
  return estimateSize(frames, spec.intrinsics, rate, scale, start, framesUsed, options);
}

// ---- tracker -------------------------------------------------------------------------------

// Tracker(settings={"detector.selectionWeight": 0, ...}): TrackerSettings fields by the names
// `dynahand settings` lists (track::setTrackerSetting), as `dynahand track --set` takes them.
void applySettingsByName(const py::object& byName, track::TrackerSettings& settings) {
  if (byName.is_none()) return;
  if (!py::isinstance<py::dict>(byName))
    throw py::type_error("settings must be a dict of setting name -> number or bool");
  for (const auto& [key, value] : byName.cast<py::dict>()) {
    if (!py::isinstance<py::str>(key)) throw py::type_error("settings: names must be strings");
    std::string text;
    if (py::isinstance<py::bool_>(value))
      text = value.cast<bool>() ? "true" : "false";
    else if (py::isinstance<py::int_>(value) || py::isinstance<py::float_>(value))
      text = py::str(value).cast<std::string>();
    else
      throw py::type_error("settings['" + key.cast<std::string>() + "']: a number or a bool");
    const Status set = track::setTrackerSetting(settings, key.cast<std::string>(), text);
    if (!set) throw py::value_error("settings: " + set.message());
  }
}

class PyTracker {
 public:
  PyTracker(const py::object& camera, int hands, const py::object& handSize,
            const py::object& detector, int threads, bool perFrame, std::optional<double> fps,
            const py::object& modelFile, const py::object& frames, int handSizeFrames,
            bool behindUser, const py::object& settingsByName) {
    const CameraSpec spec = cameraSpec(camera);
    intrinsics_ = spec.intrinsics;
    fps_ = fps ? *fps : spec.fps.value_or(30.0);
    if (!(fps_ > 0.0 && std::isfinite(fps_))) throw py::value_error("fps must be > 0");
    if (hands != 1 && hands != 2) throw py::value_error("hands must be 1 or 2");
    if (threads < 1 || threads > 64) throw py::value_error("threads must be 1..64");

    const bool autoSize =
        py::isinstance<py::str>(handSize) && handSize.cast<std::string>() == "auto";
    if (py::isinstance<py::str>(handSize) && !autoSize)
      throw py::value_error(
          "hand_size must be None, (length, width) in metres, 'auto' or a dynahand.HandSize "
          "(got '" +
          handSize.cast<std::string>() + "')");
    if (autoSize && !modelFile.is_none())
      throw py::value_error(
          "hand_size='auto' sizes the built-in hand; it does not go with model_file");
    if (!frames.is_none() && !autoSize)
      throw py::value_error(
          "frames: only with hand_size='auto' (the frames the hand size is estimated from)");
    checkSizeFrames(handSizeFrames, "hand_size_frames");
    if (autoSize && frames.is_none() && !hasFrames(camera))
      throw py::value_error(
          "hand_size='auto' needs the frames to estimate from: frames=... (a Sequence, a "
          "SyntheticClip, an (N, H, W) array or a list of frames), or a Sequence or "
          "SyntheticClip as camera; or pass dynahand.estimate_hand_size(...)'s result as "
          "hand_size");
    if (!modelFile.is_none()) {
      if (!handSize.is_none()) throw py::value_error("hand_size and model_file are exclusive");
      const std::filesystem::path file = existingPath(modelFile, "model_file");
      auto loaded = model::loadModel(file);
      if (!loaded) throw FileError(loaded.message());
      hand_ = std::move(*loaded);
    } else if (!autoSize) {
      model::HandDimensions size;  // `dynahand track`'s default, 0.19 x 0.085 m
      model::HandShape shape;
      if (py::isinstance<track::HandSizeEstimate>(handSize)) {
        estimate_ = handSize.cast<track::HandSizeEstimate>();
        size = estimate_->dimensions;
        shape = estimate_->shape;
      } else if (!handSize.is_none()) {
        try {
          const auto pair = handSize.cast<std::pair<float, float>>();
          size = {pair.first, pair.second};
        } catch (const py::cast_error&) {
          throw py::value_error("hand_size must be None or (length, width) in metres");
        }
      }
      checkLength(size.length, "hand_size: length");
      checkWidth(size.width, "hand_size: width");
      hand_ = model::makeDefaultHand(size, model::Side::Right, shape);
      handSize_ = io::HandSizeRecord{size};
    }

    track::TrackerSettings settings;
    settings.hands = hands;
    settings.threads = threads;
    settings.perFrame = perFrame;
    if (behindUser) settings.split.placement = CameraPlacement::kBehindUser;
    if (spec.minRangeM && *spec.minRangeM > 0.0f)
      settings.cloud.segmentation.sensorMinRangeM = *spec.minRangeM;
    if (py::isinstance<py::bool_>(detector)) {
      settings.detector.enabled = detector.cast<bool>();
    } else {
      settings.detector.weights = existingPath(detector, "detector").string();
    }
    applySettingsByName(settingsByName, settings);
    if (autoSize) {
      // As `dynahand track --hand-size auto`: the first frames read ahead, the size estimated
      // from them, the built-in hand of that size; tracking then starts afresh at frame 0.
      track::HandSizeOptions options;
      options.tracker = settings;
      options.threads = threads;
      estimate_ = estimateSize(frames.is_none() ? camera : frames, intrinsics_, fps_, 0.001f,
                               std::nullopt, handSizeFrames, options);
      hand_ = model::makeDefaultHand(estimate_->dimensions, model::Side::Right, estimate_->shape);
    }
    if (estimate_) handSize_ = io::HandSizeRecord::fromEstimate(*estimate_);
    auto created = track::Tracker::create(*hand_, intrinsics_, settings);
    if (!created) {
      if (!settings.detector.weights.empty()) throw FileError(created.message());
      throw py::value_error(created.message());
    }
    tracker_ = std::move(*created);
    frame_ = DepthFrame(intrinsics_.width, intrinsics_.height, 0.001f);
  }

  py::list track(const py::handle& depth, float depthScale, std::optional<double> timestamp) {
    if (!(depthScale > 0.0f && std::isfinite(depthScale)))
      throw py::value_error("depth_scale must be a positive number (metres per unit)");
    if (timestamp && !std::isfinite(*timestamp)) throw py::value_error("timestamp must be finite");
    const auto pixels = depthInput(depth, intrinsics_.width, intrinsics_.height);
    const std::uint16_t* data = pixels.data();
    track::TrackResult result;
    {
      // The numpy buffer stays alive (`pixels`); the tracker runs without the GIL, one call at
      // a time per Tracker.
      py::gil_scoped_release nogil;
      std::lock_guard<std::mutex> lock(mutex_);
      std::memcpy(frame_.depth.data(), data, frame_.depth.size() * sizeof(std::uint16_t));
      frame_.depthScale = depthScale;
      // As a recording's frames: frame i at i / fps (the tracker's finger-flip cycle uses it).
      frame_.timestamp = timestamp ? *timestamp : frames_ / fps_;
      ++frames_;
      result = tracker_->track(frame_);
      last_ = result;
    }
    py::list hands;
    for (const auto& h : result.hands) hands.append(py::cast(handOut(h)));
    return hands;
  }

  // `side` ("right" or "left") as a hand this tracker tracks.
  model::Side trackedSide(const std::string& side) const {
    if (side != "right" && side != "left") throw py::value_error("side must be 'right' or 'left'");
    if (side == "left" && tracker_->settings().hands == 1)
      throw py::value_error("side 'left': this tracker tracks one (right) hand");
    return side == "right" ? model::Side::Right : model::Side::Left;
  }

  void initialize(const py::handle& keypoints, const std::string& side) {
    const model::Side hand = trackedSide(side);
    const auto k = keypointsInput(keypoints, "initialize");
    if (!k) throw py::value_error("initialize: keypoints are all NaN");
    std::lock_guard<std::mutex> lock(mutex_);
    const Status s = tracker_->initializeFromKeypoints(*k, hand);
    if (!s) throw py::value_error("initialize: " + s.message());
  }

  void setKeypoints(const py::handle& keypoints, const py::handle& confidence,
                    const std::string& side) {
    const model::Side hand = trackedSide(side);
    const auto k = keypointsInput(keypoints, "set_keypoints");
    if (!k) throw py::value_error("set_keypoints: keypoints are all NaN");
    detect::DetectedKeypoints given;
    given.valid = true;
    given.points = *k;
    given.confidence.fill(1.0f);
    if (!confidence.is_none()) {
      auto c = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(confidence);
      if (!c) {
        PyErr_Clear();
        throw py::value_error("set_keypoints: confidence is not an array of numbers");
      }
      if (c.ndim() != 1 || c.shape(0) != 21)
        throw py::value_error("set_keypoints: confidence must have shape (21,)");
      for (py::ssize_t i = 0; i < 21; ++i) {
        const double v = c.at(i);
        if (!(v >= 0.0 && v <= 1.0))
          throw py::value_error("set_keypoints: confidences must be in [0, 1]");
        given.confidence[static_cast<std::size_t>(i)] = static_cast<float>(v);
      }
    }
    std::lock_guard<std::mutex> lock(mutex_);
    tracker_->setKeypoints(given, hand);
  }

  void reset() {
    std::lock_guard<std::mutex> lock(mutex_);
    tracker_->reset();
  }

  std::string resultJson() const {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!last_) throw py::value_error("result_json: no frame tracked yet");
    io::JsonOptions json;
    json.handSize = handSize_;
    return io::trackResultToJson(*last_, *hand_, json);
  }

  const Intrinsics& intrinsics() const { return intrinsics_; }
  double fps() const { return fps_; }
  int frames() const { return frames_; }
  int hands() const { return tracker_->settings().hands; }
  bool detectorEnabled() const { return tracker_->settings().detector.enabled; }
  std::string detectorWeights() const { return tracker_->settings().detector.weights; }
  py::object handSize() const {
    if (!handSize_) return py::none();
    return py::make_tuple(handSize_->dimensions.length, handSize_->dimensions.width);
  }
  const std::optional<track::HandSizeEstimate>& handSizeEstimate() const { return estimate_; }
  std::vector<std::string> bodyNames() const {
    std::vector<std::string> names;
    for (const auto& b : hand_->bodies()) names.push_back(b.name);
    return names;
  }

 private:
  std::optional<model::ArticulatedModel> hand_;  // set by the constructor
  std::optional<io::HandSizeRecord> handSize_;
  std::optional<track::HandSizeEstimate> estimate_;  // hand_size 'auto' or a HandSize
  std::unique_ptr<track::Tracker> tracker_;
  Intrinsics intrinsics_;
  double fps_ = 30.0;
  int frames_ = 0;
  DepthFrame frame_;
  std::optional<track::TrackResult> last_;
  mutable std::mutex mutex_;
};

}  // namespace

void bindTracker(py::module_& m) {
  py::class_<HandOut>(m, "HandResult",
                      "One hand's result for one frame (Tracker.track). Arrays are float32, "
                      "metres; NaN where the hand is not tracked.")
      .def_readonly("side", &HandOut::side, "'right' or 'left'.")
      .def_readonly("tracked", &HandOut::tracked, "Whether the hand is tracked this frame.")
      .def_readonly("keypoints21", &HandOut::keypoints21,
                    "(21, 3) keypoints, m, camera frame, MediaPipe order (0 wrist, 1-4 thumb, "
                    "5-8 index, 9-12 middle, 13-16 ring, 17-20 pinky): the pose's moved toward "
                    "the detector's (DetectorSettings.reportBlend).")
      .def_readonly("skeleton_keypoints21", &HandOut::skeletonKeypoints21,
                    "(21, 3) the pose's own keypoints, m, MediaPipe order.")
      .def_readonly("openxr26", &HandOut::openxr26,
                    "(26, 8) OpenXR hand joints (XrHandJointEXT order): x, y, z (m), qw, qx, qy, "
                    "qz, radius (m).")
      .def_readonly("bodies", &HandOut::bodies,
                    "(17, 7) body poses of the hand model (Tracker.body_names order): x, y, z "
                    "(m), qw, qx, qy, qz.")
      .def_readonly("error", &HandOut::error, "The winning simulation's total error, m.")
      .def_readonly("fit_error", &HandOut::fitError, "Sum of the per-body fit errors, m.")
      .def_readonly("occlusion_error", &HandOut::occlusionError,
                    "Sum of the per-body occlusion errors, m.")
      .def_readonly("body_error", &HandOut::bodyError, "(17,) fit + occlusion error per body, m.")
      .def_readonly("simulation", &HandOut::simulation,
                    "The winning simulation: normal, gross_motion, grasp_bias, finger_flip, "
                    "feature_detection or detector_fit.")
      .def_readonly("acquired", &HandOut::acquired,
                    "Whether this frame (re)acquired the hand from scratch.")
      .def_readonly("points", &HandOut::points, "Sample points used.")
      .def_readonly("data_near_model", &HandOut::dataNearModel,
                    "Share of the hand's sample points within 10 mm of the model (those "
                    "beyond its wrist left out).")
      .def_readonly("model_on_hand", &HandOut::modelOnHand,
                    "Share of the camera-facing model surface over segmented pixels.")
      .def_readonly("fingertips_off_hand", &HandOut::fingertipsOffHand,
                    "Fingertip keypoints projecting onto background.")
      .def_readonly("detected", &HandOut::detected, "Whether the learned detector ran.")
      .def_readonly("detector_keypoints21", &HandOut::detectorKeypoints21,
                    "(21, 3) the learned detector's keypoints, m (NaN when it did not run).")
      .def_readonly("detector_confidence", &HandOut::detectorConfidence,
                    "(21,) the detector's confidence per keypoint, [0, 1].")
      .def_readonly("detector_disagreement", &HandOut::detectorDisagreement,
                    "Mean distance of the keypoints from the detector's confident ones, m.")
      .def_readonly("disagreeing_frames", &HandOut::disagreeingFrames,
                    "Frames in a row the disagreement exceeded its threshold.")
      .def("__repr__", [](const HandOut& h) {
        char s[160];
        std::snprintf(s, sizeof s, "HandResult(side='%s', tracked=%s, error=%.4f, simulation='%s')",
                      h.side.c_str(), h.tracked ? "True" : "False", static_cast<double>(h.error),
                      h.simulation.c_str());
        return std::string(s);
      });

  py::class_<track::HandSizeEstimate>(
      m, "HandSize",
      "A hand size estimated from depth frames (estimate_hand_size(), Tracker(hand_size='auto')):"
      " the size of the built-in hand that best explains the frames, as `dynahand track "
      "--hand-size auto` estimates it. Pass it to Tracker as hand_size.")
      .def_property_readonly(
          "length", [](const track::HandSizeEstimate& e) { return e.dimensions.length; },
          "Hand length, wrist crease to middle fingertip, m.")
      .def_property_readonly(
          "width", [](const track::HandSizeEstimate& e) { return e.dimensions.width; },
          "Palm width across the knuckles, m.")
      .def_readonly("fit_score", &track::HandSizeEstimate::fitScore,
                    "The best candidate's fit score in [0, 1] (about 0.98-0.99 on clean synthetic "
                    "data; low values: the estimate is unreliable).")
      .def_readonly("frames_used", &track::HandSizeEstimate::framesUsed,
                    "Frames each candidate model tracked.")
      .def_readonly("candidates", &track::HandSizeEstimate::candidates,
                    "Candidate models tracked (13 for the size, 7 with a length or width "
                    "given, 1 with both or seen from behind; up to 24 more for the "
                    "metacarpals).")
      .def_property_readonly(
          "metacarpals",
          [](const track::HandSizeEstimate& e) {
            const auto& b = e.shape.boneLength;
            return py::make_tuple(b[0][0], b[1][0], b[2][0], b[3][0], b[4][0]);
          },
          "Each digit's metacarpal length factor, thumb to pinky (1: the built-in hand's; 1 "
          "when no frame showed the palm to the camera).")
      .def(
          "to_dict",
          [](const track::HandSizeEstimate& e) {
            py::dict d;
            d["length"] = e.dimensions.length;
            d["width"] = e.dimensions.width;
            d["fit_score"] = e.fitScore;
            d["frames_used"] = e.framesUsed;
            d["candidates"] = e.candidates;
            py::list metacarpals;
            for (const auto& digit : e.shape.boneLength) metacarpals.append(digit[0]);
            d["metacarpals"] = metacarpals;
            return d;
          },
          "The estimate as a dict.")
      .def("__repr__", [](const track::HandSizeEstimate& e) {
        char s[160];
        std::snprintf(s, sizeof s,
                      "HandSize(length=%.4f, width=%.4f, fit_score=%.3f, frames_used=%d, "
                      "candidates=%d)",
                      static_cast<double>(e.dimensions.length),
                      static_cast<double>(e.dimensions.width), static_cast<double>(e.fitScore),
                      e.framesUsed, e.candidates);
        return std::string(s);
      });

  py::class_<PyTracker>(m, "Tracker",
                        "Tracks one or two hands in depth frames, as `dynahand track` does (same "
                        "model, settings and learned detector, so the same results frame by "
                        "frame).")
      .def(py::init<const py::object&, int, const py::object&, const py::object&, int, bool,
                    std::optional<double>, const py::object&, const py::object&, int, bool,
                    const py::object&>(),
           py::arg("camera"), py::arg("hands") = 1, py::arg("hand_size") = py::none(),
           py::arg("detector") = true, py::arg("threads") = 1, py::arg("per_frame") = false,
           py::arg("fps") = py::none(), py::arg("model_file") = py::none(),
           py::arg("frames") = py::none(), py::arg("hand_size_frames") = kDefaultSizeFrames,
           py::arg("behind_user") = false, py::arg("settings") = py::none(),
           "camera: a Camera, a dict (width, height, fx, fy, cx, cy[, fps][, min_range_m]) or a "
           "Sequence / SyntheticClip (its camera, fps and near range: min_range_m, m, tells the "
           "segmentation where the sensor cuts off an arm reaching past it).\n"
           "hands: 1 or 2 (behind_user: the camera looks along the user's view, worn on the head, "
           "so their left hand is on the image's left; default: it faces the user). hand_size: "
           "None (0.19, 0.085) or (length, width) of the built-in hand, "
           "m; a HandSize (estimate_hand_size()); or 'auto': estimated as `dynahand track "
           "--hand-size auto` does, from the first hand_size_frames (10..600, default 30) "
           "frames of `frames` (default: camera, when it is a Sequence or SyntheticClip; bare "
           "arrays are read at depth scale 0.001), before anything is tracked: track() then "
           "starts at frame 0 with the estimated hand (hand_size_estimate). model_file: a hand "
           "model file instead. detector: True (the shipped weights, or $DYNAHAND_DETECTOR), "
           "False, or an ONNX file. threads: threads for a frame's simulations (and the size "
           "estimate's candidates; results identical for any count). per_frame: acquire every "
           "frame afresh. fps: frame rate for default timestamps (default: the camera's, else "
           "30). settings: {name: value} of tracker settings by the names `dynahand settings` "
           "lists (e.g. {'detector.selectionWeight': 0}), as `dynahand track --set`.")
      .def("track", &PyTracker::track, py::arg("depth"), py::arg("depth_scale") = 0.001f,
           py::arg("timestamp") = py::none(),
           "Tracks one (H, W) uint16 depth frame (metres = value * depth_scale; 0 = no data). "
           "timestamp: seconds (default: frames tracked so far / fps). Returns a list of "
           "HandResult, one per hand (right first). Runs without the GIL.")
      .def("initialize", &PyTracker::initialize, py::arg("keypoints21"), py::arg("side") = "right",
           "Starts from 21 known keypoints of the next frame ((21, 3), m), fitted under the joint "
           "limits (as `dynahand track --init gt`).")
      .def("set_keypoints", &PyTracker::setKeypoints, py::arg("keypoints21"),
           py::arg("confidence") = py::none(), py::arg("side") = "right",
           "Keypoints of the next frame's hand from another source ((21, 3), m, camera frame; "
           "confidence (21,) in [0, 1], default 1), used by the next track() call instead of "
           "the learned detector's (Tracker::setKeypoints): e.g. a colour-image detector "
           "registered to the depth camera. Works with detector=False.")
      .def("reset", &PyTracker::reset, "Forgets the hands: the next frame acquires from scratch.")
      .def("result_json", &PyTracker::resultJson,
           "The last frame as the JSON line `dynahand track --out poses.jsonl` writes.")
      .def_property_readonly("camera", &PyTracker::intrinsics, "The camera.")
      .def_property_readonly("fps", &PyTracker::fps, "Frames per second (default timestamps).")
      .def_property_readonly("frames", &PyTracker::frames, "Frames tracked so far.")
      .def_property_readonly("hands", &PyTracker::hands, "Hands tracked (1 or 2).")
      .def_property_readonly("hand_size", &PyTracker::handSize,
                             "(length, width) of the built-in hand, m; None for a model file.")
      .def_property_readonly("hand_size_estimate", &PyTracker::handSizeEstimate,
                             "The HandSize the hand was built from (hand_size 'auto' or a "
                             "HandSize); None for a given size or a model file.")
      .def_property_readonly("detector", &PyTracker::detectorEnabled,
                             "Whether the learned detector runs (False when no weights found).")
      .def_property_readonly("detector_weights", &PyTracker::detectorWeights,
                             "The detector's ONNX file ('' when it does not run).")
      .def_property_readonly("body_names", &PyTracker::bodyNames,
                             "The model's 17 body names (rows of HandResult.bodies).")
      .def_property_readonly_static(
          "openxr_joint_names",
          [](const py::object&) {
            const auto& names = model::openXrJointNames();
            return std::vector<std::string>(names.begin(), names.end());
          },
          "The 26 OpenXR joint names (rows of HandResult.openxr26).");

  m.def("estimate_hand_size", &estimateHandSizePy, py::arg("frames"),
        py::arg("camera") = py::none(), py::arg("start_keypoints") = py::none(),
        py::arg("frames_used") = kDefaultSizeFrames, py::arg("threads") = 1,
        py::arg("length") = py::none(), py::arg("width") = py::none(), py::arg("hands") = 1,
        py::arg("per_frame") = false, py::arg("depth_scale") = 0.001, py::arg("fps") = py::none(),
        py::arg("metacarpals") = true,
        "Estimates the built-in hand's size from the first frames_used (10..600) frames, as "
        "`dynahand track --hand-size auto --hand-size-frames N` does: candidate sizes are each "
        "tracked over the frames and scored by how well they explain the data. frames: a "
        "Sequence, a SyntheticClip, an (N, H, W) uint16 array or an iterable of (H, W) arrays "
        "or (depth, depth_scale, ...) tuples (read no further than frames_used; frame i at "
        "i / fps s; bare arrays at depth_scale). camera: default frames' own (a Sequence or "
        "SyntheticClip). start_keypoints: the first frame's (21, 3) keypoints, m (as --init "
        "gt; then call Tracker.initialize with them too), else the candidates start from the "
        "hand the learned detector finds in the first 6 frames (needs more than 6 frames). length "
        "or width: a known one, kept (--hand-"
        "length / --hand-width; both: the metacarpals alone). metacarpals: also each digit's "
        "metacarpal length (False: the "
        "size alone, as --hand-size-only). hands, per_frame: the tracker's settings. threads: "
        "candidates "
        "in parallel (the result does not depend on it). Returns a HandSize; runs without the "
        "GIL. ValueError for bad arguments or too few frames, OSError for an unreadable frame.");
}

}  // namespace dynahand::python
