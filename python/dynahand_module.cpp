// `import dynahand`: the Python binding (docs/python.md). Tracker, sequences on disk, synthetic
// clips in memory and the accuracy metrics of `dynahand eval`, on numpy arrays. Bad input is a
// ValueError, a file problem an OSError (FileNotFoundError for a missing path), each carrying
// the library's message; nothing here asserts on user input.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "dynahand/depth_frame.h"
#include "dynahand/metrics.h"
#include "dynahand/model.h"
#include "dynahand/model_pose.h"
#include "dynahand/sequence.h"
#include "dynahand/synth.h"
#include "dynahand/track_io.h"
#include "dynahand/tracker.h"

namespace py = pybind11;

namespace dynahand::python {
namespace {

// ---- errors ------------------------------------------------------------------------------

// A file that cannot be read (OSError in Python) and a path that does not exist
// (FileNotFoundError, a subclass of OSError).
struct FileError : std::runtime_error {
  using std::runtime_error::runtime_error;
};
struct FileMissing : FileError {
  using FileError::FileError;
};

std::string typeName(const py::handle& obj) {
  return py::str(py::type::handle_of(obj).attr("__name__")).cast<std::string>();
}

std::filesystem::path existingPath(const py::object& path, const char* what) {
  std::filesystem::path p;
  try {
    p = py::str(py::module_::import("os").attr("fspath")(path)).cast<std::string>();
  } catch (const py::error_already_set&) {
    throw py::value_error(std::string(what) + " must be a str or path-like object (got " +
                          typeName(path) + ")");
  }
  std::error_code ec;
  if (!std::filesystem::exists(p, ec)) throw FileMissing(p.string() + ": no such file or folder");
  return p;
}

// ---- numpy conversion ----------------------------------------------------------------------

using F32Array = py::array_t<float, py::array::c_style>;

F32Array keypointsArray(const std::array<Vec3, 21>& k, bool valid = true) {
  F32Array a({21, 3});
  auto m = a.mutable_unchecked<2>();
  for (py::ssize_t i = 0; i < 21; ++i)
    for (py::ssize_t j = 0; j < 3; ++j)
      m(i, j) = valid ? k[static_cast<std::size_t>(i)][j] : std::numeric_limits<float>::quiet_NaN();
  return a;
}

// Rows x, y, z, qw, qx, qy, qz (a pose), NaN when not valid.
void putPose(py::detail::unchecked_mutable_reference<float, 2>& m, py::ssize_t row, const Pose& p,
             bool valid) {
  const float values[7] = {p.p.x(), p.p.y(), p.p.z(), p.q.w(), p.q.x(), p.q.y(), p.q.z()};
  for (py::ssize_t j = 0; j < 7; ++j)
    m(row, j) = valid ? values[j] : std::numeric_limits<float>::quiet_NaN();
}

// The depth image without a copy: the numpy array owns the frame's buffer.
py::array_t<std::uint16_t> depthArray(std::vector<std::uint16_t>&& pixels, int width, int height) {
  auto* owned = new std::vector<std::uint16_t>(std::move(pixels));
  py::capsule owner(owned, [](void* p) { delete static_cast<std::vector<std::uint16_t>*>(p); });
  const py::ssize_t w = width, h = height;
  const auto item = static_cast<py::ssize_t>(sizeof(std::uint16_t));
  return py::array_t<std::uint16_t>({h, w}, {w * item, item}, owned->data(), owner);
}

// A (H, W) uint16 array as a C-contiguous array (the same buffer when it already is one).
py::array_t<std::uint16_t, py::array::c_style> depthInput(const py::handle& obj, int width,
                                                          int height) {
  if (!py::isinstance<py::array>(obj))
    throw py::value_error("depth must be a numpy uint16 array of shape (H, W) (got " +
                          typeName(obj) + ")");
  auto a = py::reinterpret_borrow<py::array>(obj);
  if (!a.dtype().equal(py::dtype::of<std::uint16_t>()))
    throw py::value_error("depth must have dtype uint16 (got " +
                          py::str(a.dtype()).cast<std::string>() + ")");
  if (a.ndim() != 2)
    throw py::value_error("depth must be a 2-D (H, W) array (got " + std::to_string(a.ndim()) +
                          " dimensions)");
  if (a.shape(0) != height || a.shape(1) != width)
    throw py::value_error("depth is " + std::to_string(a.shape(0)) + " x " +
                          std::to_string(a.shape(1)) + " (H x W) but the camera is " +
                          std::to_string(height) + " x " + std::to_string(width));
  return py::array_t<std::uint16_t, py::array::c_style>::ensure(a);
}

// Keypoints (21, 3) from any array-like; nullopt for None or an all-NaN row.
std::optional<std::array<Vec3, 21>> keypointsInput(const py::handle& obj, const std::string& what) {
  if (obj.is_none()) return std::nullopt;
  auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(obj);
  if (!a) {
    PyErr_Clear();
    throw py::value_error(what + ": not an array of numbers (got " + typeName(obj) + ")");
  }
  if (a.ndim() != 2 || a.shape(0) != 21 || a.shape(1) != 3)
    throw py::value_error(what + ": keypoints must have shape (21, 3)");
  auto r = a.unchecked<2>();
  int nans = 0;
  std::array<Vec3, 21> k{};
  for (py::ssize_t i = 0; i < 21; ++i)
    for (py::ssize_t j = 0; j < 3; ++j) {
      const double v = r(i, j);
      if (std::isnan(v)) ++nans;
      k[static_cast<std::size_t>(i)][j] = static_cast<float>(v);
    }
  if (nans == 63) return std::nullopt;
  if (nans > 0)
    throw py::value_error(what + ": keypoints partly NaN (a frame without a hand is all NaN)");
  return k;
}

// ---- cameras -------------------------------------------------------------------------------

Intrinsics checkedIntrinsics(const Intrinsics& k) {
  if (const std::string problem = k.problem(); !problem.empty())
    throw py::value_error("camera: " + problem);
  return k;
}

struct CameraSpec {
  Intrinsics intrinsics;
  std::optional<double> fps;
};

// A Camera, a dict {width, height, fx, fy, cx, cy[, fps]}, or anything with a `camera`
// attribute (a Sequence, a SyntheticClip) and maybe `fps`.
CameraSpec cameraSpec(const py::handle& obj) {
  CameraSpec spec;
  if (py::isinstance<Intrinsics>(obj)) {
    spec.intrinsics = obj.cast<Intrinsics>();
  } else if (py::isinstance<py::dict>(obj)) {
    auto d = py::reinterpret_borrow<py::dict>(obj);
    for (const char* key : {"width", "height", "fx", "fy", "cx", "cy"})
      if (!d.contains(key)) throw py::value_error(std::string("camera dict lacks '") + key + "'");
    try {
      spec.intrinsics.width = d["width"].cast<int>();
      spec.intrinsics.height = d["height"].cast<int>();
      spec.intrinsics.fx = d["fx"].cast<float>();
      spec.intrinsics.fy = d["fy"].cast<float>();
      spec.intrinsics.cx = d["cx"].cast<float>();
      spec.intrinsics.cy = d["cy"].cast<float>();
      if (d.contains("fps")) spec.fps = d["fps"].cast<double>();
    } catch (const py::cast_error&) {
      throw py::value_error("camera dict: width and height must be ints, fx fy cx cy numbers");
    }
  } else if (py::hasattr(obj, "camera")) {
    spec = cameraSpec(obj.attr("camera"));
    if (py::hasattr(obj, "fps")) spec.fps = obj.attr("fps").cast<double>();
  } else {
    throw py::value_error(
        "camera must be a dynahand.Camera, a dict with width, height, fx, fy, cx, cy, or a "
        "sequence / synthetic clip (got " +
        typeName(obj) + ")");
  }
  checkedIntrinsics(spec.intrinsics);
  return spec;
}

// ---- tracker -------------------------------------------------------------------------------

// One hand of one frame, as Python sees it.
struct HandOut {
  std::string side;
  bool tracked = false;
  F32Array keypoints21, openxr26, bodies, bodyError, detectorKeypoints21, detectorConfidence;
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

class PyTracker {
 public:
  PyTracker(const py::object& camera, int hands, const py::object& handSize,
            const py::object& detector, int threads, bool perFrame, std::optional<double> fps,
            const py::object& modelFile) {
    const CameraSpec spec = cameraSpec(camera);
    intrinsics_ = spec.intrinsics;
    fps_ = fps ? *fps : spec.fps.value_or(30.0);
    if (!(fps_ > 0.0 && std::isfinite(fps_))) throw py::value_error("fps must be > 0");
    if (hands != 1 && hands != 2) throw py::value_error("hands must be 1 or 2");
    if (threads < 1 || threads > 64) throw py::value_error("threads must be 1..64");

    if (!modelFile.is_none()) {
      if (!handSize.is_none()) throw py::value_error("hand_size and model_file are exclusive");
      const std::filesystem::path file = existingPath(modelFile, "model_file");
      auto loaded = model::loadModel(file);
      if (!loaded) throw FileError(loaded.message());
      hand_ = std::move(*loaded);
    } else {
      model::HandDimensions size;  // `dynahand track`'s default, 0.19 x 0.085 m
      if (py::isinstance<py::str>(handSize)) {
        throw py::value_error("hand_size must be None or (length, width) in metres (got '" +
                              handSize.cast<std::string>() +
                              "'; the automatic estimate of `dynahand track --hand-size auto` "
                              "is not offered here)");
      } else if (!handSize.is_none()) {
        try {
          const auto pair = handSize.cast<std::pair<float, float>>();
          size = {pair.first, pair.second};
        } catch (const py::cast_error&) {
          throw py::value_error("hand_size must be None or (length, width) in metres");
        }
      }
      if (!(size.length >= 0.10f && size.length <= 0.30f))
        throw py::value_error("hand_size: length must be in [0.10, 0.30] m");
      if (!(size.width >= 0.05f && size.width <= 0.15f))
        throw py::value_error("hand_size: width must be in [0.05, 0.15] m");
      hand_ = model::makeDefaultHand(size);
      handSize_ = io::HandSizeRecord{size};
    }

    track::TrackerSettings settings;
    settings.hands = hands;
    settings.threads = threads;
    settings.perFrame = perFrame;
    if (py::isinstance<py::bool_>(detector)) {
      settings.detector.enabled = detector.cast<bool>();
    } else {
      settings.detector.weights = existingPath(detector, "detector").string();
    }
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

  void initialize(const py::handle& keypoints, const std::string& side) {
    if (side != "right" && side != "left") throw py::value_error("side must be 'right' or 'left'");
    if (side == "left" && tracker_->settings().hands == 1)
      throw py::value_error("side 'left': this tracker tracks one (right) hand");
    const auto k = keypointsInput(keypoints, "initialize");
    if (!k) throw py::value_error("initialize: keypoints are all NaN");
    std::lock_guard<std::mutex> lock(mutex_);
    const Status s = tracker_->initializeFromKeypoints(
        *k, side == "right" ? model::Side::Right : model::Side::Left);
    if (!s) throw py::value_error("initialize: " + s.message());
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
  std::vector<std::string> bodyNames() const {
    std::vector<std::string> names;
    for (const auto& b : hand_->bodies()) names.push_back(b.name);
    return names;
  }

 private:
  std::optional<model::ArticulatedModel> hand_;  // set by the constructor
  std::optional<io::HandSizeRecord> handSize_;
  std::unique_ptr<track::Tracker> tracker_;
  Intrinsics intrinsics_;
  double fps_ = 30.0;
  int frames_ = 0;
  DepthFrame frame_;
  std::optional<track::TrackResult> last_;
  mutable std::mutex mutex_;
};

// ---- sequences ----------------------------------------------------------------------------

int checkedIndex(py::ssize_t index, int count) {
  const py::ssize_t i = index < 0 ? index + count : index;
  if (i < 0 || i >= count)
    throw py::index_error("frame " + std::to_string(index) + " out of range (" +
                          std::to_string(count) + " frames)");
  return static_cast<int>(i);
}

py::object groundTruthObject(const std::optional<std::array<Vec3, 21>>& k) {
  if (!k) return py::none();
  return keypointsArray(*k);
}

class PySequence {
 public:
  explicit PySequence(SequenceReader reader) : reader_(std::move(reader)) {}

  int size() const { return reader_.frameCount(); }
  const SequenceInfo& info() const { return reader_.info(); }

  py::tuple frame(py::ssize_t index) const {
    const int i = checkedIndex(index, size());
    auto f = reader_.frame(i);
    if (!f) throw FileError(f.message());
    const float scale = f->depthScale;
    const int w = f->width, h = f->height;
    return py::make_tuple(depthArray(std::move(f->depth), w, h), scale,
                          groundTruthObject(reader_.groundTruth(i)));
  }
  py::object groundTruth(py::ssize_t index) const {
    return groundTruthObject(reader_.groundTruth(checkedIndex(index, size())));
  }
  F32Array groundTruthArray() const {
    F32Array a({static_cast<py::ssize_t>(size()), py::ssize_t{21}, py::ssize_t{3}});
    auto m = a.mutable_unchecked<3>();
    for (int f = 0; f < size(); ++f) {
      const auto k = reader_.groundTruth(f);
      for (py::ssize_t i = 0; i < 21; ++i)
        for (py::ssize_t j = 0; j < 3; ++j)
          m(f, i, j) =
              k ? (*k)[static_cast<std::size_t>(i)][j] : std::numeric_limits<float>::quiet_NaN();
    }
    return a;
  }

 private:
  SequenceReader reader_;
};

std::unique_ptr<PySequence> openSequence(const py::object& path, const py::object& camera,
                                         std::optional<float> depthScale) {
  const std::filesystem::path p = existingPath(path, "path");
  SequenceOpenOptions options;
  if (!camera.is_none()) options.intrinsics = cameraSpec(camera).intrinsics;
  if (depthScale) {
    if (!(*depthScale > 0.0f && std::isfinite(*depthScale)))
      throw py::value_error("depth_scale must be a positive number (metres per unit)");
    options.depthScale = depthScale;
  }
  auto reader = SequenceReader::open(p, options);
  if (!reader) throw FileError(reader.message());
  return std::make_unique<PySequence>(std::move(*reader));
}

// ---- synthetic clips -------------------------------------------------------------------------

class PySynthClip {
 public:
  explicit PySynthClip(synth::SyntheticSequence seq) : seq_(std::move(seq)) {}

  int size() const { return seq_.frameCount(); }
  int handCount() const { return seq_.handCount(); }
  const Intrinsics& intrinsics() const { return seq_.intrinsics(); }
  const synth::SynthOptions& options() const { return seq_.options(); }

  py::tuple frame(py::ssize_t index) {
    const int i = checkedIndex(index, size());
    const synth::SyntheticFrame& f = seq_.frame(i);
    std::vector<std::uint16_t> pixels = f.depth.depth;
    return py::make_tuple(depthArray(std::move(pixels), f.depth.width, f.depth.height),
                          f.depth.depthScale, keypointsArray(f.hands.front().keypoints));
  }
  F32Array groundTruth(py::ssize_t index, int hand) const {
    const int i = checkedIndex(index, size());
    if (hand < 0 || hand >= handCount())
      throw py::value_error("hand " + std::to_string(hand) + " out of range (" +
                            std::to_string(handCount()) + " hands)");
    return keypointsArray(seq_.truth(i, hand).keypoints);
  }
  F32Array pose(py::ssize_t index, int hand) const {
    const int i = checkedIndex(index, size());
    if (hand < 0 || hand >= handCount())
      throw py::value_error("hand " + std::to_string(hand) + " out of range");
    const model::ModelPose p = seq_.truth(i, hand).pose;
    const auto n = static_cast<py::ssize_t>(p.bodies.size());
    F32Array a({n, py::ssize_t{7}});
    auto m = a.mutable_unchecked<2>();
    for (py::ssize_t b = 0; b < n; ++b) putPose(m, b, p.bodies[static_cast<std::size_t>(b)], true);
    return a;
  }
  py::tuple arrays() {
    const Intrinsics& k = intrinsics();
    const py::ssize_t n = size(), h = k.height, w = k.width;
    py::array_t<std::uint16_t> depth({n, h, w});
    F32Array truth({n, py::ssize_t{21}, py::ssize_t{3}});
    auto t = truth.mutable_unchecked<3>();
    for (int f = 0; f < size(); ++f) {
      const synth::SyntheticFrame& frame = seq_.frame(f);
      std::memcpy(depth.mutable_data(f), frame.depth.depth.data(),
                  frame.depth.depth.size() * sizeof(std::uint16_t));
      for (py::ssize_t i = 0; i < 21; ++i)
        for (py::ssize_t j = 0; j < 3; ++j)
          t(f, i, j) = frame.hands.front().keypoints[static_cast<std::size_t>(i)][j];
    }
    return py::make_tuple(depth, truth);
  }

 private:
  synth::SyntheticSequence seq_;
};

std::unique_ptr<PySynthClip> makeSynth(const std::string& motion, int frames,
                                       const std::string& profile, const std::string& placement,
                                       std::uint64_t seed, float fps, float speed,
                                       const std::string& background, bool table,
                                       const py::object& handSize, float proportionSpread,
                                       std::uint64_t proportionSeed) {
  synth::SynthOptions o;  // `dynahand synth`'s defaults unless given
  o.clip = motion;
  o.frameCount = frames;
  o.profile = profile;
  o.seed = seed;
  o.framesPerSecond = fps;
  o.speed = speed;
  if (placement == "desk") {
    o.scene.placement = synth::CameraPlacement::DeskFacing;
  } else if (placement == "head") {
    o.scene.placement = synth::CameraPlacement::HeadMounted;
  } else {
    throw py::value_error("placement must be 'desk' or 'head' (got '" + placement + "')");
  }
  if (background == "none") {
    o.scene.background = synth::Background::None;
  } else if (background == "wall") {
    o.scene.background = synth::Background::Wall;
  } else if (background == "torso") {
    o.scene.background = synth::Background::Torso;
  } else {
    throw py::value_error("background must be 'none', 'wall' or 'torso' (got '" + background +
                          "')");
  }
  o.scene.table = table;
  if (!handSize.is_none()) {
    try {
      const auto pair = handSize.cast<std::pair<float, float>>();
      o.hand = {pair.first, pair.second};
    } catch (const py::cast_error&) {
      throw py::value_error("hand_size must be None or (length, width) in metres");
    }
  }
  if (!(proportionSpread >= 0.0f && proportionSpread <= 0.5f))
    throw py::value_error("proportion_spread must be in [0, 0.5]");
  o.proportions = synth::randomProportions(proportionSeed, proportionSpread);
  auto seq = synth::SyntheticSequence::create(o);
  if (!seq) throw py::value_error(seq.message());
  return std::make_unique<PySynthClip>(std::move(*seq));
}

// ---- metrics -----------------------------------------------------------------------------

std::vector<std::optional<eval::Keypoints21>> keypointSequence(const py::handle& obj,
                                                               const char* what) {
  std::vector<std::optional<eval::Keypoints21>> out;
  const std::string name = what;
  if (py::isinstance<py::list>(obj) || py::isinstance<py::tuple>(obj)) {
    std::size_t i = 0;
    for (const py::handle item : obj)
      out.push_back(keypointsInput(item, name + " frame " + std::to_string(i++)));
    return out;
  }
  auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(obj);
  if (!a) {
    PyErr_Clear();
    throw py::value_error(name + ": not an (N, 21, 3) array or a list (got " + typeName(obj) + ")");
  }
  if (a.ndim() != 3 || a.shape(1) != 21 || a.shape(2) != 3)
    throw py::value_error(name + ": must have shape (N, 21, 3)");
  for (py::ssize_t f = 0; f < a.shape(0); ++f) {
    const py::object row = a[py::int_(f)];
    out.push_back(keypointsInput(row, name + " frame " + std::to_string(f)));
  }
  return out;
}

eval::KeypointMetrics evaluate(const py::handle& gt, const py::handle& pred, double fps,
                               double lostMm) {
  if (!(fps > 0.0 && std::isfinite(fps))) throw py::value_error("fps must be > 0");
  if (!(lostMm > 0.0 && std::isfinite(lostMm))) throw py::value_error("lost_mm must be > 0");
  eval::SequenceKeypoints s;
  s.groundTruth = keypointSequence(gt, "gt");
  s.predicted = keypointSequence(pred, "pred");
  // As `dynahand eval`: the shorter side is padded with frames without a hand.
  const std::size_t n = std::max(s.groundTruth.size(), s.predicted.size());
  s.groundTruth.resize(n);
  s.predicted.resize(n);
  s.fps = fps;
  eval::MetricsOptions options;
  options.lostThresholdMm = lostMm;
  auto m = eval::computeKeypointMetrics(s, options);
  if (!m) throw py::value_error(m.message());
  return std::move(*m);
}

template <class T>
py::array_t<double> doubles(const T& values) {
  py::array_t<double> a(static_cast<py::ssize_t>(values.size()));
  std::copy(values.begin(), values.end(), a.mutable_data());
  return a;
}

// Iteration over a Sequence or a SyntheticClip, frame by frame.
template <class Seq>
struct FrameIterator {
  Seq* seq;
  int next = 0;
};

template <class Seq>
void bindFrameIterator(py::module_& m, const char* name) {
  py::class_<FrameIterator<Seq>>(m, name, "Iterator over the frames of a sequence.")
      .def("__iter__", [](FrameIterator<Seq>& it) -> FrameIterator<Seq>& { return it; })
      .def("__next__", [](FrameIterator<Seq>& it) {
        if (it.next >= it.seq->size()) throw py::stop_iteration();
        return it.seq->frame(it.next++);
      });
}

}  // namespace
}  // namespace dynahand::python

PYBIND11_MODULE(dynahand, m) {
  using namespace dynahand;
  using namespace dynahand::python;
  m.doc() =
      "dynahand: dynamics-based 3D skeletal hand tracking from depth images (docs/python.md).\n"
      "Metres, camera frame as OpenCV (x right, y down, z forward); keypoints in MediaPipe order.";
  m.attr("__version__") = DYNAHAND_VERSION;

  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const FileMissing& e) {
      PyErr_SetString(PyExc_FileNotFoundError, e.what());
    } catch (const FileError& e) {
      PyErr_SetString(PyExc_OSError, e.what());
    }
  });

  py::class_<Intrinsics>(m, "Camera",
                         "Pinhole depth camera intrinsics: image size (pixels), focal lengths and "
                         "principal point (pixels). A point (x, y, z) projects to u = fx x / z + "
                         "cx, v = fy y / z + cy.")
      .def(py::init([](int width, int height, float fx, float fy, float cx, float cy) {
             return checkedIntrinsics(Intrinsics{width, height, fx, fy, cx, cy});
           }),
           py::arg("width"), py::arg("height"), py::arg("fx"), py::arg("fy"), py::arg("cx"),
           py::arg("cy"), "A camera; ValueError when the values are not usable.")
      .def_readonly("width", &Intrinsics::width, "Image width, pixels.")
      .def_readonly("height", &Intrinsics::height, "Image height, pixels.")
      .def_readonly("fx", &Intrinsics::fx, "Focal length along x, pixels.")
      .def_readonly("fy", &Intrinsics::fy, "Focal length along y, pixels.")
      .def_readonly("cx", &Intrinsics::cx, "Principal point x, pixels.")
      .def_readonly("cy", &Intrinsics::cy, "Principal point y, pixels.")
      .def(
          "to_dict",
          [](const Intrinsics& k) {
            py::dict d;
            d["width"] = k.width;
            d["height"] = k.height;
            d["fx"] = k.fx;
            d["fy"] = k.fy;
            d["cx"] = k.cx;
            d["cy"] = k.cy;
            return d;
          },
          "The camera as a dict (what Tracker also accepts).")
      .def("__eq__",
           [](const Intrinsics& a, const Intrinsics& b) {
             return a.width == b.width && a.height == b.height && a.fx == b.fx && a.fy == b.fy &&
                    a.cx == b.cx && a.cy == b.cy;
           })
      .def("__repr__", [](const Intrinsics& k) {
        char s[160];
        std::snprintf(s, sizeof s, "Camera(width=%d, height=%d, fx=%g, fy=%g, cx=%g, cy=%g)",
                      k.width, k.height, static_cast<double>(k.fx), static_cast<double>(k.fy),
                      static_cast<double>(k.cx), static_cast<double>(k.cy));
        return std::string(s);
      });

  py::class_<HandOut>(m, "HandResult",
                      "One hand's result for one frame (Tracker.track). Arrays are float32, "
                      "metres; NaN where the hand is not tracked.")
      .def_readonly("side", &HandOut::side, "'right' or 'left'.")
      .def_readonly("tracked", &HandOut::tracked, "Whether the hand is tracked this frame.")
      .def_readonly("keypoints21", &HandOut::keypoints21,
                    "(21, 3) keypoints, m, camera frame, MediaPipe order (0 wrist, 1-4 thumb, "
                    "5-8 index, 9-12 middle, 13-16 ring, 17-20 pinky).")
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
                    "Share of the hand's sample points within 10 mm of the model.")
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

  py::class_<PyTracker>(m, "Tracker",
                        "Tracks one or two hands in depth frames, as `dynahand track` does (same "
                        "model, settings and learned detector, so the same results frame by "
                        "frame).")
      .def(py::init<const py::object&, int, const py::object&, const py::object&, int, bool,
                    std::optional<double>, const py::object&>(),
           py::arg("camera"), py::arg("hands") = 1, py::arg("hand_size") = py::none(),
           py::arg("detector") = true, py::arg("threads") = 1, py::arg("per_frame") = false,
           py::arg("fps") = py::none(), py::arg("model_file") = py::none(),
           "camera: a Camera, a dict (width, height, fx, fy, cx, cy[, fps]) or a Sequence / "
           "SyntheticClip (its camera and fps).\n"
           "hands: 1 or 2. hand_size: None (0.19, 0.085) or (length, width) of the built-in hand, "
           "m; model_file: a hand model file instead. detector: True (the shipped weights, or "
           "$DYNAHAND_DETECTOR), False, or an ONNX file. threads: threads for a frame's "
           "simulations (results identical for any count). per_frame: acquire every frame "
           "afresh. fps: frame rate for default timestamps (default: the camera's, else 30).")
      .def("track", &PyTracker::track, py::arg("depth"), py::arg("depth_scale") = 0.001f,
           py::arg("timestamp") = py::none(),
           "Tracks one (H, W) uint16 depth frame (metres = value * depth_scale; 0 = no data). "
           "timestamp: seconds (default: frames tracked so far / fps). Returns a list of "
           "HandResult, one per hand (right first). Runs without the GIL.")
      .def("initialize", &PyTracker::initialize, py::arg("keypoints21"), py::arg("side") = "right",
           "Starts from 21 known keypoints of the next frame ((21, 3), m), fitted under the joint "
           "limits (as `dynahand track --init gt`).")
      .def("reset", &PyTracker::reset, "Forgets the hands: the next frame acquires from scratch.")
      .def("result_json", &PyTracker::resultJson,
           "The last frame as the JSON line `dynahand track --out poses.jsonl` writes.")
      .def_property_readonly("camera", &PyTracker::intrinsics, "The camera.")
      .def_property_readonly("fps", &PyTracker::fps, "Frames per second (default timestamps).")
      .def_property_readonly("frames", &PyTracker::frames, "Frames tracked so far.")
      .def_property_readonly("hands", &PyTracker::hands, "Hands tracked (1 or 2).")
      .def_property_readonly("hand_size", &PyTracker::handSize,
                             "(length, width) of the built-in hand, m; None for a model file.")
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

  bindFrameIterator<PySequence>(m, "SequenceIterator");
  py::class_<PySequence>(m, "Sequence",
                         "A depth recording opened by open_sequence: len(), indexing and "
                         "iteration give frames (depth, depth_scale, ground_truth).")
      .def("__len__", &PySequence::size, "Number of frames.")
      .def("__getitem__", &PySequence::frame, py::arg("index"),
           "Frame i as (depth (H, W) uint16, depth_scale m/unit, ground truth (21, 3) float32 "
           "or None). OSError when the frame cannot be decoded.")
      .def("frame", &PySequence::frame, py::arg("index"), "The same as sequence[index].")
      .def(
          "__iter__", [](PySequence& s) { return FrameIterator<PySequence>{&s}; },
          py::keep_alive<0, 1>(), "Iterates the frames in order.")
      .def("ground_truth", &PySequence::groundTruth, py::arg("index"),
           "Frame i's ground truth (21, 3), m, or None (no hand / none recorded).")
      .def("ground_truth_array", &PySequence::groundTruthArray,
           "(N, 21, 3) float32 ground truth; rows without a hand are NaN.")
      .def_property_readonly(
          "camera", [](const PySequence& s) { return s.info().intrinsics; }, "The camera.")
      .def_property_readonly(
          "fps", [](const PySequence& s) { return s.info().framesPerSecond; },
          "Frames per second (frame i is at i / fps s).")
      .def_property_readonly(
          "depth_scale", [](const PySequence& s) { return s.info().depthScale; },
          "Metres per stored depth unit.")
      .def_property_readonly(
          "format", [](const PySequence& s) { return s.info().format; },
          "canonical, intel-rs, nyu-png, png16 or oni.")
      .def_property_readonly(
          "has_ground_truth", [](const PySequence& s) { return s.info().hasGroundTruth; },
          "Whether ground truth is recorded.")
      .def_property_readonly(
          "path", [](const PySequence& s) { return s.info().path.string(); }, "What was opened.")
      .def_property_readonly(
          "info",
          [](const PySequence& s) {
            const SequenceInfo& i = s.info();
            py::dict d;
            d["width"] = i.intrinsics.width;
            d["height"] = i.intrinsics.height;
            d["fx"] = i.intrinsics.fx;
            d["fy"] = i.intrinsics.fy;
            d["cx"] = i.intrinsics.cx;
            d["cy"] = i.intrinsics.cy;
            d["fps"] = i.framesPerSecond;
            d["depth_scale"] = i.depthScale;
            d["frames"] = i.frameCount;
            d["has_ground_truth"] = i.hasGroundTruth;
            d["format"] = i.format;
            d["path"] = i.path.string();
            return d;
          },
          "The recording's description as a dict (Tracker accepts it as camera).")
      .def("__repr__", [](const PySequence& s) {
        return "Sequence('" + s.info().path.string() + "', format='" + s.info().format +
               "', frames=" + std::to_string(s.size()) + ")";
      });

  m.def("open_sequence", &openSequence, py::arg("path"), py::arg("camera") = py::none(),
        py::arg("depth_scale") = py::none(),
        "Opens a depth recording in any format `dynahand track` reads: a canonical folder "
        "(camera.json, depth/, groundtruth.jsonl), the original authors' .rs + .json, a NYU PNG "
        "folder, a plain 16-bit PNG folder (needs camera, and depth_scale unless mm), or .oni "
        "(with OpenNI2). FileNotFoundError for a missing path, OSError for one that cannot be "
        "read.");

  bindFrameIterator<PySynthClip>(m, "SyntheticClipIterator");
  py::class_<PySynthClip>(m, "SyntheticClip",
                          "A synthetic depth clip with exact ground truth, rendered on demand "
                          "(the same frames `dynahand synth` writes).")
      .def("__len__", &PySynthClip::size, "Number of frames.")
      .def("__getitem__", &PySynthClip::frame, py::arg("index"),
           "Frame i as (depth (H, W) uint16, depth_scale, ground truth (21, 3) float32 of hand "
           "0).")
      .def("frame", &PySynthClip::frame, py::arg("index"), "The same as clip[index].")
      .def(
          "__iter__", [](PySynthClip& s) { return FrameIterator<PySynthClip>{&s}; },
          py::keep_alive<0, 1>(), "Iterates the frames in order.")
      .def("ground_truth", &PySynthClip::groundTruth, py::arg("index"), py::arg("hand") = 0,
           "Hand `hand`'s 21 keypoints (21, 3) at frame i, m (no rendering).")
      .def("pose", &PySynthClip::pose, py::arg("index"), py::arg("hand") = 0,
           "Hand `hand`'s model body poses (17, 7) at frame i: x, y, z, qw, qx, qy, qz.")
      .def("arrays", &PySynthClip::arrays,
           "Renders every frame: (depth (N, H, W) uint16, ground truth (N, 21, 3) float32 of hand "
           "0).")
      .def_property_readonly("camera", &PySynthClip::intrinsics, "The sensor profile's camera.")
      .def_property_readonly(
          "fps", [](const PySynthClip& s) { return s.options().framesPerSecond; },
          "Frames per second.")
      .def_property_readonly("hand_count", &PySynthClip::handCount,
                             "Hands in the clip (2 for two-hands).")
      .def_property_readonly(
          "motion", [](const PySynthClip& s) { return s.options().clip; }, "The clip's name.")
      .def_property_readonly(
          "profile", [](const PySynthClip& s) { return s.options().profile; },
          "The sensor profile.")
      .def("__repr__", [](const PySynthClip& s) {
        return "SyntheticClip(motion='" + s.options().clip + "', profile='" + s.options().profile +
               "', frames=" + std::to_string(s.size()) + ")";
      });

  m.def("synth", &makeSynth, py::arg("motion") = "wave", py::arg("frames") = 300,
        py::arg("profile") = "tof", py::arg("placement") = "desk", py::arg("seed") = 1,
        py::arg("fps") = 30.0f, py::arg("speed") = 1.0f, py::arg("background") = "none",
        py::arg("table") = false, py::arg("hand_size") = py::none(),
        py::arg("proportion_spread") = 0.0f, py::arg("proportion_seed") = 1,
        "A synthetic clip in memory, as `dynahand synth --motion M --frames N --profile P "
        "--placement desk|head --seed S ...` renders it. motion: a clip name (clips()); "
        "profile: ideal, tof, structured-light or active-stereo. ValueError for an unknown "
        "clip or profile or a value out of range.");
  m.def(
      "clips",
      [] {
        std::vector<std::string> names;
        for (const auto& c : synth::clips()) names.push_back(c.name);
        return names;
      },
      "The built-in clip names synth() takes.");

  py::class_<eval::KeypointMetrics>(m, "Metrics",
                                    "21-keypoint accuracy (evaluate()): the figures `dynahand "
                                    "eval` prints. Errors in mm.")
      .def_readonly("frames", &eval::KeypointMetrics::frames, "Frames in the sequence.")
      .def_readonly("visible_frames", &eval::KeypointMetrics::visibleFrames,
                    "Frames with ground truth.")
      .def_readonly("evaluated_frames", &eval::KeypointMetrics::evaluatedFrames,
                    "Frames with ground truth and a prediction.")
      .def_readonly("mean_mm", &eval::KeypointMetrics::meanMm, "Mean joint error, mm.")
      .def_readonly("median_mm", &eval::KeypointMetrics::medianMm, "Median joint error, mm.")
      .def_readonly("p95_mm", &eval::KeypointMetrics::p95Mm, "95th percentile joint error, mm.")
      .def_readonly("max_mm", &eval::KeypointMetrics::maxMm, "Largest joint error, mm.")
      .def_readonly("jitter_mm", &eval::KeypointMetrics::jitterMm,
                    "Frame-to-frame motion beyond the true motion, mm.")
      .def_readonly("lost_frames", &eval::KeypointMetrics::lostFrames,
                    "Visible frames counted as lost.")
      .def_readonly("lost_episodes", &eval::KeypointMetrics::lostEpisodes, "Runs of lost frames.")
      .def_readonly("mean_recovery_s", &eval::KeypointMetrics::meanRecoverySeconds,
                    "Mean length of recovered lost episodes, s.")
      .def_readonly("max_recovery_s", &eval::KeypointMetrics::maxRecoverySeconds,
                    "Longest recovered lost episode, s.")
      .def_readonly("unrecovered_episodes", &eval::KeypointMetrics::unrecoveredEpisodes,
                    "Lost at the end of the sequence.")
      .def_property_readonly(
          "success_thresholds_mm",
          [](const eval::KeypointMetrics& k) { return doubles(k.successThresholdsMm); },
          "Thresholds of the success curve, mm.")
      .def_property_readonly(
          "success_fraction",
          [](const eval::KeypointMetrics& k) { return doubles(k.successFraction); },
          "Fraction of visible frames whose largest joint error is <= each threshold.")
      .def_property_readonly(
          "per_joint_mean_mm",
          [](const eval::KeypointMetrics& k) { return doubles(k.perJointMeanMm); },
          "(21,) mean error per keypoint, mm.")
      .def_property_readonly(
          "per_frame_mean_mm",
          [](const eval::KeypointMetrics& k) { return doubles(k.perFrameMeanMm); },
          "(N,) mean joint error per frame, mm (NaN where not evaluated).")
      .def_property_readonly(
          "per_frame_max_mm",
          [](const eval::KeypointMetrics& k) { return doubles(k.perFrameMaxMm); },
          "(N,) largest joint error per frame, mm (NaN where not evaluated).")
      .def("summary", &eval::summaryText, "The lines `dynahand eval` prints.")
      .def("report_markdown", &eval::markdownReport, py::arg("title") = "Evaluation",
           "The Markdown report `dynahand eval --out` writes (report.md).")
      .def("__repr__", [](const eval::KeypointMetrics& k) {
        char s[160];
        std::snprintf(s, sizeof s, "Metrics(frames=%d, evaluated=%d, mean_mm=%.2f)", k.frames,
                      k.evaluatedFrames, k.meanMm);
        return std::string(s);
      });

  m.def("evaluate", &evaluate, py::arg("gt"), py::arg("pred"), py::arg("fps") = 30.0,
        py::arg("lost_mm") = 50.0,
        "Accuracy of predicted keypoints against ground truth, as `dynahand eval --fps F "
        "--lost-mm L`. gt, pred: (N, 21, 3) arrays (m; an all-NaN row = no hand) or lists whose "
        "items are (21, 3) arrays or None. The shorter is padded with frames without a hand.");
}
