#include "cloud/region_grow.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>

#include "cloud/depth_filter.h"

namespace dynahand::cloud {

void RegionGrower::reserve(std::size_t cells, int maxWidth, int maxHeight) {
  columnX_.reserve(static_cast<std::size_t>(maxWidth));
  rowY_.reserve(static_cast<std::size_t>(maxHeight));
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
  // Normalised image coordinates of each grid column / row: x = columnX[i] * z.
  columnX_.resize(static_cast<std::size_t>(grid.width));
  rowY_.resize(static_cast<std::size_t>(grid.height));
  for (int i = 0; i < grid.width; ++i) {
    columnX_[static_cast<std::size_t>(i)] =
        (static_cast<float>(grid.originU + i * grid.step) - k.cx) / k.fx;
  }
  for (int j = 0; j < grid.height; ++j) {
    rowY_[static_cast<std::size_t>(j)] =
        (static_cast<float>(grid.originV + j * grid.step) - k.cy) / k.fy;
  }
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

namespace {
// Largest depth step toward the camera still taken as part of the same hand (m): a
// fist's fingers stand up to about this far in front of the palm.
constexpr float kMaxOccluderStepM = 0.06f;
}  // namespace

GrownRegion RegionGrower::grow(int seed, const DepthStepRule& rule, float radiusM) {
  assert(seed >= 0 && static_cast<std::size_t>(seed) < labels_.size());
  const int w = grid_.width;
  const int h = grid_.height;
  const float* depth = grid_.depth;
  std::uint8_t* visited = visited_.data();
  const std::uint8_t* labels = labels_.data();
  const float* columnX = columnX_.data();
  const float* rowY = rowY_.data();
  const auto step = static_cast<float>(grid_.step);
  const float spacingX = step / k_.fx;  // lateral m per m of depth between neighbours
  const float spacingY = step / k_.fy;
  const float areaPerZ2 = spacingX * spacingY;
  const float radius2 = radiusM * radiusM;

  ++attempt_;
  if (attempt_ == 0) {  // stamp wrap-around: wipe once
    std::fill(visited_.begin(), visited_.end(), std::uint8_t{0});
    attempt_ = 1;
  }
  const std::uint8_t stamp = attempt_;
  const int seedI = seed % w;
  const int seedJ = seed / w;
  const float seedZ = depth[seed];
  const Vec3 nearest(columnX[seedI] * seedZ, rowY[seedJ] * seedZ, seedZ);

  // Accumulators in locals (registers), written to the result once at the end.
  Vec3 pointSum = Vec3::Zero();
  float iSum = 0.0f;
  float jSum = 0.0f;
  float areaZ2 = 0.0f;
  int minI = seedI, maxI = seedI, minJ = seedJ, maxJ = seedJ;
  int cutCount = 0;
  Vec3 cutPointSum = Vec3::Zero();
  float cutISum = 0.0f;
  float cutJSum = 0.0f;
  bool touches = false;

  // The queue holds packed cell coordinates (j << 16 | i): no division per cell.
  std::int32_t* queue = queue_.data();
  int head = 0;
  int tail = 0;
  int cutTop = static_cast<int>(queue_.size());
  visited[seed] = stamp;
  queue[tail++] = (seedJ << 16) | seedI;
  while (head < tail) {
    const std::int32_t packed = queue[head++];
    const int i = packed & 0xffff;
    const int j = packed >> 16;
    const int c = j * w + i;
    const float z = depth[c];
    pointSum += Vec3(columnX[i] * z, rowY[j] * z, z);
    iSum += static_cast<float>(i);
    jSum += static_cast<float>(j);
    areaZ2 += z * z;
    minI = std::min(minI, i);
    maxI = std::max(maxI, i);
    minJ = std::min(minJ, j);
    maxJ = std::max(maxJ, j);
    const float limitX = maxDepthStep(rule, z, spacingX);
    const float limitY = maxDepthStep(rule, z, spacingY);
    const auto visit = [&](int n, int ni, int nj, float limit) {
      if (visited[n] == stamp) return;
      const float zn = depth[n];
      if (zn == 0.0f) return;
      // A surface in front of this one, close behind it in depth, occludes it: a finger
      // curled in front of the palm or a thumb across it. It belongs to the same volume
      // even across a depth step (the step rule only stops steps away from the camera),
      // and even if it was passed over before as too small on its own.
      const bool occluder = zn < z && z - zn <= kMaxOccluderStepM;
      if (!occluder && std::fabs(zn - z) > limit) return;
      const std::uint8_t label = labels[n];
      if (label != kFree && !(label == kTried && occluder)) {
        // Connected to an accepted region or its cut: this is not a separate volume.
        touches |= label != kTried;
        return;
      }
      visited[n] = stamp;
      const Vec3 q(columnX[ni] * zn, rowY[nj] * zn, zn);
      if ((q - nearest).squaredNorm() <= radius2) {
        queue[tail++] = (nj << 16) | ni;
      } else {
        queue[--cutTop] = (nj << 16) | ni;
        ++cutCount;
        cutPointSum += q;
        cutISum += static_cast<float>(ni);
        cutJSum += static_cast<float>(nj);
      }
    };
    if (i > 0) visit(c - 1, i - 1, j, limitX);
    if (i + 1 < w) visit(c + 1, i + 1, j, limitX);
    if (j > 0) visit(c - w, i, j - 1, limitY);
    if (j + 1 < h) visit(c + w, i, j + 1, limitY);
  }

  // Cell sums to pixel sums: u = originU + i * step.
  const auto ou = static_cast<float>(grid_.originU);
  const auto ov = static_cast<float>(grid_.originV);
  GrownRegion r;
  r.cellCount = tail;
  r.areaM2 = areaZ2 * areaPerZ2;
  r.touchesEarlierRegion = touches;
  r.nearestPoint = nearest;
  r.pointSum = pointSum;
  r.pixelSum = Vec2(ou * static_cast<float>(tail) + step * iSum,
                    ov * static_cast<float>(tail) + step * jSum);
  r.cutCount = cutCount;
  r.cutPointSum = cutPointSum;
  r.cutPixelSum = Vec2(ou * static_cast<float>(cutCount) + step * cutISum,
                       ov * static_cast<float>(cutCount) + step * cutJSum);
  r.minI = minI;
  r.maxI = maxI;
  r.minJ = minJ;
  r.maxJ = maxJ;
  regionEnd_ = tail;
  cutBegin_ = cutTop;
  return r;
}

void RegionGrower::accept(CellLabel region) {
  assert(region == kRegion1 || region == kRegion2);
  const auto cut = static_cast<std::uint8_t>(region == kRegion1 ? kCut1 : kCut2);
  for (int q = 0; q < regionEnd_; ++q)
    labels_[cellOf(queue_[static_cast<std::size_t>(q)])] = region;
  for (std::size_t q = static_cast<std::size_t>(cutBegin_); q < queue_.size(); ++q) {
    labels_[cellOf(queue_[q])] = cut;
  }
}

void RegionGrower::reject() {
  for (int q = 0; q < regionEnd_; ++q)
    labels_[cellOf(queue_[static_cast<std::size_t>(q)])] = kTried;
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
