// `import dynahand` (docs/python.md): what the binding's files share. Errors, numpy conversion,
// cameras, frame indices and iteration; and the functions module.cpp calls to bind each part
// (bind_tracker.cpp, bind_sequence.cpp, bind_synth.cpp, bind_metrics.cpp, bind_detector.cpp).
// Bad input is a ValueError, a file problem an OSError (FileNotFoundError for a missing path),
// each carrying the library's message; nothing here asserts on user input.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "dynahand/core.h"
#include "dynahand/depth_frame.h"

namespace py = pybind11;

namespace dynahand::python {

// ---- errors ------------------------------------------------------------------------------

// A file that cannot be read (OSError in Python) and a path that does not exist
// (FileNotFoundError, a subclass of OSError); module.cpp translates them.
struct FileError : std::runtime_error {
  using std::runtime_error::runtime_error;
};
struct FileMissing : FileError {
  using FileError::FileError;
};

std::string typeName(const py::handle& obj);

// A str or path-like object naming an existing file or folder (FileMissing otherwise).
std::filesystem::path existingPath(const py::object& path, const char* what);

// ---- numpy conversion ----------------------------------------------------------------------

using F32Array = py::array_t<float, py::array::c_style>;

F32Array keypointsArray(const std::array<Vec3, 21>& k, bool valid = true);

// Rows x, y, z, qw, qx, qy, qz (a pose), NaN when not valid.
void putPose(py::detail::unchecked_mutable_reference<float, 2>& m, py::ssize_t row, const Pose& p,
             bool valid);

// The depth image without a copy: the numpy array owns the frame's buffer.
py::array_t<std::uint16_t> depthArray(std::vector<std::uint16_t>&& pixels, int width, int height);

// A (H, W) uint16 array as a C-contiguous array (the same buffer when it already is one).
py::array_t<std::uint16_t, py::array::c_style> depthInput(const py::handle& obj, int width,
                                                          int height);

// Keypoints (21, 3) from any array-like; nullopt for None or an all-NaN row.
std::optional<std::array<Vec3, 21>> keypointsInput(const py::handle& obj, const std::string& what);

// ---- cameras -------------------------------------------------------------------------------

Intrinsics checkedIntrinsics(const Intrinsics& k);

struct CameraSpec {
  Intrinsics intrinsics;
  std::optional<double> fps;
  std::optional<float> minRangeM;  // the camera's near range, m
};

// A Camera, a dict {width, height, fx, fy, cx, cy[, fps][, min_range_m]}, or anything with a
// `camera` attribute (a Sequence, a SyntheticClip) and maybe `fps` and `min_range_m`.
CameraSpec cameraSpec(const py::handle& obj);

// ---- frames --------------------------------------------------------------------------------

// Index `index` (negative: from the end) of `count` frames; IndexError when out of range.
int checkedIndex(py::ssize_t index, int count);

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

// ---- the module's parts, bound in this order by module.cpp ---------------------------------

void bindCamera(py::module_& m);        // module_util.cpp: Camera
void bindTracker(py::module_& m);       // HandResult, HandSize, Tracker, estimate_hand_size
void bindSequence(py::module_& m);      // Sequence, open_sequence
void bindSynth(py::module_& m);         // SyntheticClip, synth, clips
void bindMetrics(py::module_& m);       // Metrics, evaluate
void bindDetectorData(py::module_& m);  // detector_data

}  // namespace dynahand::python
