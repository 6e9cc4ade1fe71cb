#include "cloud/limb_end.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "cloud/depth_filter.h"

namespace dynahand::cloud {

namespace {
enum CellState : std::uint8_t { kUnseen = 0, kSurface = 1, kAttachment = 2 };
}  // namespace

void LimbEndFinder::reserve(std::size_t cells) {
  distance_.reserve(cells);
  state_.reserve(cells);
  cells_.reserve(cells);
  heap_.reserve(5 * cells);  // attachments + at most four relaxations per cell
}

int LimbEndFinder::find(const DepthGrid& grid, const Intrinsics& k, int seed,
                        const DepthStepRule& rule, float limbRadiusM, int borderMarginPixels) {
  const int w = grid.width;
  const int h = grid.height;
  const auto cellCount = static_cast<std::size_t>(w) * h;
  state_.assign(cellCount, kUnseen);
  distance_.assign(cellCount, std::numeric_limits<float>::infinity());
  cells_.clear();
  heap_.clear();
  const float* depth = grid.depth;
  const auto step = static_cast<float>(grid.step);
  const float spacingX = step / k.fx;
  const float spacingY = step / k.fy;
  // One rule both ways (symmetric), so the surface explored is the graph searched.
  const auto joined = [&](float za, float zb, float spacing) {
    return std::fabs(za - zb) <= maxDepthStep(rule, std::max(za, zb), spacing);
  };
  const auto atBorder = [&](int i, int j) {
    if (borderMarginPixels <= 0) return i == 0 || j == 0 || i + 1 == w || j + 1 == h;
    const int u = grid.originU + i * grid.step;
    const int v = grid.originV + j * grid.step;
    return u < borderMarginPixels || v < borderMarginPixels || u >= k.width - borderMarginPixels ||
           v >= k.height - borderMarginPixels;
  };
  const int seedI = seed % w;
  const int seedJ = seed / w;
  const Vec3 centre = grid.point(k, seedI, seedJ);
  const float radius2 = limbRadiusM * limbRadiusM;

  // 1. The connected surface inside the ball; attachments where it leaves the ball or
  //    the image.
  state_[static_cast<std::size_t>(seed)] = kSurface;
  cells_.push_back(seed);
  bool attached = false;
  for (std::size_t q = 0; q < cells_.size(); ++q) {
    const int c = cells_[q];
    const int i = c % w;
    const int j = c / w;
    const float z = depth[c];
    bool leaves = atBorder(i, j);
    const auto visit = [&](int n, int ni, int nj, float spacing) {
      const auto un = static_cast<std::size_t>(n);
      if (state_[un] != kUnseen || depth[n] == 0.0f || !joined(z, depth[n], spacing)) return;
      if ((grid.point(k, ni, nj) - centre).squaredNorm() > radius2) {
        leaves = true;
        return;
      }
      state_[un] = kSurface;
      cells_.push_back(n);
    };
    if (i > 0) visit(c - 1, i - 1, j, spacingX);
    if (i + 1 < w) visit(c + 1, i + 1, j, spacingX);
    if (j > 0) visit(c - w, i, j - 1, spacingY);
    if (j + 1 < h) visit(c + w, i, j + 1, spacingY);
    if (leaves) {
      state_[static_cast<std::size_t>(c)] = kAttachment;
      distance_[static_cast<std::size_t>(c)] = 0.0f;
      heap_.push_back({0.0f, c});
      attached = true;
    }
  }
  if (!attached) return -1;

  // 2. Distance along the surface from the nearest attachment (Dijkstra, 3D steps).
  const auto later = [](const HeapEntry& a, const HeapEntry& b) {
    return a.distance > b.distance || (a.distance == b.distance && a.cell > b.cell);
  };
  std::make_heap(heap_.begin(), heap_.end(), later);
  while (!heap_.empty()) {
    std::pop_heap(heap_.begin(), heap_.end(), later);
    const HeapEntry top = heap_.back();
    heap_.pop_back();
    const auto uc = static_cast<std::size_t>(top.cell);
    if (top.distance > distance_[uc]) continue;  // a stale entry
    const int i = top.cell % w;
    const int j = top.cell / w;
    const float z = depth[uc];
    const Vec3 p = grid.point(k, i, j);
    const auto relax = [&](int n, int ni, int nj, float spacing) {
      const auto un = static_cast<std::size_t>(n);
      if (state_[un] == kUnseen || !joined(z, depth[n], spacing)) return;
      const float d = top.distance + (grid.point(k, ni, nj) - p).norm();
      if (d >= distance_[un]) return;
      distance_[un] = d;
      heap_.push_back({d, n});
      std::push_heap(heap_.begin(), heap_.end(), later);
    };
    if (i > 0) relax(top.cell - 1, i - 1, j, spacingX);
    if (i + 1 < w) relax(top.cell + 1, i + 1, j, spacingX);
    if (j > 0) relax(top.cell - w, i, j - 1, spacingY);
    if (j + 1 < h) relax(top.cell + w, i, j + 1, spacingY);
  }

  // 3. The farthest reachable cell (first in discovery order on ties: deterministic).
  int end = -1;
  float farthest = -1.0f;
  for (const std::int32_t c : cells_) {
    const float d = distance_[static_cast<std::size_t>(c)];
    if (std::isfinite(d) && d > farthest) {
      farthest = d;
      end = c;
    }
  }
  return end;
}

}  // namespace dynahand::cloud
