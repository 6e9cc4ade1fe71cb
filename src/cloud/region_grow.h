// Region growing on a depth grid (coarse samples or the filtered box): "the closest,
// sufficiently large volume". Shared by the coarse search and the full-resolution pass.
#pragma once

#include <bit>
#include <cstdint>
#include <limits>
#include <vector>

#include "dynahand/cloud.h"

namespace dynahand::cloud {

// Cell labels. kCut marks connected cells just beyond the hand radius of an accepted
// region (where the arm leaves); kTried cells belonged to a rejected (too small) region.
enum CellLabel : std::uint8_t {
  kFree = 0,
  kRegion1 = 1,
  kRegion2 = 2,
  kTried = 3,
  kCut1 = 4,
  kCut2 = 5
};

// A depth grid: cell (i, j) holds depth (m, 0 = none) of pixel
// (originU + i * step, originV + j * step).
struct DepthGrid {
  const float* depth = nullptr;  // (height x width)
  int width = 0;
  int height = 0;
  int originU = 0;  // pixels
  int originV = 0;  // pixels
  int step = 1;     // pixels between cells

  Vec3 point(const Intrinsics& k, int i, int j) const {
    const float z = depth[static_cast<std::size_t>(j) * width + i];
    return k.deproject(static_cast<float>(originU + i * step),
                       static_cast<float>(originV + j * step), z);
  }
};

struct GrownRegion {
  int cellCount = 0;
  float areaM2 = 0.0f;  // sum of z^2 step^2 / (fx fy)
  bool touchesEarlierRegion = false;
  // Built from fragments (surfaces smaller than minAreaM2) that lie in front of a larger
  // surface close behind them: they are pieces of it, not a volume; reject the region.
  bool inFrontOfSurface = false;
  Vec3 nearestPoint = Vec3::Zero();  // the seed's point, m
  Vec3 pointSum = Vec3::Zero();      // m
  Vec2 pixelSum = Vec2::Zero();      // pixels (u, v)
  int cutCount = 0;
  Vec3 cutPointSum = Vec3::Zero();
  Vec2 cutPixelSum = Vec2::Zero();
  int minI = 0, minJ = 0, maxI = 0, maxJ = 0;  // inclusive cell box
};

// Grows regions nearest-first over one grid. Buffers are sized once for the largest grid.
class RegionGrower {
 public:
  void reserve(std::size_t cells, int maxWidth, int maxHeight);
  // Starts a new grid (seen through intrinsics k): all cells kFree.
  void reset(const DepthGrid& grid, const Intrinsics& k);

  // Index of the nearest kFree valid cell, or -1. With maxDepthM > 0 only cells up to
  // that depth; with avoidCentre set, only cells farther than avoidRadiusM from it.
  int nearestFreeCell(float maxDepthM = 0.0f, const Vec3* avoidCentre = nullptr,
                      float avoidRadiusM = 0.0f) const;
  // The valid kFree cell whose point is closest to p (m), or -1.
  int closestFreeCell(const Vec3& p) const;
  // Nearest valid kFree cell (i, j) for which allowed(i, j) is true, or -1. The
  // predicate is only asked about cells nearer than the best so far (rarely).
  template <class Allowed>
  int nearestFreeCellWhere(const Allowed& allowed) const {
    int best = -1;
    // Positive floats order like their bit patterns; "bits - 1" wraps 0 (no data) to the
    // largest value, so one well-predicted comparison skips both empty and farther cells.
    std::uint32_t bestKey = std::bit_cast<std::uint32_t>(std::numeric_limits<float>::infinity());
    for (int j = 0; j < grid_.height; ++j) {
      const std::size_t row = static_cast<std::size_t>(j) * grid_.width;
      const float* depth = grid_.depth + row;
      for (int i = 0; i < grid_.width; ++i) {
        const std::uint32_t key = std::bit_cast<std::uint32_t>(depth[i]) - 1u;
        // Strict < keeps the first cell in scan order on ties (deterministic).
        if (key >= bestKey || labels_[row + i] != kFree || !allowed(i, j)) continue;
        bestKey = key;
        best = static_cast<int>(row + static_cast<std::size_t>(i));
      }
    }
    return best;
  }

  // Grows from `seed` across neighbours within the step rule (or up to 6 cm nearer) and
  // radiusM of the seed's point, then across larger depth steps: fragments (surfaces
  // below minAreaM2) at any step while the region is below minAreaM2; afterwards
  // fragments in front and surfaces up to 6 cm behind that are no larger than half the
  // ball's cross-section (docs/cloud.md, "Regions across depth steps"). Cells stay
  // unlabelled until accept() or reject().
  GrownRegion grow(int seed, const DepthStepRule& rule, float radiusM, float minAreaM2);
  // Labels the last grown region kRegion1/kRegion2 and its cut cells kCut1/kCut2.
  void accept(CellLabel region);
  // Labels the last grown region kTried (its seed is not tried again).
  void reject();
  // Appends the last grown region's cells (packed j << 16 | i) to `out`, if they fit in its
  // capacity (no allocation); false otherwise.
  bool appendLastRegion(std::vector<std::int32_t>& out) const {
    if (out.size() + static_cast<std::size_t>(regionEnd_) > out.capacity()) return false;
    out.insert(out.end(), queue_.begin(), queue_.begin() + regionEnd_);
    return true;
  }
  // Labels `region` those of the given cells (packed, from appendLastRegion) that lie within
  // radiusM of centre and are not labelled `region` already; returns their area (m^2, as
  // GrownRegion::areaM2 counts it).
  float labelCellsWithin(const std::int32_t* packed, std::size_t count, CellLabel region,
                         const Vec3& centre, float radiusM);
  // Turns all accepted regions into kTried and frees their cut cells.
  void retireAccepted();

  const std::vector<std::uint8_t>& labels() const { return labels_; }
  const DepthGrid& grid() const { return grid_; }

 private:
  // grow's running state (region_grow.cpp) and its stages: the seed's setup; flooding the
  // current surface (within the step rule, occluders included) until the queue drains; a
  // surface across a depth step, once flooded, kept or undone; the next such surface to try;
  // the result.
  struct Growth;
  Growth beginGrowth(int seed, const DepthStepRule& rule, float radiusM, float minAreaM2);
  void floodSurface(Growth& g);
  bool settleTriedSurface(Growth& g);  // true: the region is in front of a surface, stop
  std::int32_t nextSurfaceAcross(Growth& g);
  GrownRegion finishGrowth(const Growth& g);

  DepthGrid grid_;
  Intrinsics k_;
  std::vector<std::uint8_t> labels_;   // (cells) CellLabel
  std::vector<std::uint8_t> visited_;  // (cells) attempt that reached the cell, 0 = none
  // (cells) attempt that found the cell on a large surface behind its region, 0 = none
  std::vector<std::uint8_t> separate_;
  std::vector<std::uint8_t> acrossQueued_;  // (cells) attempt that queued it in across_
  // Packed cells (j << 16 | i): the region from the front, its cut cells from the back.
  std::vector<std::int32_t> queue_;
  std::vector<std::int32_t> across_;      // packed cells across a depth step, to try
  std::vector<std::uint8_t> acrossSide_;  // (across_) in front, behind or far behind
  std::vector<float> columnX_;            // (width) (u - cx) / fx of each column
  std::vector<float> rowY_;               // (height) (v - cy) / fy of each row
  std::size_t cellOf(std::int32_t packed) const {
    return static_cast<std::size_t>(packed >> 16) * static_cast<std::size_t>(grid_.width) +
           static_cast<std::size_t>(packed & 0xffff);
  }
  std::uint8_t attempt_ = 0;  // grows per grow() call; the stamps are wiped when it wraps
  bool labelled_ = false;     // some cell is no longer kFree (since the last reset)
  int regionEnd_ = 0;         // queue_[0, regionEnd_) = region of the last grow
  int cutBegin_ = 0;          // queue_[cutBegin_, cells) = its cut cells
};

}  // namespace dynahand::cloud
