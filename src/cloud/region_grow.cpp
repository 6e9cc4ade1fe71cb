#include "cloud/region_grow.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <numbers>

#include "cloud/depth_filter.h"

namespace dynahand::cloud {

void RegionGrower::reserve(std::size_t cells, int maxWidth, int maxHeight) {
  columnX_.reserve(static_cast<std::size_t>(maxWidth));
  rowY_.reserve(static_cast<std::size_t>(maxHeight));
  labels_.reserve(cells);
  visited_.reserve(cells);
  separate_.reserve(cells);
  acrossQueued_.reserve(cells);
  queue_.reserve(cells);
  across_.reserve(cells);
  acrossSide_.reserve(cells);
}

void RegionGrower::reset(const DepthGrid& grid, const Intrinsics& k) {
  grid_ = grid;
  k_ = k;
  const auto cells = static_cast<std::size_t>(grid.width) * grid.height;
  labels_.assign(cells, kFree);
  // One byte per cell (cache-friendly), stamped with the grow() attempt. Stamps only grow
  // until they wrap (then all are wiped, in grow()), so a stale stamp of an earlier grid never
  // equals the current one: nothing to clear here.
  visited_.resize(cells);
  separate_.resize(cells);
  acrossQueued_.resize(cells);
  queue_.resize(cells);
  across_.resize(cells);
  acrossSide_.resize(cells);
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
  labelled_ = false;
}

int RegionGrower::nearestFreeCell(float maxDepthM, const Vec3* avoidCentre,
                                  float avoidRadiusM) const {
  int best = -1;
  // See nearestFreeCellWhere: bit patterns minus one put "no data" last.
  const float limit =
      maxDepthM > 0.0f ? std::nextafter(maxDepthM, 1e9f) : std::numeric_limits<float>::infinity();
  std::uint32_t bestKey = std::bit_cast<std::uint32_t>(limit) - 1u;
  if (!labelled_ && avoidCentre == nullptr) {
    // Every cell is free: the smallest key, then its first cell (both loops vectorise).
    const std::size_t cells = static_cast<std::size_t>(grid_.width) * grid_.height;
    std::uint32_t smallest = std::numeric_limits<std::uint32_t>::max();
    for (std::size_t c = 0; c < cells; ++c) {
      const std::uint32_t key = std::bit_cast<std::uint32_t>(grid_.depth[c]) - 1u;
      smallest = key < smallest ? key : smallest;
    }
    if (smallest >= bestKey) return -1;
    std::size_t c = 0;
    while (std::bit_cast<std::uint32_t>(grid_.depth[c]) - 1u != smallest) ++c;
    return static_cast<int>(c);
  }
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

int RegionGrower::closestFreeCell(const Vec3& p) const {
  int best = -1;
  float bestDistance2 = std::numeric_limits<float>::infinity();
  for (int j = 0; j < grid_.height; ++j) {
    const std::size_t row = static_cast<std::size_t>(j) * grid_.width;
    const float* depth = grid_.depth + row;
    for (int i = 0; i < grid_.width; ++i) {
      const float z = depth[i];
      if (z == 0.0f || labels_[row + i] != kFree) continue;
      const Vec3 q(columnX_[static_cast<std::size_t>(i)] * z,
                   rowY_[static_cast<std::size_t>(j)] * z, z);
      const float d2 = (q - p).squaredNorm();
      if (d2 < bestDistance2) {
        bestDistance2 = d2;
        best = static_cast<int>(row + static_cast<std::size_t>(i));
      }
    }
  }
  return best;
}

namespace {
// Largest depth step between two surfaces of one hand (m): a fist's fingers stand up to
// about this far in front of the palm, and fingers pointing at the camera this far in
// front of each other.
constexpr float kMaxOccluderStepM = 0.06f;
// Largest depth step (m) to a finger seen past the hand that hides the rest of it: a finger
// pointing away from the camera (the index of a fist seen from behind by a head-mounted
// camera) shows its tip up to about its length behind the knuckles in front of it.
constexpr float kMaxHiddenFingerStepM = 0.12f;
// Where a surface across a depth step lies relative to the region cell beside it: in front,
// behind within kMaxOccluderStepM, behind within kMaxHiddenFingerStepM, or farther.
enum AcrossSide : std::uint8_t { kInFront = 0, kBehind = 1, kFingerBehind = 2, kFarBehind = 3 };
}  // namespace

// grow's running state: the settings of this call, the region's sums, the queue's ends and
// the surface across a depth step being tried.
struct RegionGrower::Growth {
  // Accumulators, written to the result once at the end. A copy is kept while a surface
  // across a depth step is tried, to undo it.
  struct Sums {
    Vec3 pointSum = Vec3::Zero();
    float iSum = 0.0f;
    float jSum = 0.0f;
    float areaZ2 = 0.0f;
    int minI = 0, maxI = 0, minJ = 0, maxJ = 0;
    int cutCount = 0;
    Vec3 cutPointSum = Vec3::Zero();
    float cutISum = 0.0f;
    float cutJSum = 0.0f;
    bool touches = false;
  };
  const DepthStepRule* rule = nullptr;
  float spacingX = 0.0f;  // lateral m per m of depth between neighbours
  float spacingY = 0.0f;
  float areaPerZ2 = 0.0f;
  float minAreaZ2 = 0.0f;      // minAreaM2 as a sum of z^2
  float maxPartAreaZ2 = 0.0f;  // see beginGrowth
  float radius2 = 0.0f;        // m^2
  std::uint8_t stamp = 0;
  Vec3 nearest = Vec3::Zero();  // the seed's point
  Sums sums;
  // The queue holds packed cell coordinates (j << 16 | i): the region from the front, its
  // cut cells from the back.
  int head = 0;
  int tail = 0;
  int cutTop = 0;
  // Cells across a depth step from the region (too large for the step rule, not an
  // occluder) within its ball, and on which side they lie (across_, acrossSide_). Tried once
  // the region's own surface is complete.
  int acrossHead = 0;
  int acrossTail = 0;
  // While a surface across a step is tried: its side and area limit, the state to return
  // to, and whether it turned out to be part of a surface already found separate.
  bool trying = false;
  bool joinsSeparate = false;
  float partLimitZ2 = 0.0f;
  std::uint8_t trySide = kInFront;
  bool fragmentsChecked = false;
  bool fromFragments = false;     // the seed's surface alone is smaller than minAreaM2
  bool inFrontOfSurface = false;  // see settleTriedSurface: not a volume of its own
  Sums before;
  int tailBefore = 0;
  int cutTopBefore = 0;
  int acrossTailBefore = 0;
};

GrownRegion RegionGrower::grow(int seed, const DepthStepRule& rule, float radiusM,
                               float minAreaM2) {
  assert(seed >= 0 && static_cast<std::size_t>(seed) < labels_.size());
  Growth g = beginGrowth(seed, rule, radiusM, minAreaM2);
  for (;;) {
    floodSurface(g);
    if (!g.trying && !g.fragmentsChecked) {
      // The seed's own surface is complete.
      g.fragmentsChecked = true;
      g.fromFragments = g.sums.areaZ2 < g.minAreaZ2;
    }
    if (g.trying && settleTriedSurface(g)) break;
    const std::int32_t next = nextSurfaceAcross(g);
    if (next < 0) break;
    g.trying = true;
    g.joinsSeparate = false;
    g.before = g.sums;
    g.tailBefore = g.tail;
    g.cutTopBefore = g.cutTop;
    g.acrossTailBefore = g.acrossTail;
    visited_[cellOf(next)] = g.stamp;
    queue_[static_cast<std::size_t>(g.tail++)] = next;
  }
  return finishGrowth(g);
}

RegionGrower::Growth RegionGrower::beginGrowth(int seed, const DepthStepRule& rule, float radiusM,
                                               float minAreaM2) {
  Growth g;
  g.rule = &rule;
  const auto step = static_cast<float>(grid_.step);
  g.spacingX = step / k_.fx;
  g.spacingY = step / k_.fy;
  g.areaPerZ2 = g.spacingX * g.spacingY;
  g.minAreaZ2 = minAreaM2 / g.areaPerZ2;
  // A surface across a depth step covering more than half the ball's cross-section is
  // larger than a hand and forearm inside the ball: a wall, a table or the torso.
  g.maxPartAreaZ2 = 0.5f * std::numbers::pi_v<float> * radiusM * radiusM / g.areaPerZ2;
  g.radius2 = radiusM * radiusM;

  ++attempt_;
  if (attempt_ == 0) {  // stamp wrap-around: wipe once
    std::fill(visited_.begin(), visited_.end(), std::uint8_t{0});
    std::fill(separate_.begin(), separate_.end(), std::uint8_t{0});
    std::fill(acrossQueued_.begin(), acrossQueued_.end(), std::uint8_t{0});
    attempt_ = 1;
  }
  g.stamp = attempt_;
  const int seedI = seed % grid_.width;
  const int seedJ = seed / grid_.width;
  const float seedZ = grid_.depth[seed];
  g.nearest = Vec3(columnX_[static_cast<std::size_t>(seedI)] * seedZ,
                   rowY_[static_cast<std::size_t>(seedJ)] * seedZ, seedZ);
  g.sums.minI = g.sums.maxI = seedI;
  g.sums.minJ = g.sums.maxJ = seedJ;
  g.cutTop = static_cast<int>(queue_.size());
  visited_[static_cast<std::size_t>(seed)] = g.stamp;
  queue_[static_cast<std::size_t>(g.tail++)] = (seedJ << 16) | seedI;
  return g;
}

void RegionGrower::floodSurface(Growth& g) {
  const int w = grid_.width;
  const int h = grid_.height;
  const float* depth = grid_.depth;
  std::uint8_t* visited = visited_.data();
  std::uint8_t* separate = separate_.data();
  std::uint8_t* acrossQueued = acrossQueued_.data();
  const std::uint8_t* labels = labels_.data();
  const float* columnX = columnX_.data();
  const float* rowY = rowY_.data();
  std::int32_t* queue = queue_.data();
  std::int32_t* across = across_.data();
  std::uint8_t* acrossSide = acrossSide_.data();
  const DepthStepRule& rule = *g.rule;
  const float spacingX = g.spacingX;
  const float spacingY = g.spacingY;
  const float radius2 = g.radius2;
  const std::uint8_t stamp = g.stamp;
  const Vec3 nearest = g.nearest;
  const bool trying = g.trying;
  const float partLimitZ2 = g.partLimitZ2;
  const float beforeAreaZ2 = g.before.areaZ2;
  // The running state in locals (registers) while the queue drains, written back at the end.
  Growth::Sums sums = g.sums;
  int head = g.head;
  int tail = g.tail;
  int cutTop = g.cutTop;
  int acrossTail = g.acrossTail;
  bool joinsSeparate = g.joinsSeparate;
  while (head < tail) {
    const std::int32_t packed = queue[head++];
    const int i = packed & 0xffff;
    const int j = packed >> 16;
    const int c = j * w + i;
    const float z = depth[c];
    sums.pointSum += Vec3(columnX[i] * z, rowY[j] * z, z);
    sums.iSum += static_cast<float>(i);
    sums.jSum += static_cast<float>(j);
    sums.areaZ2 += z * z;
    sums.minI = std::min(sums.minI, i);
    sums.maxI = std::max(sums.maxI, i);
    sums.minJ = std::min(sums.minJ, j);
    sums.maxJ = std::max(sums.maxJ, j);
    const float limitX = maxDepthStep(rule, z, spacingX);
    const float limitY = maxDepthStep(rule, z, spacingY);
    const auto visit = [&](int n, int ni, int nj, float limit) {
      if (visited[n] == stamp) {
        // A surface being tried that continues into one found separate is part of it.
        if (trying && separate[n] == stamp && std::fabs(depth[n] - z) <= limit) {
          joinsSeparate = true;
        }
        return;
      }
      const float zn = depth[n];
      if (zn == 0.0f) return;
      // A surface in front of this one, close behind it in depth, occludes it: a finger
      // curled in front of the palm or a thumb across it. It belongs to the same volume
      // even across a depth step (the step rule only stops steps away from the camera),
      // and even if it was passed over before as too small on its own.
      const bool occluder = zn < z && z - zn <= kMaxOccluderStepM;
      if (!occluder && std::fabs(zn - z) > limit) {
        // Another surface across a depth step; within the hand's ball it may still be part
        // of the same volume. Decided once the region's own surfaces are complete.
        if (acrossQueued[n] != stamp && (labels[n] == kFree || (labels[n] == kTried && zn < z))) {
          const Vec3 q(columnX[ni] * zn, rowY[nj] * zn, zn);
          if ((q - nearest).squaredNorm() <= radius2) {
            acrossQueued[n] = stamp;
            acrossSide[acrossTail] = zn < z                            ? kInFront
                                     : zn - z <= kMaxOccluderStepM     ? kBehind
                                     : zn - z <= kMaxHiddenFingerStepM ? kFingerBehind
                                                                       : kFarBehind;
            across[acrossTail++] = (nj << 16) | ni;
          }
        }
        return;
      }
      const std::uint8_t label = labels[n];
      if (label != kFree && !(label == kTried && occluder)) {
        // Connected to an accepted region or its cut: this is not a separate volume.
        sums.touches |= label != kTried;
        return;
      }
      visited[n] = stamp;
      const Vec3 q(columnX[ni] * zn, rowY[nj] * zn, zn);
      if ((q - nearest).squaredNorm() <= radius2) {
        queue[tail++] = (nj << 16) | ni;
      } else {
        queue[--cutTop] = (nj << 16) | ni;
        ++sums.cutCount;
        sums.cutPointSum += q;
        sums.cutISum += static_cast<float>(ni);
        sums.cutJSum += static_cast<float>(nj);
      }
    };
    if (i > 0) visit(c - 1, i - 1, j, limitX);
    if (i + 1 < w) visit(c + 1, i + 1, j, limitX);
    if (j > 0) visit(c - w, i, j - 1, limitY);
    if (j + 1 < h) visit(c + w, i, j + 1, limitY);
    if (trying && (joinsSeparate || sums.areaZ2 - beforeAreaZ2 > partLimitZ2)) break;
  }
  g.sums = sums;
  g.head = head;
  g.tail = tail;
  g.cutTop = cutTop;
  g.acrossTail = acrossTail;
  g.joinsSeparate = joinsSeparate;
}

bool RegionGrower::settleTriedSurface(Growth& g) {
  g.trying = false;
  const float partZ2 = g.sums.areaZ2 - g.before.areaZ2;
  // Fragments in front of a surface close behind them (not a fragment itself) are
  // pieces of that surface broken up by holes or steep sides (a fingertip in front of
  // the palm, the torso's edge): not a volume of their own.
  if (g.fromFragments && g.trySide == kBehind && (g.joinsSeparate || partZ2 >= g.minAreaZ2)) {
    g.inFrontOfSurface = true;
  }
  if (g.inFrontOfSurface || g.joinsSeparate || partZ2 > g.partLimitZ2) {
    // Too large to be part of the hand: a surface of its own. Its cells stay visited and
    // are marked separate, so the rest of that surface is recognised from any side.
    for (int q = g.tailBefore; q < g.tail; ++q)
      separate_[cellOf(queue_[static_cast<std::size_t>(q)])] = g.stamp;
    for (int q = g.cutTop; q < g.cutTopBefore; ++q)
      visited_[cellOf(queue_[static_cast<std::size_t>(q)])] = 0;
    for (int q = g.acrossTailBefore; q < g.acrossTail; ++q)
      acrossQueued_[cellOf(across_[static_cast<std::size_t>(q)])] = 0;
    g.sums = g.before;
    g.head = g.tail = g.tailBefore;
    g.cutTop = g.cutTopBefore;
    g.acrossTail = g.acrossTailBefore;
  }
  return g.inFrontOfSurface;
}

std::int32_t RegionGrower::nextSurfaceAcross(Growth& g) {
  // The next surface across a depth step from the region, within its ball. A region
  // smaller than minAreaM2 is not a hand yet: it collects the fragments (surfaces smaller
  // than minAreaM2) beside it at any step, e.g. fingers pointing at the camera, each a few
  // cm in front of the next. Once large enough it takes fragments in front of it (more
  // fingers) and surfaces behind it within kMaxOccluderStepM (the palm behind curled
  // fingers) or kMaxHiddenFingerStepM (a finger pointing away, its tip seen past the
  // knuckles that hide the rest of it) unless larger than a hand and forearm can be inside
  // the ball (a wall, a table, the torso).
  const bool small = g.sums.areaZ2 < g.minAreaZ2;
  while (g.acrossHead < g.acrossTail) {
    const auto index = static_cast<std::size_t>(g.acrossHead++);
    const std::int32_t packed = across_[index];
    const std::uint8_t side = acrossSide_[index];
    if (visited_[cellOf(packed)] == g.stamp || (!small && side == kFarBehind)) continue;
    g.partLimitZ2 = small || side == kInFront ? g.minAreaZ2 : g.maxPartAreaZ2;
    g.trySide = side;
    return packed;
  }
  return -1;
}

GrownRegion RegionGrower::finishGrowth(const Growth& g) {
  // Cell sums to pixel sums: u = originU + i * step.
  const auto step = static_cast<float>(grid_.step);
  const auto ou = static_cast<float>(grid_.originU);
  const auto ov = static_cast<float>(grid_.originV);
  const Growth::Sums& sums = g.sums;
  GrownRegion r;
  r.cellCount = g.tail;
  r.areaM2 = sums.areaZ2 * g.areaPerZ2;
  r.touchesEarlierRegion = sums.touches;
  r.inFrontOfSurface = g.inFrontOfSurface;
  r.nearestPoint = g.nearest;
  r.pointSum = sums.pointSum;
  r.pixelSum = Vec2(ou * static_cast<float>(g.tail) + step * sums.iSum,
                    ov * static_cast<float>(g.tail) + step * sums.jSum);
  r.cutCount = sums.cutCount;
  r.cutPointSum = sums.cutPointSum;
  r.cutPixelSum = Vec2(ou * static_cast<float>(sums.cutCount) + step * sums.cutISum,
                       ov * static_cast<float>(sums.cutCount) + step * sums.cutJSum);
  r.minI = sums.minI;
  r.maxI = sums.maxI;
  r.minJ = sums.minJ;
  r.maxJ = sums.maxJ;
  regionEnd_ = g.tail;
  cutBegin_ = g.cutTop;
  return r;
}

void RegionGrower::accept(CellLabel region) {
  assert(region == kRegion1 || region == kRegion2);
  labelled_ = true;
  const auto cut = static_cast<std::uint8_t>(region == kRegion1 ? kCut1 : kCut2);
  for (int q = 0; q < regionEnd_; ++q)
    labels_[cellOf(queue_[static_cast<std::size_t>(q)])] = region;
  for (std::size_t q = static_cast<std::size_t>(cutBegin_); q < queue_.size(); ++q) {
    labels_[cellOf(queue_[q])] = cut;
  }
}

void RegionGrower::reject() {
  labelled_ = true;
  for (int q = 0; q < regionEnd_; ++q)
    labels_[cellOf(queue_[static_cast<std::size_t>(q)])] = kTried;
}

float RegionGrower::labelCellsWithin(const std::int32_t* packed, std::size_t count,
                                     CellLabel region, const Vec3& centre, float radiusM) {
  const auto label = static_cast<std::uint8_t>(region);
  const float radius2 = radiusM * radiusM;
  float areaZ2 = 0.0f;
  for (std::size_t q = 0; q < count; ++q) {
    const std::size_t c = cellOf(packed[q]);
    if (labels_[c] == label) continue;
    const int i = packed[q] & 0xffff;
    const int j = packed[q] >> 16;
    const float z = grid_.depth[c];
    const Vec3 p(columnX_[static_cast<std::size_t>(i)] * z, rowY_[static_cast<std::size_t>(j)] * z,
                 z);
    if ((p - centre).squaredNorm() > radius2) continue;
    labels_[c] = label;
    labelled_ = true;
    areaZ2 += z * z;
  }
  const auto step = static_cast<float>(grid_.step);
  return areaZ2 * (step / k_.fx) * (step / k_.fy);
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
