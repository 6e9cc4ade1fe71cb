#include "dynahand/hand_split.h"

#include <cassert>

namespace dynahand {

HandSplitter::HandSplitter(const HandSplitConfig& config) : config_(config) {
  assert(config.maxIterations > 0 && config.mergeDistanceM >= 0.0f);
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

  // Seeds: last frame's hands (identity kept), else the two x-extreme points.
  std::array<Vec3, 2> centre;
  const bool tracking = hadTwoHands_;
  if (tracking) {
    centre = previousCentroid_;
  } else {
    std::size_t minIndex = 0;
    std::size_t maxIndex = 0;
    for (std::size_t i = 1; i < n; ++i) {
      if (points[i].x() < points[minIndex].x()) minIndex = i;
      if (points[i].x() > points[maxIndex].x()) maxIndex = i;
    }
    centre = {points[minIndex], points[maxIndex]};
  }

  // Lloyd iterations. out.label doubles as the assignment (kLeft = cluster 0).
  std::array<int, 2> count = {0, 0};
  for (int iteration = 0; iteration < config_.maxIterations; ++iteration) {
    bool changed = iteration == 0;
    std::array<Vec3, 2> sum = {Vec3::Zero(), Vec3::Zero()};
    count = {0, 0};
    for (std::size_t i = 0; i < n; ++i) {
      // Ties go to cluster 0, so the result never depends on evaluation order.
      const int c = (points[i] - centre[1]).squaredNorm() < (points[i] - centre[0]).squaredNorm();
      const Hand h = static_cast<Hand>(c);
      if (out.label[i] != h) changed = true;
      out.label[i] = h;
      sum[static_cast<std::size_t>(c)] += points[i];
      ++count[static_cast<std::size_t>(c)];
    }
    for (std::size_t c = 0; c < 2; ++c) {
      if (count[c] > 0) centre[c] = sum[c] / static_cast<float>(count[c]);
    }
    if (!changed || count[0] == 0 || count[1] == 0) break;
  }

  const bool merge = count[0] < config_.minPointsPerHand || count[1] < config_.minPointsPerHand ||
                     (centre[0] - centre[1]).norm() < config_.mergeDistanceM;
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

  // Cluster 0 is the left hand when tracking; otherwise label by image side.
  bool cluster0IsLeft = true;
  if (!tracking) {
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
