// A large plane near the hand, a table top or a wall, found on the coarse depth grid and left
// out of the segmentation: a hand resting on a table otherwise grows into it (the table is
// one connected surface with the hand) and the table's samples pull the model's bones.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#include "cloud/region_grow.h"
#include "dynahand/cloud.h"

namespace dynahand::cloud {

// Finds the planes with the largest seen area among a depth grid's samples, largest first
// (RANSAC with a fixed seed: the same planes for the same grid and history). The previous
// frame's planes are tried first.
class SupportPlaneFinder {
 public:
  void reserve(std::size_t cells);
  // Searches `grid`; writes up to min(config.maxPlanes, out.size()) planes whose samples within
  // config.bandM cover at least config.minAreaM2 each, and returns how many.
  int find(const DepthGrid& grid, const Intrinsics& k, const SupportPlaneConfig& config,
           std::span<SupportPlane> out);

 private:
  // Area (m^2, as seen) of the remaining samples within bandM of the plane, visiting every
  // `every`-th one.
  float inlierArea(const SupportPlane& plane, float bandM, std::size_t every) const;
  // Least-squares plane through the remaining samples within bandM of `plane`, which it
  // replaces (its area is left as it was); false if degenerate.
  bool refit(SupportPlane& plane, float bandM) const;
  // A plane through three remaining samples near each other (its area unset), or false.
  bool hypothesis(const DepthGrid& grid, SupportPlane& plane);
  void removeInliers(const SupportPlane& plane, float bandM);

  std::vector<Vec3> points_;               // the grid's samples with depth, m
  std::vector<float> area_;                // each sample's seen area, m^2 (0: removed)
  std::vector<std::int32_t> cellOfPoint_;  // grid cell of each sample
  std::vector<std::int32_t> pointOfCell_;  // sample of each grid cell, -1: no depth
  std::uint32_t random_ = 1;               // the hypotheses' generator (LCG)
  std::array<SupportPlane, 2> previous_;
  int previousCount_ = 0;
};

// Whether p lies within bandM of the plane (either side).
inline bool onPlane(const SupportPlane& plane, const Vec3& p, float bandM) {
  return std::abs(plane.normal.dot(p) - plane.offset) <= bandM;
}

// Zeroes the grid samples (depth, m; 0 = none) of `depth` that lie on the plane: cell (i, j)
// is pixel (originU + i step, originV + j step). removed (optional, per cell): set to 1 where
// a sample was zeroed.
void removePlaneSamples(const SupportPlane& plane, float bandM, const Intrinsics& k, int originU,
                        int originV, int step, int width, int height, float* depth,
                        std::uint8_t* removed = nullptr);

}  // namespace dynahand::cloud
