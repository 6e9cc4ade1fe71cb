#include <algorithm>
#include <cmath>
#include <limits>

#include "dynahand/metrics.h"

namespace dynahand::eval {

const std::array<const char*, 21> kKeypointNames = {
    "wrist",     "thumb_cmc", "thumb_mcp",  "thumb_ip",   "thumb_tip",  "index_mcp",  "index_pip",
    "index_dip", "index_tip", "middle_mcp", "middle_pip", "middle_dip", "middle_tip", "ring_mcp",
    "ring_pip",  "ring_dip",  "ring_tip",   "pinky_mcp",  "pinky_pip",  "pinky_dip",  "pinky_tip"};

namespace {

constexpr double kMmPerM = 1000.0;

// Linear-interpolated percentile of sorted values, q in [0, 1].
double sortedPercentile(const std::vector<double>& sorted, double q) {
  if (sorted.empty()) return 0.0;
  const double pos = q * static_cast<double>(sorted.size() - 1);
  const auto lo = static_cast<std::size_t>(std::floor(pos));
  const std::size_t hi = std::min(lo + 1, sorted.size() - 1);
  const double t = pos - static_cast<double>(lo);
  return sorted[lo] * (1.0 - t) + sorted[hi] * t;
}

bool allFinite(const Keypoints21& k) {
  for (const Vec3& p : k) {
    if (!p.allFinite()) return false;
  }
  return true;
}

}  // namespace

double percentile(std::vector<double> values, double q) {
  std::sort(values.begin(), values.end());
  return sortedPercentile(values, q);
}

Result<KeypointMetrics> computeKeypointMetrics(const SequenceKeypoints& s,
                                               const MetricsOptions& options) {
  if (s.groundTruth.size() != s.predicted.size()) {
    return Error{"ground truth has " + std::to_string(s.groundTruth.size()) +
                 " frames but the prediction has " + std::to_string(s.predicted.size())};
  }
  if (!(s.fps > 0.0)) return Error{"frames per second must be positive"};
  if (!s.scored.empty() && s.scored.size() != s.groundTruth.size()) {
    return Error{"the scored-joint mask has " + std::to_string(s.scored.size()) +
                 " frames but the ground truth has " + std::to_string(s.groundTruth.size())};
  }
  const std::size_t n = s.groundTruth.size();
  KeypointMetrics m;
  m.frames = static_cast<int>(n);
  m.perFrameMeanMm.assign(n, std::numeric_limits<double>::quiet_NaN());
  m.perFrameMaxMm.assign(n, std::numeric_limits<double>::quiet_NaN());
  m.successThresholdsMm = options.successThresholdsMm;
  m.successFraction.assign(options.successThresholdsMm.size(), 0.0);

  std::vector<double> all;
  all.reserve(n * 21);
  std::array<double, 21> jointSum{};
  std::array<int, 21> jointCount{};
  std::vector<int> successCount(options.successThresholdsMm.size(), 0);
  std::vector<bool> lost(n, false);
  double jitterSum = 0;
  long jitterCount = 0;

  for (std::size_t f = 0; f < n; ++f) {
    const auto& gt = s.groundTruth[f];
    const auto& pr = s.predicted[f];
    if (gt && !allFinite(*gt))
      return Error{"ground truth frame " + std::to_string(f) + " is not finite"};
    if (pr && !allFinite(*pr))
      return Error{"predicted frame " + std::to_string(f) + " is not finite"};
    if (!gt) continue;
    ++m.visibleFrames;
    if (!pr) {
      lost[f] = true;
      continue;
    }
    ++m.evaluatedFrames;
    double sum = 0, worst = 0;
    int scored = 0;
    for (int j = 0; j < 21; ++j) {
      if (!s.scored.empty() && !s.scored[f][static_cast<std::size_t>(j)]) continue;
      const double e = static_cast<double>(((*pr)[j] - (*gt)[j]).norm()) * kMmPerM;
      all.push_back(e);
      jointSum[j] += e;
      ++jointCount[j];
      sum += e;
      worst = std::max(worst, e);
      ++scored;
    }
    m.perFrameMeanMm[f] = scored > 0 ? sum / scored : 0.0;
    m.perFrameMaxMm[f] = worst;
    for (std::size_t t = 0; t < successCount.size(); ++t) {
      if (worst <= options.successThresholdsMm[t]) ++successCount[t];
    }
    lost[f] = worst > options.lostThresholdMm;
    if (f > 0 && s.groundTruth[f - 1] && s.predicted[f - 1]) {
      for (int j = 0; j < 21; ++j) {
        const Vec3 dPred = (*pr)[j] - (*s.predicted[f - 1])[j];
        const Vec3 dTrue = (*gt)[j] - (*s.groundTruth[f - 1])[j];
        jitterSum += static_cast<double>((dPred - dTrue).norm()) * kMmPerM;
        ++jitterCount;
      }
    }
  }

  if (!all.empty()) {
    std::vector<double> sorted = all;
    std::sort(sorted.begin(), sorted.end());
    double total = 0;
    for (double e : all) total += e;
    m.meanMm = total / static_cast<double>(all.size());
    m.medianMm = sortedPercentile(sorted, 0.5);
    m.p95Mm = sortedPercentile(sorted, 0.95);
    m.maxMm = sorted.back();
    for (int j = 0; j < 21; ++j)
      m.perJointMeanMm[j] = jointCount[j] > 0 ? jointSum[j] / jointCount[j] : 0.0;
  }
  for (std::size_t t = 0; t < successCount.size(); ++t) {
    m.successFraction[t] =
        m.visibleFrames > 0 ? static_cast<double>(successCount[t]) / m.visibleFrames : 0.0;
  }
  m.jitterMm = jitterCount > 0 ? jitterSum / static_cast<double>(jitterCount) : 0.0;

  // Lost episodes: maximal runs of lost visible frames (frames without ground truth
  // neither start nor end a run: the hand was out of view, nothing to track).
  double recoverySum = 0;
  int recovered = 0;
  std::size_t f = 0;
  while (f < n) {
    if (!lost[f]) {
      ++f;
      continue;
    }
    const std::size_t start = f;
    int length = 0;
    while (f < n && (lost[f] || !s.groundTruth[f])) {
      if (lost[f]) ++length;
      ++f;
    }
    m.lostFrames += length;
    ++m.lostEpisodes;
    if (f < n) {
      const double seconds = static_cast<double>(f - start) / s.fps;
      recoverySum += seconds;
      m.maxRecoverySeconds = std::max(m.maxRecoverySeconds, seconds);
      ++recovered;
    } else {
      ++m.unrecoveredEpisodes;
    }
  }
  m.meanRecoverySeconds = recovered > 0 ? recoverySum / recovered : 0.0;
  return m;
}

}  // namespace dynahand::eval
