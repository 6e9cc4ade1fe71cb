#include "cloud/region_grow.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>

#include "cloud/depth_filter.h"

namespace dynahand::cloud {

void RegionGrower::reserve(std::size_t cells) {
  labels_.reserve(cells);
  visited_.reserve(cells);
  queue_.reserve(cells);
}

void RegionGrower::reset(const DepthGrid& grid, const Intrinsics& k) {
  grid_ = grid;
  k_ = k;
  const auto cells = static_cast<std::size_t>(grid.width) * grid.height;
  labels_.assign(cells, kFree);
  // One byte per cell (cache-friendly); cleared per grid and when the 255 stamps run out.
  visited_.assign(cells, 0);
  attempt_ = 0;
  queue_.resize(cells);
  regionEnd_ = 0;
  cutBegin_ = static_cast<int>(cells);
}

int RegionGrower::nearestFreeCell(float maxDepthM, const Vec3* avoidCentre,
                                  float avoidRadiusM) const {
  int best = -1;
  // See nearestFreeCellWhere: bit patterns minus one put "no data" last.
  const float limit =
      maxDepthM > 0.0f ? std::nextafter(maxDepthM, 1e9f) : std::numeric_limits<float>::infinity();
  std::uint32_t bestKey = std::bit_cast<std::uint32_t>(limit) - 1u;
  const float avoid2 = avoidRadiusM * avoidRadiusM;
  for (int j = 0; j < grid_.height; ++j) {
    const std::size_t row = static_cast<std::size_t>(j) * grid_.width;
    const float* depth = grid_.depth + row;
    for (int i = 0; i < grid_.width; ++i) {
      const std::uint32_t key = std::bit_cast<std::uint32_t>(depth[i]) - 1u;
      // Strict < keeps the first cell in scan order on ties (deterministic).
      if (key >= bestKey || labels_[row + i] != kFree) continue;
      if (avoidCentre && (grid_.point(k_, i, j) - *avoidCentre).squaredNorm() <= avoid2) continue;
      bestKey = key;
      best = static_cast<int>(row + static_cast<std::size_t>(i));
    }
  }
  return best;
}

GrownRegion RegionGrower::grow(int seed, const DepthStepRule& rule, float radiusM) {
  assert(seed >= 0 && static_cast<std::size_t>(seed) < labels_.size());
  const int w = grid_.width;
  const int h = grid_.height;
  const float* depth = grid_.depth;
  const auto step = static_cast<float>(grid_.step);
  const float spacingX = step / k_.fx;  // lateral m per m of depth between neighbours
  const float spacingY = step / k_.fy;
  const float areaPerZ2 = spacingX * spacingY;
  const float radius2 = radiusM * radiusM;
  // Deprojection without a divide: x = (u - cx) * z / fx.
  const float invFx = 1.0f / k_.fx;
  const float invFy = 1.0f / k_.fy;
  const auto pointAt = [&](int i, int j, float z) {
    return Vec3((static_cast<float>(grid_.originU + i * grid_.step) - k_.cx) * invFx * z,
                (static_cast<float>(grid_.originV + j * grid_.step) - k_.cy) * invFy * z, z);
  };

  ++attempt_;
  if (attempt_ == 0) {  // stamp wrap-around: wipe once
    std::fill(visited_.begin(), visited_.end(), std::uint8_t{0});
    attempt_ = 1;
  }
  const std::uint8_t stamp = attempt_;
  GrownRegion r;
  const int seedI = seed % w;
  const int seedJ = seed / w;
  r.nearestPoint = pointAt(seedI, seedJ, depth[seed]);
  r.minI = r.maxI = seedI;
  r.minJ = r.maxJ = seedJ;

  int* queue = queue_.data();
  int head = 0;
  int tail = 0;
  int cutTop = static_cast<int>(queue_.size());
  visited_[static_cast<std::size_t>(seed)] = stamp;
  queue[tail++] = seed;
  while (head < tail) {
    const int c = queue[head++];
    const int i = c % w;
    const int j = c / w;
    const float z = depth[c];
    const Vec3 p = pointAt(i, j, z);
    r.pointSum += p;
    r.pixelSum += Vec2(static_cast<float>(grid_.originU + i * grid_.step),
                       static_cast<float>(grid_.originV + j * grid_.step));
    r.areaM2 += z * z * areaPerZ2;
    r.minI = std::min(r.minI, i);
    r.maxI = std::max(r.maxI, i);
    r.minJ = std::min(r.minJ, j);
    r.maxJ = std::max(r.maxJ, j);
    const float limitX = maxDepthStep(rule, z, spacingX);
    const float limitY = maxDepthStep(rule, z, spacingY);
    const auto visit = [&](int n, int ni, int nj, float limit) {
      const auto ns = static_cast<std::size_t>(n);
      if (visited_[ns] == stamp) return;
      const float zn = depth[n];
      if (zn == 0.0f || std::fabs(zn - z) > limit) return;
      const std::uint8_t label = labels_[ns];
      if (label != kFree) {
        // Connected to an accepted region or its cut: this is not a separate volume.
        if (label != kTried) r.touchesEarlierRegion = true;
        return;
      }
      visited_[ns] = stamp;
      const Vec3 q = pointAt(ni, nj, zn);
      if ((q - r.nearestPoint).squaredNorm() <= radius2) {
        queue[tail++] = n;
      } else {
        queue[--cutTop] = n;
        ++r.cutCount;
        r.cutPointSum += q;
        r.cutPixelSum += Vec2(static_cast<float>(grid_.originU + ni * grid_.step),
                              static_cast<float>(grid_.originV + nj * grid_.step));
      }
    };
    if (i > 0) visit(c - 1, i - 1, j, limitX);
    if (i + 1 < w) visit(c + 1, i + 1, j, limitX);
    if (j > 0) visit(c - w, i, j - 1, limitY);
    if (j + 1 < h) visit(c + w, i, j + 1, limitY);
  }
  r.cellCount = tail;
  regionEnd_ = tail;
  cutBegin_ = cutTop;
  return r;
}

void RegionGrower::accept(CellLabel region) {
  assert(region == kRegion1 || region == kRegion2);
  const auto cut = static_cast<std::uint8_t>(region == kRegion1 ? kCut1 : kCut2);
  for (int q = 0; q < regionEnd_; ++q) labels_[static_cast<std::size_t>(queue_[q])] = region;
  for (std::size_t q = static_cast<std::size_t>(cutBegin_); q < queue_.size(); ++q) {
    labels_[static_cast<std::size_t>(queue_[q])] = cut;
  }
}

void RegionGrower::reject() {
  for (int q = 0; q < regionEnd_; ++q) labels_[static_cast<std::size_t>(queue_[q])] = kTried;
}

void RegionGrower::retireAccepted() {
  for (std::uint8_t& label : labels_) {
    if (label == kRegion1 || label == kRegion2) {
      label = kTried;
    } else if (label == kCut1 || label == kCut2) {
      label = kFree;
    }
  }
}

}  // namespace dynahand::cloud
