// `import dynahand`: the accuracy metrics of `dynahand eval` (docs/python.md).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "dynahand/metrics.h"
#include "module_util.h"

namespace dynahand::python {
namespace {

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

}  // namespace

void bindMetrics(py::module_& m) {
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

}  // namespace dynahand::python
