// `import dynahand`: errors, numpy conversion and cameras, shared by the binding's files
// (module_util.h), and the Camera class.
#include "module_util.h"

#include <cmath>
#include <cstdio>
#include <limits>
#include <utility>

#include "dynahand/model_pose.h"

namespace dynahand::python {

// ---- errors ------------------------------------------------------------------------------

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

F32Array keypointsArray(const std::array<Vec3, 21>& k, bool valid) {
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
      if (d.contains("min_range_m")) spec.minRangeM = d["min_range_m"].cast<float>();
    } catch (const py::cast_error&) {
      throw py::value_error(
          "camera dict: width and height must be ints, fx fy cx cy (fps, min_range_m) numbers");
    }
  } else if (py::hasattr(obj, "camera")) {
    spec = cameraSpec(obj.attr("camera"));
    if (py::hasattr(obj, "fps")) spec.fps = obj.attr("fps").cast<double>();
    if (py::hasattr(obj, "min_range_m")) spec.minRangeM = obj.attr("min_range_m").cast<float>();
  } else {
    throw py::value_error(
        "camera must be a dynahand.Camera, a dict with width, height, fx, fy, cx, cy, or a "
        "sequence / synthetic clip (got " +
        typeName(obj) + ")");
  }
  checkedIntrinsics(spec.intrinsics);
  if (spec.minRangeM && !(*spec.minRangeM >= 0.0f && *spec.minRangeM <= 100.0f))
    throw py::value_error("camera: min_range_m must be in [0, 100] m");
  return spec;
}

void bindCamera(py::module_& m) {
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
}

// ---- frames --------------------------------------------------------------------------------

int checkedIndex(py::ssize_t index, int count) {
  const py::ssize_t i = index < 0 ? index + count : index;
  if (i < 0 || i >= count)
    throw py::index_error("frame " + std::to_string(index) + " out of range (" +
                          std::to_string(count) + " frames)");
  return static_cast<int>(i);
}

}  // namespace dynahand::python
