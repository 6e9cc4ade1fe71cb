#include "dynahand/hand_split.h"

#include <algorithm>
#include <cassert>
#include <cmath>

#include <Eigen/Eigenvalues>

namespace dynahand {

HandSplitter::HandSplitter(const HandSplitConfig& config) : config_(config) {
  assert(config.maxIterations > 0 && config.mergeDistanceM >= 0.0f &&
         config.apartDistanceM >= config.mergeDistanceM);
}

// Whether the two clusters (label[i] of points[i], centred at centre) are one limb cut in two:
// either cluster's longest axis (its points' principal direction) runs along the line between
// the centroids.
bool HandSplitter::oneLimb(std::span<const Vec3> points, std::span<const Hand> label,
                           const std::array<Vec3, 2>& centre) const {
  std::array<Eigen::Matrix3f, 2> scatter = {Eigen::Matrix3f::Zero(), Eigen::Matrix3f::Zero()};
  for (std::size_t i = 0; i < points.size(); ++i) {
    const std::size_t c = static_cast<std::size_t>(label[i]);
    const Vec3 d = points[i] - centre[c];
    scatter[c] += d * d.transpose();
  }
  const Vec3 between = (centre[1] - centre[0]).normalized();
  float along = 0.0f;
  for (const Eigen::Matrix3f& s : scatter) {
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3f> solver(s);
    along = std::max(along, std::abs(solver.eigenvectors().col(2).dot(between)));  // ascending
  }
  return along >= config_.maxAlongLimb;
}

void HandSplitter::cluster(std::span<const Vec3> points, std::array<Vec3, 2>& centre,
                           std::vector<Hand>& label, std::array<int, 2>& count) const {
  const std::size_t n = points.size();
  label.assign(n, Hand::kRight);
  for (int iteration = 0; iteration < config_.maxIterations; ++iteration) {
    bool changed = iteration == 0;
    std::array<Vec3, 2> sum = {Vec3::Zero(), Vec3::Zero()};
    count = {0, 0};
    for (std::size_t i = 0; i < n; ++i) {
      // Ties go to cluster 0, so the result never depends on evaluation order.
      const int c = (points[i] - centre[1]).squaredNorm() < (points[i] - centre[0]).squaredNorm();
      const Hand h = static_cast<Hand>(c);
      if (label[i] != h) changed = true;
      label[i] = h;
      sum[static_cast<std::size_t>(c)] += points[i];
      ++count[static_cast<std::size_t>(c)];
    }
    for (std::size_t c = 0; c < 2; ++c) {
      if (count[c] > 0) centre[c] = sum[c] / static_cast<float>(count[c]);
    }
    if (!changed || count[0] == 0 || count[1] == 0) break;
  }
}

void HandSplitter::split(std::span<const Vec3> points, HandSplit& out) {
  const std::size_t n = points.size();
  out.label.assign(n, Hand::kRight);
  out.hands = {};
  out.handCount = 0;
  if (n == 0) {
    hadTwoHands_ = false;
    return;
  }

  // k-means seeded at the two x-extreme points every frame; identity comes from matching the
  // clusters to last frame's below. Seeded from last frame's centroids instead, two hands side
  // by side that come close slide into a split across both arms (both forearms against both
  // hands, a smaller spread than one hand against the other) and keep it.
  std::size_t minIndex = 0;
  std::size_t maxIndex = 0;
  for (std::size_t i = 1; i < n; ++i) {
    if (points[i].x() < points[minIndex].x()) minIndex = i;
    if (points[i].x() > points[maxIndex].x()) maxIndex = i;
  }
  std::array<Vec3, 2> centre = {points[minIndex], points[maxIndex]};
  std::array<int, 2> count = {0, 0};
  cluster(points, centre, out.label, count);
  const bool tracking = hadTwoHands_;
  const float apart = (centre[0] - centre[1]).norm();
  const bool merge = count[0] < config_.minPointsPerHand || count[1] < config_.minPointsPerHand ||
                     apart < config_.mergeDistanceM ||
                     (apart < config_.apartDistanceM && oneLimb(points, out.label, centre));
  if (merge) {
    Vec3 sum = Vec3::Zero();
    for (const Vec3& p : points) sum += p;
    std::fill(out.label.begin(), out.label.end(), Hand::kRight);
    out.handCount = 1;
    HandCluster& right = out.hands[static_cast<std::size_t>(Hand::kRight)];
    right = {true, sum / static_cast<float>(n), static_cast<int>(n)};
    hadTwoHands_ = false;
    return;
  }

  // Cluster 0 is the left hand when it lies nearer to last frame's left hand (tracking);
  // otherwise label by image side.
  bool cluster0IsLeft = true;
  if (tracking) {
    cluster0IsLeft =
        (centre[0] - previousCentroid_[0]).norm() + (centre[1] - previousCentroid_[1]).norm() <=
        (centre[0] - previousCentroid_[1]).norm() + (centre[1] - previousCentroid_[0]).norm();
  } else {
    const bool cluster0HasLargerX = centre[0].x() > centre[1].x();
    cluster0IsLeft = (config_.placement == CameraPlacement::kFacingUser) == cluster0HasLargerX;
  }
  if (!cluster0IsLeft) {
    for (Hand& h : out.label) h = h == Hand::kLeft ? Hand::kRight : Hand::kLeft;
    std::swap(centre[0], centre[1]);
    std::swap(count[0], count[1]);
  }
  out.handCount = 2;
  for (std::size_t c = 0; c < 2; ++c) out.hands[c] = {true, centre[c], count[c]};
  previousCentroid_ = centre;
  hadTwoHands_ = true;
}

}  // namespace dynahand
