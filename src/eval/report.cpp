// Markdown and SVG renderings of KeypointMetrics. The SVG is hand-written so a
// report needs no plotting library and fetches nothing.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "dynahand/metrics.h"

namespace dynahand::eval {

std::string summaryText(const KeypointMetrics& m) {
  std::string s = fmt::format("frames {} (hand visible {}, evaluated {})\n", m.frames,
                              m.visibleFrames, m.evaluatedFrames);
  s += fmt::format(
      "21-keypoint error  mean {:.2f} mm  median {:.2f} mm  p95 {:.2f} mm  max {:.2f} mm\n",
      m.meanMm, m.medianMm, m.p95Mm, m.maxMm);
  s += "success (max joint error <=)";
  for (std::size_t t = 0; t < m.successThresholdsMm.size(); ++t)
    s +=
        fmt::format("  {:.0f} mm: {:.1f}%", m.successThresholdsMm[t], 100.0 * m.successFraction[t]);
  s += fmt::format(
      "\njitter {:.2f} mm  lost frames {} in {} episodes  recovery mean {:.2f} s max {:.2f} s\n",
      m.jitterMm, m.lostFrames, m.lostEpisodes, m.meanRecoverySeconds, m.maxRecoverySeconds);
  return s;
}

std::string markdownReport(const KeypointMetrics& m, const std::string& title) {
  std::string out = fmt::format("# {}\n\n", title);
  out += "| metric | value |\n| --- | --- |\n";
  out += fmt::format("| frames (with a visible hand / evaluated) | {} ({} / {}) |\n", m.frames,
                     m.visibleFrames, m.evaluatedFrames);
  out += fmt::format("| mean 21-keypoint error | {:.2f} mm |\n", m.meanMm);
  out += fmt::format("| median | {:.2f} mm |\n", m.medianMm);
  out += fmt::format("| 95th percentile | {:.2f} mm |\n", m.p95Mm);
  out += fmt::format("| maximum | {:.2f} mm |\n", m.maxMm);
  out += fmt::format("| jitter (extra frame-to-frame motion) | {:.2f} mm |\n", m.jitterMm);
  out += fmt::format("| lost frames / episodes | {} / {} |\n", m.lostFrames, m.lostEpisodes);
  out += fmt::format("| recovery time mean / max | {:.2f} s / {:.2f} s |\n", m.meanRecoverySeconds,
                     m.maxRecoverySeconds);
  out += fmt::format("| lost at the end | {} |\n\n", m.unrecoveredEpisodes);

  out += "## Success curve (frames whose maximum joint error is under the threshold)\n\n";
  out += "| threshold | frames |\n| --- | --- |\n";
  for (std::size_t t = 0; t < m.successThresholdsMm.size(); ++t) {
    out += fmt::format("| {:.0f} mm | {:.1f}% |\n", m.successThresholdsMm[t],
                       100.0 * m.successFraction[t]);
  }
  out += "\n## Per joint\n\n| keypoint | mean error |\n| --- | --- |\n";
  for (int j = 0; j < 21; ++j) {
    out += fmt::format("| {} {} | {:.2f} mm |\n", j, kKeypointNames[j], m.perJointMeanMm[j]);
  }
  return out;
}

namespace {

struct PlotFrame {
  double x0 = 60, y0 = 20, w = 560, h = 260;  // plot area in SVG units
  double xMin = 0, xMax = 1, yMin = 0, yMax = 1;
  double px(double x) const { return x0 + (x - xMin) / (xMax - xMin) * w; }
  double py(double y) const { return y0 + h - (y - yMin) / (yMax - yMin) * h; }
};

std::string svgOpen(const std::string& title) {
  return fmt::format(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"660\" height=\"330\" "
      "font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"660\" height=\"330\" "
      "fill=\"white\"/>\n<text x=\"330\" y=\"14\" text-anchor=\"middle\">{}</text>\n",
      title);
}

std::string axes(const PlotFrame& f, const std::string& xLabel, const std::string& yLabel,
                 int xTicks, int yTicks) {
  std::string s = fmt::format(
      "<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" fill=\"none\" stroke=\"black\"/>\n", f.x0,
      f.y0, f.w, f.h);
  for (int i = 0; i <= xTicks; ++i) {
    const double x = f.xMin + (f.xMax - f.xMin) * i / xTicks;
    s += fmt::format("<text x=\"{:.1f}\" y=\"{:.1f}\" text-anchor=\"middle\">{:.4g}</text>\n",
                     f.px(x), f.y0 + f.h + 15, x);
  }
  for (int i = 0; i <= yTicks; ++i) {
    const double y = f.yMin + (f.yMax - f.yMin) * i / yTicks;
    s += fmt::format(
        "<line x1=\"{:.1f}\" y1=\"{:.1f}\" x2=\"{:.1f}\" y2=\"{:.1f}\" stroke=\"#ddd\"/>\n"
        "<text x=\"{:.1f}\" y=\"{:.1f}\" text-anchor=\"end\">{:.4g}</text>\n",
        f.x0, f.py(y), f.x0 + f.w, f.py(y), f.x0 - 4, f.py(y) + 4, y);
  }
  s += fmt::format("<text x=\"{:.1f}\" y=\"318\" text-anchor=\"middle\">{}</text>\n",
                   f.x0 + f.w / 2, xLabel);
  s += fmt::format(
      "<text x=\"14\" y=\"{:.1f}\" text-anchor=\"middle\" transform=\"rotate(-90 14 {:.1f})\">{}"
      "</text>\n",
      f.y0 + f.h / 2, f.y0 + f.h / 2, yLabel);
  return s;
}

// A polyline through the finite values; NaN breaks the line.
std::string series(const PlotFrame& f, const std::vector<double>& ys, const char* colour) {
  std::string s, points;
  auto flush = [&] {
    if (!points.empty()) {
      s += fmt::format(
          "<polyline fill=\"none\" stroke=\"{}\" stroke-width=\"1.5\" points=\"{}\"/>\n", colour,
          points);
    }
    points.clear();
  };
  for (std::size_t i = 0; i < ys.size(); ++i) {
    if (!std::isfinite(ys[i])) {
      flush();
      continue;
    }
    points +=
        fmt::format("{:.1f},{:.1f} ", f.px(static_cast<double>(i)), f.py(std::min(ys[i], f.yMax)));
  }
  flush();
  return s;
}

}  // namespace

std::string svgErrorOverTime(const KeypointMetrics& m, const std::string& title) {
  PlotFrame f;
  f.xMax = std::max(1.0, static_cast<double>(m.frames - 1));
  double top = 10;
  for (double v : m.perFrameMaxMm) {
    if (std::isfinite(v)) top = std::max(top, v);
  }
  f.yMax = std::ceil(std::min(top, 200.0) / 10.0) * 10.0;
  std::string s = svgOpen(title) + axes(f, "frame", "error (mm)", 5, 5);
  s += series(f, m.perFrameMaxMm, "#d62728");
  s += series(f, m.perFrameMeanMm, "#1f77b4");
  s += "<text x=\"520\" y=\"36\" fill=\"#1f77b4\">mean joint error</text>\n"
       "<text x=\"520\" y=\"50\" fill=\"#d62728\">max joint error</text>\n</svg>\n";
  return s;
}

std::string svgSuccessCurve(const KeypointMetrics& m, const std::string& title) {
  PlotFrame f;
  f.xMin = 0;
  f.xMax = m.successThresholdsMm.empty() ? 50.0 : m.successThresholdsMm.back();
  f.yMax = 100;
  std::string s = svgOpen(title) + axes(f, "max joint error threshold (mm)", "frames (%)", 5, 5);
  std::string points = fmt::format("{:.1f},{:.1f} ", f.px(0), f.py(0));
  for (std::size_t t = 0; t < m.successThresholdsMm.size(); ++t) {
    points += fmt::format("{:.1f},{:.1f} ", f.px(m.successThresholdsMm[t]),
                          f.py(100.0 * m.successFraction[t]));
  }
  s += fmt::format(
      "<polyline fill=\"none\" stroke=\"#2ca02c\" stroke-width=\"2\" points=\"{}\"/>\n</svg>\n",
      points);
  return s;
}

}  // namespace dynahand::eval
