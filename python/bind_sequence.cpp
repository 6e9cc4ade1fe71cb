// `import dynahand`: depth recordings on disk, as `dynahand track` reads them (docs/python.md).
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <utility>

#include "dynahand/sequence.h"
#include "module_util.h"

namespace dynahand::python {
namespace {

// ---- sequences ----------------------------------------------------------------------------

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

}  // namespace

void bindSequence(py::module_& m) {
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
          "min_range_m", [](const PySequence& s) { return s.info().minRangeM; },
          "The camera's near range, m (nothing nearer is measured); 0 = not recorded.")
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
            d["min_range_m"] = i.minRangeM;
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
}

}  // namespace dynahand::python
