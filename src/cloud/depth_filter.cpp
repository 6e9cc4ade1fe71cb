#include "cloud/depth_filter.h"

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cassert>
#include <cmath>

namespace dynahand::cloud {

void FilterScratch::reserve(std::size_t pixels) {
  gated.reserve(pixels);
  median.reserve(pixels);
  metres.reserve(pixels);
}

namespace {

// Raw unit range [lo, hi] that maps into [minDepthM, maxDepthM].
std::pair<std::uint32_t, std::uint32_t> rawRange(const DepthFilterConfig& config, float scale) {
  const double lo = std::ceil(static_cast<double>(config.minDepthM) / static_cast<double>(scale));
  const double hi = std::floor(static_cast<double>(config.maxDepthM) / static_cast<double>(scale));
  const auto clampRaw = [](double x) {
    return static_cast<std::uint32_t>(std::clamp(x, 1.0, 65535.0));
  };
  return {clampRaw(lo), hi < 1.0 ? 0u : clampRaw(hi)};
}

// A pixel is flying when it is cut off from both neighbours of a horizontal or of a
// vertical pair: mixed foreground/background samples at depth edges, and lone specks.
// Neighbours outside the box are unknown and never count as a cut.
void removeFlyingPixels(const std::vector<float>& in, int w, int h, const DepthStepRule& rule,
                        float fx, float fy, std::vector<float>& out) {
  const float spacingX = 1.0f / fx;
  const float spacingY = 1.0f / fy;
  // An invalid neighbour (0) differs by z: a cut whenever z > limit. z = 0 stays 0.
  const auto generic = [&](int u, int v) {
    const float* row = in.data() + static_cast<std::size_t>(v) * w;
    const float z = row[u];
    const float limitX = maxDepthStep(rule, z, spacingX);
    const float limitY = maxDepthStep(rule, z, spacingY);
    const bool cutLeft = u > 0 && std::fabs(row[u - 1] - z) > limitX;
    const bool cutRight = u + 1 < w && std::fabs(row[u + 1] - z) > limitX;
    const bool cutUp = v > 0 && std::fabs(row[u - w] - z) > limitY;
    const bool cutDown = v + 1 < h && std::fabs(row[u + w] - z) > limitY;
    return (cutLeft && cutRight) || (cutUp && cutDown) ? 0.0f : z;
  };
  for (int v = 0; v < h; ++v) {
    float* dst = out.data() + static_cast<std::size_t>(v) * w;
    if (v == 0 || v + 1 == h || w < 3) {
      for (int u = 0; u < w; ++u) dst[u] = generic(u, v);
      continue;
    }
    const float* row = in.data() + static_cast<std::size_t>(v) * w;
    const float* up = row - w;
    const float* down = row + w;
    dst[0] = generic(0, v);
    // Interior: no bounds tests, no branches (the compiler can vectorise this).
    for (int u = 1; u + 1 < w; ++u) {
      const float z = row[u];
      const float limitX = maxDepthStep(rule, z, spacingX);
      const float limitY = maxDepthStep(rule, z, spacingY);
      const bool cutX = (std::fabs(row[u - 1] - z) > limitX) & (std::fabs(row[u + 1] - z) > limitX);
      const bool cutY = (std::fabs(up[u] - z) > limitY) & (std::fabs(down[u] - z) > limitY);
      dst[u] = cutX | cutY ? 0.0f : z;
    }
    dst[w - 1] = generic(w - 1, v);
  }
}

}  // namespace

void filterBox(const DepthFrame& frame, const PixelBox& box, int stride,
               const DepthFilterConfig& config, const DepthStepRule& stepRule, float fx, float fy,
               FilterScratch& scratch, std::vector<float>& out) {
  assert(!box.empty() && box.x0 >= 0 && box.y0 >= 0 && box.x1 <= frame.width &&
         box.y1 <= frame.height && stride >= 1);
  const int w = samplesAlong(box.width(), stride);
  const int h = samplesAlong(box.height(), stride);
  const auto n = static_cast<std::size_t>(w) * h;
  const auto [lo, hi] = rawRange(config, frame.depthScale);

  scratch.gated.resize(n);
  for (int v = 0; v < h; ++v) {
    const std::uint16_t* src =
        frame.depth.data() + static_cast<std::size_t>(box.y0 + v * stride) * frame.width + box.x0;
    std::uint16_t* dst = scratch.gated.data() + static_cast<std::size_t>(v) * w;
    for (int u = 0; u < w; ++u) {
      const std::uint32_t d = src[u * stride];
      dst[u] = d >= lo && d <= hi ? static_cast<std::uint16_t>(d) : std::uint16_t{0};
    }
  }

  const std::uint16_t* raw = scratch.gated.data();
  if (config.median && w >= 3 && h >= 3) {
    scratch.median.resize(n);
    // Headers over our buffers: OpenCV writes in place, nothing is reallocated.
    const cv::Mat src(h, w, CV_16UC1, scratch.gated.data());
    cv::Mat dst(h, w, CV_16UC1, scratch.median.data());
    cv::medianBlur(src, dst, 3);
    raw = scratch.median.data();
  }

  scratch.metres.resize(n);
  const float scale = frame.depthScale;
  for (std::size_t i = 0; i < n; ++i) scratch.metres[i] = static_cast<float>(raw[i]) * scale;

  if (config.bilateral) {
    out.resize(n);
    const cv::Mat src(h, w, CV_32FC1, scratch.metres.data());
    cv::Mat dst(h, w, CV_32FC1, out.data());
    cv::bilateralFilter(src, dst, 5, config.bilateralSigmaDepthM, config.bilateralSigmaPixels);
    // Smoothing must not invent depth where there was none.
    for (std::size_t i = 0; i < n; ++i) {
      if (scratch.metres[i] == 0.0f) out[i] = 0.0f;
    }
    std::swap(out, scratch.metres);
  }

  out.resize(n);
  if (config.removeFlyingPixels) {
    // Neighbouring samples are `stride` pixels apart.
    removeFlyingPixels(scratch.metres, w, h, stepRule, fx / static_cast<float>(stride),
                       fy / static_cast<float>(stride), out);
  } else {
    std::copy(scratch.metres.begin(), scratch.metres.end(), out.begin());
  }
}

}  // namespace dynahand::cloud
