#include "cloud/limb_end.h"

#include <algorithm>
#include <cmath>

#include "cloud/depth_filter.h"

namespace dynahand::cloud {

namespace {
enum CellState : std::uint8_t { kUnseen = 0, kSurface = 1, kAttachment = 2 };
// A surface nearer than find()'s nearCutDepthM that runs into a hole of at least two cells while
// coming nearer by more than this share of the cell spacing per cell (depth / lateral) leaves
// the sensor's near range there: an arm reaching past a head-mounted camera, cut off where it
// comes too near to be measured. Silhouette edges (the surface turning away) and level holes
// are not cuts.
constexpr float kNearCutSlope = 0.5f;
// Separate attachments whose mean image rows lie farther apart than this share of the ball's
// radius (at the seed's depth) are a limb attached at the lower one and a hand that goes on
// out of view at the upper one (keepBodySide).
constexpr float kBodySideSeparation = 0.25f;

// Whether neighbouring samples at depths za and zb (m), `spacing` apart per m of depth, lie on
// one surface. One rule both ways (symmetric), so the surface explored is the graph searched.
bool joined(const DepthStepRule& rule, float za, float zb, float spacing) {
  return std::fabs(za - zb) <= maxDepthStep(rule, std::max(za, zb), spacing);
}

// Cells are queued as packed coordinates (j << 16 | i): no division per cell.
std::int32_t pack(int i, int j) {
  return (j << 16) | i;
}
// The grid index (row-major) of a packed cell.
std::size_t cellIndex(std::int32_t packed, int width) {
  return static_cast<std::size_t>((packed >> 16) * width + (packed & 0xffff));
}
}  // namespace

void LimbEndFinder::reserve(std::size_t cells, int maxWidth, int maxHeight) {
  columnX_.reserve(static_cast<std::size_t>(maxWidth));
  rowY_.reserve(static_cast<std::size_t>(maxHeight));
  steps_.reserve(cells);
  state_.reserve(cells);
  cells_.reserve(cells);
  queue_.reserve(cells);
  planeContacts_.reserve(cells);
  group_.reserve(cells);
  stack_.reserve(cells);
  groupRows_.reserve(cells);
  groupCounts_.reserve(cells);
}

int LimbEndFinder::find(const DepthGrid& grid, const Intrinsics& k, int seed,
                        const DepthStepRule& rule, float limbRadiusM, int borderMarginPixels,
                        float nearCutDepthM, const std::uint8_t* planeCells) {
  const int w = grid.width;
  const int h = grid.height;
  const auto cellCount = static_cast<std::size_t>(w) * h;
  state_.assign(cellCount, kUnseen);
  steps_.assign(cellCount, -1);
  cells_.clear();
  queue_.clear();
  planeContacts_.clear();
  const float* depth = grid.depth;
  const auto step = static_cast<float>(grid.step);
  const float spacingX = step / k.fx;
  const float spacingY = step / k.fy;
  const auto atBorder = [&](int i, int j) {
    if (borderMarginPixels <= 0) return i == 0 || j == 0 || i + 1 == w || j + 1 == h;
    const int u = grid.originU + i * grid.step;
    const int v = grid.originV + j * grid.step;
    return u < borderMarginPixels || v < borderMarginPixels || u >= k.width - borderMarginPixels ||
           v >= k.height - borderMarginPixels;
  };
  // Normalised image coordinates of each column / row: x = columnX[i] * z.
  columnX_.resize(static_cast<std::size_t>(w));
  rowY_.resize(static_cast<std::size_t>(h));
  for (int i = 0; i < w; ++i) {
    columnX_[static_cast<std::size_t>(i)] =
        (static_cast<float>(grid.originU + i * grid.step) - k.cx) / k.fx;
  }
  for (int j = 0; j < h; ++j) {
    rowY_[static_cast<std::size_t>(j)] =
        (static_cast<float>(grid.originV + j * grid.step) - k.cy) / k.fy;
  }
  const auto point = [&](int i, int j, float z) {
    return Vec3(columnX_[static_cast<std::size_t>(i)] * z, rowY_[static_cast<std::size_t>(j)] * z,
                z);
  };
  const int seedI = seed % w;
  const int seedJ = seed / w;
  const Vec3 centre = point(seedI, seedJ, depth[seed]);
  const float radius2 = limbRadiusM * limbRadiusM;

  // 1. The connected surface inside the ball; attachments where it leaves the ball or
  //    the image.
  state_[static_cast<std::size_t>(seed)] = kSurface;
  cells_.push_back(pack(seedI, seedJ));
  bool attached = false;
  for (std::size_t q = 0; q < cells_.size(); ++q) {
    const int i = cells_[q] & 0xffff;
    const int j = cells_[q] >> 16;
    const int c = j * w + i;
    const float z = depth[c];
    bool leaves = atBorder(i, j);
    bool touchesPlane = false;
    // n = c + d; back = c - d; beyond = c + 2d (-1 where outside the grid).
    const auto visit = [&](int n, int ni, int nj, float spacing, int back, int beyond) {
      const auto un = static_cast<std::size_t>(n);
      if (depth[n] == 0.0f) {
        touchesPlane = touchesPlane || (planeCells != nullptr && planeCells[n] != 0);
        if (z < nearCutDepthM && back >= 0 && beyond >= 0 && depth[beyond] == 0.0f &&
            depth[back] > 0.0f && depth[back] - z > kNearCutSlope * spacing * z)
          leaves = true;  // the limb comes nearer than the sensor's range
        return;
      }
      if (state_[un] != kUnseen || !joined(rule, z, depth[n], spacing)) return;
      if ((point(ni, nj, depth[n]) - centre).squaredNorm() > radius2) {
        leaves = true;
        return;
      }
      state_[un] = kSurface;
      cells_.push_back(pack(ni, nj));
    };
    if (i > 0) visit(c - 1, i - 1, j, spacingX, i + 1 < w ? c + 1 : -1, i > 1 ? c - 2 : -1);
    if (i + 1 < w) visit(c + 1, i + 1, j, spacingX, i > 0 ? c - 1 : -1, i + 2 < w ? c + 2 : -1);
    if (j > 0) visit(c - w, i, j - 1, spacingY, j + 1 < h ? c + w : -1, j > 1 ? c - 2 * w : -1);
    if (j + 1 < h) visit(c + w, i, j + 1, spacingY, j > 0 ? c - w : -1, j + 2 < h ? c + 2 * w : -1);
    if (leaves) {
      state_[static_cast<std::size_t>(c)] = kAttachment;
      steps_[static_cast<std::size_t>(c)] = 0;
      queue_.push_back(cells_[q]);
      attached = true;
    } else if (touchesPlane) {
      planeContacts_.push_back(cells_[q]);
    }
  }
  if (!attached) {
    // Attached nowhere else: where it meets a support plane.
    for (const std::int32_t packed : planeContacts_) {
      const std::size_t c = cellIndex(packed, w);
      state_[c] = kAttachment;
      steps_[c] = 0;
      queue_.push_back(packed);
      attached = true;
    }
  }
  if (!attached) return -1;

  keepBodySide(grid, k, centre.z(), kBodySideSeparation * limbRadiusM);
  stepFromAttachments(grid, k, rule);
  return farthestCell(grid.width);
}

void LimbEndFinder::keepBodySide(const DepthGrid& grid, const Intrinsics& k, float depthM,
                                 float separationM) {
  // Connected groups of attachment cells (8-neighbours, flood-filled over the grid), each with
  // its mean row.
  const int w = grid.width;
  const int h = grid.height;
  group_.assign(state_.size(), -1);
  groupRows_.clear();
  groupCounts_.clear();
  for (const std::int32_t first : queue_) {
    const std::size_t c0 = cellIndex(first, w);
    if (group_[c0] >= 0) continue;
    const int group = static_cast<int>(groupRows_.size());
    groupRows_.push_back(0.0f);
    groupCounts_.push_back(0);
    group_[c0] = group;
    stack_.assign(1, first);
    while (!stack_.empty()) {
      const std::int32_t packed = stack_.back();
      stack_.pop_back();
      const int i = packed & 0xffff;
      const int j = packed >> 16;
      groupRows_[static_cast<std::size_t>(group)] += static_cast<float>(j);
      ++groupCounts_[static_cast<std::size_t>(group)];
      for (int dj = -1; dj <= 1; ++dj) {
        for (int di = -1; di <= 1; ++di) {
          const int ni = i + di, nj = j + dj;
          if ((di == 0 && dj == 0) || ni < 0 || nj < 0 || ni >= w || nj >= h) continue;
          const auto n = static_cast<std::size_t>(nj * w + ni);
          if (state_[n] != kAttachment || group_[n] >= 0) continue;
          group_[n] = group;
          stack_.push_back(pack(ni, nj));
        }
      }
    }
  }
  if (groupRows_.size() < 2) return;
  float lowest = -1.0f;
  for (std::size_t g = 0; g < groupRows_.size(); ++g) {
    groupRows_[g] /= static_cast<float>(groupCounts_[g]);
    lowest = std::max(lowest, groupRows_[g]);
  }
  // Rows (cells) apart that make two attachments a limb and a hand out of view.
  const float apart = separationM * k.fy / (depthM * static_cast<float>(grid.step));
  std::size_t kept = 0;
  for (std::size_t a = 0; a < queue_.size(); ++a) {
    const std::size_t c = cellIndex(queue_[a], w);
    if (groupRows_[static_cast<std::size_t>(group_[c])] < lowest - apart) {
      state_[c] = kSurface;
      steps_[c] = -1;
    } else {
      queue_[kept++] = queue_[a];
    }
  }
  queue_.resize(kept);
}

void LimbEndFinder::stepFromAttachments(const DepthGrid& grid, const Intrinsics& k,
                                        const DepthStepRule& rule) {
  // Steps along the surface from the nearest attachment (breadth-first from all of them).
  const int w = grid.width;
  const int h = grid.height;
  const float* depth = grid.depth;
  const auto step = static_cast<float>(grid.step);
  const float spacingX = step / k.fx;
  const float spacingY = step / k.fy;
  for (std::size_t q = 0; q < queue_.size(); ++q) {
    const int i = queue_[q] & 0xffff;
    const int j = queue_[q] >> 16;
    const int c = j * w + i;
    const float z = depth[c];
    const int next = steps_[static_cast<std::size_t>(c)] + 1;
    const auto relax = [&](int n, int ni, int nj, float spacing) {
      const auto un = static_cast<std::size_t>(n);
      if (state_[un] == kUnseen || steps_[un] >= 0 || !joined(rule, z, depth[n], spacing)) return;
      steps_[un] = next;
      queue_.push_back(pack(ni, nj));
    };
    if (i > 0) relax(c - 1, i - 1, j, spacingX);
    if (i + 1 < w) relax(c + 1, i + 1, j, spacingX);
    if (j > 0) relax(c - w, i, j - 1, spacingY);
    if (j + 1 < h) relax(c + w, i, j + 1, spacingY);
  }
}

int LimbEndFinder::farthestCell(int width) const {
  // The farthest reachable cell (first in discovery order on ties: deterministic).
  int end = -1;
  int farthest = -1;
  for (const std::int32_t packed : cells_) {
    const std::size_t c = cellIndex(packed, width);
    const int d = steps_[c];
    if (d > farthest) {
      farthest = d;
      end = static_cast<int>(c);
    }
  }
  return end;
}

}  // namespace dynahand::cloud
