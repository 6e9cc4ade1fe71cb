// `import dynahand`: synthetic clips in memory, as `dynahand synth` renders them (docs/python.md).
#include <algorithm>
#include <cstdint>
#include <cstring>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "dynahand/model_pose.h"
#include "dynahand/synth.h"
#include "module_util.h"

namespace dynahand::python {
namespace {

// ---- synthetic clips -------------------------------------------------------------------------

class PySynthClip {
 public:
  explicit PySynthClip(synth::SyntheticSequence seq) : seq_(std::move(seq)) {}

  int size() const { return seq_.frameCount(); }
  int handCount() const { return seq_.handCount(); }
  const Intrinsics& intrinsics() const { return seq_.intrinsics(); }
  const synth::SynthOptions& options() const { return seq_.options(); }
  const synth::SensorProfile& profile() const { return seq_.profile(); }

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
                                       std::uint64_t proportionSeed, const std::string& heldObject,
                                       float heldObjectSize, std::pair<float, float> viewShift) {
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
  bool knownObject = false;
  for (const auto object : {synth::HeldObject::None, synth::HeldObject::Ball,
                            synth::HeldObject::Cylinder, synth::HeldObject::Box}) {
    if (heldObject == synth::heldObjectName(object)) {
      o.scene.heldObject = object;
      knownObject = true;
    }
  }
  if (!knownObject)
    throw py::value_error("held_object must be 'none', 'ball', 'cylinder' or 'box' (got '" +
                          heldObject + "')");
  o.scene.heldObjectSize = heldObjectSize;
  o.scene.viewShift = Vec2(viewShift.first, viewShift.second);
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

}  // namespace

void bindSynth(py::module_& m) {
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
      .def_property_readonly(
          "min_range_m", [](const PySynthClip& s) { return s.profile().minRange; },
          "The sensor profile's near range, m (nothing nearer is measured).")
      .def("__repr__", [](const PySynthClip& s) {
        return "SyntheticClip(motion='" + s.options().clip + "', profile='" + s.options().profile +
               "', frames=" + std::to_string(s.size()) + ")";
      });

  m.def("synth", &makeSynth, py::arg("motion") = "wave", py::arg("frames") = 300,
        py::arg("profile") = "tof", py::arg("placement") = "desk", py::arg("seed") = 1,
        py::arg("fps") = 30.0f, py::arg("speed") = 1.0f, py::arg("background") = "none",
        py::arg("table") = false, py::arg("hand_size") = py::none(),
        py::arg("proportion_spread") = 0.0f, py::arg("proportion_seed") = 1,
        py::arg("held_object") = "none", py::arg("held_object_size") = 0.025f,
        py::arg("view_shift") = std::pair<float, float>(0.0f, 0.0f),
        "A synthetic clip in memory, as `dynahand synth --motion M --frames N --profile P "
        "--placement desk|head --seed S --object O --object-size R --view-shift DX DY ...` "
        "renders it. motion: a clip name (clips()); held_object: none, ball, cylinder or box "
        "against the palm; view_shift: (dx, dy) pixels the scene moves in the image (a hand "
        "near a border goes on out of view); "
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
}

}  // namespace dynahand::python
