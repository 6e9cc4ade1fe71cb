// Which faces of a convex shape can hold the largest face-plane distance n·q - offset of a
// body-frame point q, per cell of a grid over the hull's bounds grown by a margin. That
// largest distance (the nearest face of an inside point, a lower bound for an outside one)
// is what the tracker's nearest-body scans look for: visiting only the faces of q's cell,
// in index order, finds the same face and the same bits as visiting every face (the others
// are more than the rounding of the arithmetic below it; docs/physics.md).
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "dynahand/core.h"

namespace dynahand::physics {

class ConvexShape;

class FaceCells {
 public:
  static constexpr float kCellSize = 0.003f;  // m; a finger bone's cell holds ~5 of 42 faces
  static constexpr float kMargin = 0.02f;     // m past the hull's bounds; beyond: every face

  explicit FaceCells(const ConvexShape& shape);

  int words() const { return words_; }  // 64-bit words per cell: faces / 64, rounded up
  // The faces that can hold q's largest plane distance (bit f % 64 of word f / 64), or
  // nullptr when q is outside the grid or not finite (then any face can).
  const std::uint64_t* candidates(float x, float y, float z) const {
    const float fx = (x - grid_.loX) * grid_.inverseCell;
    const float fy = (y - grid_.loY) * grid_.inverseCell;
    const float fz = (z - grid_.loZ) * grid_.inverseCell;
    if (!(fx >= 0.0f && fx < grid_.cellsX && fy >= 0.0f && fy < grid_.cellsY && fz >= 0.0f &&
          fz < grid_.cellsZ))
      return nullptr;
    return mask(static_cast<std::size_t>(
        (std::floor(fz) * grid_.cellsY + std::floor(fy)) * grid_.cellsX + std::floor(fx)));
  }
  // The grid, for vectorised lookups: cell (i, j, k) covers lo + [i, i + 1) x cell size (and
  // likewise in y, z); its index is (k cellsY + j) cellsX + i, computed exactly in float.
  struct Grid {
    float loX = 0.0f, loY = 0.0f, loZ = 0.0f;  // body frame, m
    float inverseCell = 1.0f / kCellSize;
    float cellsX = 0.0f, cellsY = 0.0f, cellsZ = 0.0f;
  };
  const Grid& grid() const { return grid_; }
  const std::uint64_t* mask(std::size_t cell) const {
    return masks_.data() + cell * static_cast<std::size_t>(words_);
  }
  std::size_t cellCount() const { return masks_.size() / static_cast<std::size_t>(words_); }

 private:
  Grid grid_;
  int words_ = 1;
  std::vector<std::uint64_t> masks_;  // (cells x words_), x fastest
};

}  // namespace dynahand::physics
