// `import dynahand`: the learned detector's synthetic training data as numpy arrays, the samples
// `dynahand detector data` writes (docs/formats/detector-data.md), for train/train_detector.py.
#include <cstdint>
#include <span>
#include <string>

#include "dynahand/detector.h"
#include "dynahand/detector_data.h"
#include "module_util.h"

namespace dynahand::python {
namespace {

constexpr int kMaxCount = 10000000;  // as `dynahand detector data --count`

// A seed as `dynahand detector data --seed` takes it: an integer in [0, 2^64).
std::uint64_t seedValue(const py::object& seed) {
  if (!py::isinstance<py::int_>(seed))
    throw py::value_error("seed must be an integer (got " + typeName(seed) + ")");
  const unsigned long long value = PyLong_AsUnsignedLongLong(seed.ptr());
  if (PyErr_Occurred()) {
    PyErr_Clear();
    throw py::value_error("seed must be in [0, 2**64) (got " + py::repr(seed).cast<std::string>() +
                          ")");
  }
  return value;
}

// Samples [0, count) of a set as numpy arrays, filled block by block from the generator that
// `dynahand detector data` writes its file from (detect::forEachSampleBlock): the same values,
// at the same speed.
py::dict detectorData(const std::string& split, int count, const py::object& seed, int threads,
                      double proportionSpread, double heldObjectShare, bool heldObjectBoxes,
                      double sharedCurlShare, double headViewShare) {
  detect::DataOptions options;
  if (split == "train") {
    options.split = detect::DataSplit::Train;
  } else if (split == "held-back") {
    options.split = detect::DataSplit::HeldBack;
  } else {
    throw py::value_error("split must be 'train' or 'held-back' (got '" + split + "')");
  }
  if (count < 1 || count > kMaxCount)
    throw py::value_error("count must be in 1.." + std::to_string(kMaxCount) + " (got " +
                          std::to_string(count) + ")");
  if (threads < 1 || threads > 64) throw py::value_error("threads must be 1..64");
  if (!(proportionSpread >= 0.0 && proportionSpread <= 0.5))
    throw py::value_error("proportion_spread must be in [0, 0.5]");
  if (!(heldObjectShare >= 0.0 && heldObjectShare <= 1.0))
    throw py::value_error("held_object_share must be in [0, 1]");
  if (!(sharedCurlShare >= 0.0 && sharedCurlShare <= 1.0))
    throw py::value_error("shared_curl_share must be in [0, 1]");
  if (!(headViewShare >= 0.0 && headViewShare <= 1.0))
    throw py::value_error("head_view_share must be in [0, 1]");
  options.count = count;
  options.seed = seedValue(seed);
  options.threads = threads;
  options.proportionSpread = static_cast<float>(proportionSpread);  // as the command's 0.15f
  options.heldObjectShare = static_cast<float>(heldObjectShare);
  options.heldObjectBoxes = heldObjectBoxes;
  options.sharedCurlShare = static_cast<float>(sharedCurlShare);
  options.headViewShare = static_cast<float>(headViewShare);

  constexpr py::ssize_t kSide = detect::kCropPixels, kPoints = detect::kKeypointCount;
  const py::ssize_t n = count;
  py::array_t<std::uint8_t> pixels({n, kSide, kSide});
  py::array_t<float> uvd({n, kPoints, py::ssize_t{3}});
  py::array_t<std::int32_t> profile(n), source(n);
  std::uint8_t* pixelOut = pixels.mutable_data();
  float* uvdOut = uvd.mutable_data();
  std::int32_t* profileOut = profile.mutable_data();
  std::int32_t* sourceOut = source.mutable_data();
  bool interrupted = false;
  Status made = Ok{};
  {
    py::gil_scoped_release nogil;
    made = detect::forEachSampleBlock(
        options, [&](int first, std::span<const detect::DataSample> block) {
          for (std::size_t b = 0; b < block.size(); ++b) {
            const detect::DataSample& s = block[b];
            const py::ssize_t i = first + static_cast<py::ssize_t>(b);
            std::uint8_t* px = pixelOut + i * kSide * kSide;
            for (py::ssize_t p = 0; p < kSide * kSide; ++p)
              px[p] = detect::dataPixelByte(s.pixels[static_cast<std::size_t>(p)]);
            for (py::ssize_t j = 0; j < kPoints; ++j)
              for (int a = 0; a < 3; ++a)
                uvdOut[(i * kPoints + j) * 3 + a] = s.uvd[static_cast<std::size_t>(j)][a];
            profileOut[i] = s.profile;
            sourceOut[i] = s.source;
          }
          py::gil_scoped_acquire gil;
          interrupted = PyErr_CheckSignals() != 0;
          return !interrupted;
        });
  }
  if (interrupted) throw py::error_already_set();
  if (!made) throw py::value_error("detector_data: " + made.message());
  py::dict out;
  out["pixels"] = pixels;
  out["uvd"] = uvd;
  out["profile"] = profile;
  out["source"] = source;
  return out;
}

}  // namespace

void bindDetectorData(py::module_& m) {
  m.def("detector_data", &detectorData, py::arg("split") = "train", py::arg("count") = 1000,
        py::arg("seed") = 1, py::arg("threads") = 1, py::arg("proportion_spread") = 0.15,
        py::arg("held_object_share") = 0.15, py::arg("held_object_boxes") = false,
        py::arg("shared_curl_share") = 0.3, py::arg("head_view_share") = 0.45,
        "The learned detector's synthetic training data as numpy arrays: the samples `dynahand "
        "detector data --split S --count N --seed SEED --proportion-spread P --held-object-share "
        "H [--held-object-boxes] --shared-curl-share C --head-view-share V` writes to its file "
        "(docs/formats/detector-data.md), value for value (sample i is a function of (split, "
        "seed, i) alone; the same for any threads). Returns a dict: pixels (N, 64, 64) uint8 "
        "(the crop; x in [-1, 1] is pixels / 127.5 - 1), uvd (N, 21, 3) float32 (keypoints in "
        "normalised crop coordinates), profile (N,) int32 (sensor profile index) and source "
        "(N,) int32 (0 random pose, 1 clip pose, 2 perturbed clip pose). split: 'train' or "
        "'held-back'. Made in memory by the command's own generator; runs without the GIL, Ctrl-C "
        "stops it (KeyboardInterrupt). ValueError for bad arguments.");
}

}  // namespace dynahand::python
