// Depth filtering inside a pixel box: range gate, median, bilateral, flying pixels.
#pragma once

#include <cstdint>
#include <vector>

#include "dynahand/cloud.h"

namespace dynahand::cloud {

// Largest depth step (m) between neighbouring samples of one surface at depth z (m),
// `spacingPerMetre` = step / focal length (lateral metres between them per metre of depth).
inline float maxDepthStep(const DepthStepRule& rule, float z, float spacingPerMetre) {
  return rule.jumpM + rule.slope * z * spacingPerMetre;
}

// Reusable scratch for filterBox (sized for a whole frame once).
struct FilterScratch {
  std::vector<std::uint16_t> gated;   // range-gated raw values of the box
  std::vector<std::uint16_t> median;  // after the median
  std::vector<float> metres;          // before flying-pixel removal
  void reserve(std::size_t pixels);
};

// Samples along `pixels` taken every `stride` pixels.
inline int samplesAlong(int pixels, int stride) {
  return (pixels + stride - 1) / stride;
}

// Writes the filtered depth (m, 0 = none) of the samples of `box` taken every `stride`
// pixels into `out`, row-major (samplesAlong(height) x samplesAlong(width)). fx, fy:
// focal lengths (pixels) for the flying-pixel rule.
void filterBox(const DepthFrame& frame, const PixelBox& box, int stride,
               const DepthFilterConfig& config, const DepthStepRule& stepRule, float fx, float fy,
               FilterScratch& scratch, std::vector<float>& out);

}  // namespace dynahand::cloud
