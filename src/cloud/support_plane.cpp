#include "cloud/support_plane.h"

#include <Eigen/Eigenvalues>
#include <algorithm>

namespace dynahand::cloud {

namespace {

// Hypotheses are scored on about this many samples; only the best is scored on all.
constexpr std::size_t kScoredSamples = 1200;
// A hypothesis' second and third samples lie within this many cells of its first (samples near
// each other lie on one surface more often than random ones).
constexpr int kHypothesisCells = 10;
// Three samples spanning less than this triangle area (m^2) give no reliable normal.
constexpr float kMinTriangleAreaM2 = 2e-4f;
constexpr int kSampleTries = 8;  // draws per hypothesis before giving up on it
constexpr std::uint32_t kSeed = 0x9e3779b9u;

std::uint32_t nextRandom(std::uint32_t& state) {
  state = state * 1664525u + 1013904223u;  // Numerical Recipes' LCG
  return state >> 8;
}

// Orients (n, offset) toward the camera (the origin lies on the positive side).
void faceCamera(Vec3& n, float& offset) {
  if (offset > 0.0f) {
    n = -n;
    offset = -offset;
  }
}

}  // namespace

void SupportPlaneFinder::reserve(std::size_t cells) {
  points_.reserve(cells);
  area_.reserve(cells);
  cellOfPoint_.reserve(cells);
  pointOfCell_.reserve(cells);
}

float SupportPlaneFinder::inlierArea(const SupportPlane& plane, float bandM,
                                     std::size_t every) const {
  float area = 0.0f;
  for (std::size_t i = 0; i < points_.size(); i += every) {
    if (onPlane(plane, points_[i], bandM)) area += area_[i];
  }
  return area * static_cast<float>(every);
}

bool SupportPlaneFinder::refit(SupportPlane& plane, float bandM) const {
  Vec3 mean = Vec3::Zero();
  float weight = 0.0f;
  for (std::size_t i = 0; i < points_.size(); ++i) {
    if (area_[i] > 0.0f && onPlane(plane, points_[i], bandM)) {
      mean += area_[i] * points_[i];
      weight += area_[i];
    }
  }
  if (weight <= 0.0f) return false;
  mean /= weight;
  Eigen::Matrix3f covariance = Eigen::Matrix3f::Zero();
  for (std::size_t i = 0; i < points_.size(); ++i) {
    if (area_[i] > 0.0f && onPlane(plane, points_[i], bandM)) {
      const Vec3 d = points_[i] - mean;
      covariance += area_[i] * d * d.transpose();
    }
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3f> solver(covariance);
  if (solver.info() != Eigen::Success) return false;
  Vec3 n = solver.eigenvectors().col(0);  // the smallest eigenvalue's: the plane's normal
  if (!(n.squaredNorm() > 0.5f)) return false;
  n.normalize();
  float offset = n.dot(mean);
  faceCamera(n, offset);
  plane.normal = n;
  plane.offset = offset;
  return true;
}

bool SupportPlaneFinder::hypothesis(const DepthGrid& grid, SupportPlane& plane) {
  const auto count = static_cast<std::uint32_t>(points_.size());
  for (int attempt = 0; attempt < kSampleTries; ++attempt) {
    const std::uint32_t first = nextRandom(random_) % count;
    if (area_[first] <= 0.0f) continue;
    const int cell = cellOfPoint_[first];
    const int ci = cell % grid.width, cj = cell / grid.width;
    std::int32_t others[2] = {-1, -1};
    for (std::int32_t& other : others) {
      for (int t = 0; t < kSampleTries && other < 0; ++t) {
        const int span = 2 * kHypothesisCells + 1;
        const int i = ci + static_cast<int>(nextRandom(random_) % span) - kHypothesisCells;
        const int j = cj + static_cast<int>(nextRandom(random_) % span) - kHypothesisCells;
        if (i < 0 || j < 0 || i >= grid.width || j >= grid.height) continue;
        const std::int32_t p = pointOfCell_[static_cast<std::size_t>(j) * grid.width + i];
        if (p >= 0 && area_[static_cast<std::size_t>(p)] > 0.0f) other = p;
      }
    }
    if (others[0] < 0 || others[1] < 0) continue;
    const Vec3& a = points_[first];
    const Vec3 n = (points_[static_cast<std::size_t>(others[0])] - a)
                       .cross(points_[static_cast<std::size_t>(others[1])] - a);
    const float twiceArea = n.norm();
    if (twiceArea < 2.0f * kMinTriangleAreaM2) continue;
    plane.normal = n / twiceArea;
    plane.offset = plane.normal.dot(a);
    faceCamera(plane.normal, plane.offset);
    return true;
  }
  return false;
}

void SupportPlaneFinder::removeInliers(const SupportPlane& plane, float bandM) {
  for (std::size_t i = 0; i < points_.size(); ++i) {
    if (onPlane(plane, points_[i], bandM)) area_[i] = 0.0f;
  }
}

int SupportPlaneFinder::find(const DepthGrid& grid, const Intrinsics& k,
                             const SupportPlaneConfig& config, std::span<SupportPlane> out) {
  const int wanted = std::min(config.maxPlanes, static_cast<int>(out.size()));
  points_.clear();
  area_.clear();
  cellOfPoint_.clear();
  pointOfCell_.assign(static_cast<std::size_t>(grid.width) * grid.height, -1);
  const float cellArea = static_cast<float>(grid.step * grid.step) / (k.fx * k.fy);
  for (int j = 0; j < grid.height; ++j) {
    for (int i = 0; i < grid.width; ++i) {
      const std::size_t cell = static_cast<std::size_t>(j) * grid.width + i;
      const float z = grid.depth[cell];
      if (z <= 0.0f) continue;
      pointOfCell_[cell] = static_cast<std::int32_t>(points_.size());
      points_.push_back(grid.point(k, i, j));
      area_.push_back(z * z * cellArea);
      cellOfPoint_.push_back(static_cast<std::int32_t>(cell));
    }
  }
  int found = 0;
  random_ = kSeed;
  if (!config.enabled || points_.size() < 3) {
    previousCount_ = 0;
    return 0;
  }
  const std::size_t every = std::max<std::size_t>(1, points_.size() / kScoredSamples);
  for (; found < wanted; ++found) {
    SupportPlane best;
    best.areaM2 = -1.0f;  // none yet
    // Last frame's planes first: a table stays where it is.
    for (int p = 0; p < previousCount_; ++p) {
      SupportPlane c = previous_[static_cast<std::size_t>(p)];
      c.areaM2 = inlierArea(c, config.bandM, every);
      if (c.areaM2 > best.areaM2) best = c;
    }
    for (int h = 0; h < config.hypotheses; ++h) {
      SupportPlane c;
      if (!hypothesis(grid, c)) continue;
      c.areaM2 = inlierArea(c, config.bandM, every);
      if (c.areaM2 > best.areaM2) best = c;
    }
    // A plane too small on the subsample is too small: spare the full passes.
    if (best.areaM2 < 0.5f * config.minAreaM2 || !refit(best, config.bandM)) break;
    best.areaM2 = inlierArea(best, config.bandM, 1);
    if (best.areaM2 < config.minAreaM2) break;
    out[static_cast<std::size_t>(found)] = best;
    removeInliers(best, config.bandM);
  }
  previousCount_ = std::min(found, static_cast<int>(previous_.size()));
  for (int p = 0; p < previousCount_; ++p)
    previous_[static_cast<std::size_t>(p)] = out[static_cast<std::size_t>(p)];
  return found;
}

void removePlaneSamples(const SupportPlane& plane, float bandM, const Intrinsics& k, int originU,
                        int originV, int step, int width, int height, float* depth,
                        std::uint8_t* removed) {
  const float invFx = 1.0f / k.fx, invFy = 1.0f / k.fy;
  for (int j = 0; j < height; ++j) {
    const float y = (static_cast<float>(originV + j * step) - k.cy) * invFy;
    float* row = depth + static_cast<std::size_t>(j) * width;
    for (int i = 0; i < width; ++i) {
      const float z = row[i];
      if (z <= 0.0f) continue;
      const float x = (static_cast<float>(originU + i * step) - k.cx) * invFx;
      if (!onPlane(plane, Vec3(x * z, y * z, z), bandM)) continue;
      row[i] = 0.0f;
      if (removed != nullptr) removed[static_cast<std::size_t>(j) * width + i] = 1;
    }
  }
}

}  // namespace dynahand::cloud
