#include "dynahand/hand_size.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "track/worker_pool.h"

namespace dynahand::track {

namespace {

// The default hand's proportions (model::HandDimensions{}): the search scales them.
constexpr float kDefaultLength = 0.19f, kDefaultWidth = 0.085f;  // m

// Stage 1: uniform scale, coarse steps, then half steps beside the best.
constexpr std::array<float, 5> kCoarseScales = {0.80f, 0.90f, 1.00f, 1.10f, 1.20f};
constexpr float kHalfStep = 0.05f;
// Stages 2 and 3: relative steps of width alone, then length alone.
constexpr float kWidthStep = 0.07f;
constexpr float kLengthStep = 0.08f;

// How well one tracked frame's hand explains the data both ways, [0, 1].
float frameScore(const HandResult& hand) {
  if (!hand.tracked) return 0.0f;
  const float near = hand.quality.dataNearModel, onHand = hand.quality.modelOnHand;
  return near + onHand > 0.0f ? 2.0f * near * onHand / (near + onHand) : 0.0f;
}

class CandidateScorer {
 public:
  CandidateScorer(std::span<const DepthFrame> frames, const Intrinsics& intrinsics,
                  const std::optional<Keypoints21>& start, const HandSizeOptions& options)
      : frames_(frames),
        intrinsics_(intrinsics),
        start_(start),
        options_(options),
        pool_(options.threads) {
    options_.tracker.keepCandidates = false;
  }

  // The scores of the given sizes, tracked in parallel.
  std::vector<float> score(const std::vector<model::HandDimensions>& sizes) {
    std::vector<float> scores(sizes.size(), 0.0f);
    pool_.run(static_cast<int>(sizes.size()), [&](int i) {
      scores[static_cast<std::size_t>(i)] = scoreOne(sizes[static_cast<std::size_t>(i)]);
    });
    count_ += static_cast<int>(sizes.size());
    return scores;
  }
  int count() const { return count_; }

 private:
  float scoreOne(const model::HandDimensions& size) const {
    auto tracker = Tracker::create(model::makeDefaultHand(size), intrinsics_, options_.tracker);
    if (!tracker) return 0.0f;
    if (start_ && !(*tracker)->initializeFromKeypoints(*start_)) return 0.0f;
    double sum = 0.0;
    int scored = 0;
    for (std::size_t f = 0; f < frames_.size(); ++f) {
      const TrackResult& r = (*tracker)->track(frames_[f]);
      if (static_cast<int>(f) < options_.settleFrames) continue;
      float frame = 0.0f;
      for (const HandResult& h : r.hands) frame += frameScore(h);
      sum += static_cast<double>(frame) /
             static_cast<double>(std::max<std::size_t>(r.hands.size(), 1));
      ++scored;
    }
    return scored > 0 ? static_cast<float>(sum / scored) : 0.0f;
  }

  std::span<const DepthFrame> frames_;
  Intrinsics intrinsics_;
  std::optional<Keypoints21> start_;
  HandSizeOptions options_;
  WorkerPool pool_;
  int count_ = 0;
};

// The peak of the parabola through (x - h, below), (x, centre), (x + h, above), within
// [x - h, x + h]; x itself when the three are not concave.
float parabolaPeak(float x, float h, float below, float centre, float above) {
  const float curvature = below - 2.0f * centre + above;
  if (curvature >= 0.0f) return x;
  const float offset = 0.5f * h * (below - above) / curvature;
  return x + std::clamp(offset, -h, h);
}

// Index of the best score (the first on ties, for determinism).
std::size_t bestIndex(const std::vector<float>& scores) {
  return static_cast<std::size_t>(std::max_element(scores.begin(), scores.end()) - scores.begin());
}

struct SearchResult {
  float factor = 1.0f;  // the peak
  float score = 0.0f;   // the best score tracked
};

// Step 1: the factor f in sizeAt(f) with the best score: the coarse grid, the half steps
// beside its best, and the parabola through the best of those and its neighbours.
template <typename SizeAt>
SearchResult searchFactor(CandidateScorer& scorer, const SizeAt& sizeAt) {
  std::vector<float> factors(kCoarseScales.begin(), kCoarseScales.end());
  std::vector<model::HandDimensions> sizes;
  for (float f : factors) sizes.push_back(sizeAt(f));
  std::vector<float> scores = scorer.score(sizes);
  const float coarseBest = factors[bestIndex(scores)];
  const std::vector<float> half = {coarseBest - kHalfStep, coarseBest + kHalfStep};
  const std::vector<float> halfScores = scorer.score({sizeAt(half[0]), sizeAt(half[1])});
  for (std::size_t i = 0; i < half.size(); ++i) {
    factors.push_back(half[i]);
    scores.push_back(halfScores[i]);
  }
  const std::size_t best = bestIndex(scores);
  auto scoreAt = [&](float f) -> std::optional<float> {
    for (std::size_t i = 0; i < factors.size(); ++i)
      if (std::abs(factors[i] - f) < 1e-4f) return scores[i];
    return std::nullopt;  // past the grid's end
  };
  SearchResult r{factors[best], scores[best]};
  const auto below = scoreAt(r.factor - kHalfStep), above = scoreAt(r.factor + kHalfStep);
  if (below && above) r.factor = parabolaPeak(r.factor, kHalfStep, *below, r.score, *above);
  return r;
}

// Steps 2 and 3: the peak of sizeAt(1 - step), sizeAt(1), sizeAt(1 + step).
template <typename SizeAt>
SearchResult refineFactor(CandidateScorer& scorer, float step, const SizeAt& sizeAt) {
  const std::vector<float> s =
      scorer.score({sizeAt(1.0f - step), sizeAt(1.0f), sizeAt(1.0f + step)});
  return {parabolaPeak(1.0f, step, s[0], s[1], s[2]), *std::max_element(s.begin(), s.end())};
}

}  // namespace

Result<HandSizeEstimate> estimateHandSize(std::span<const DepthFrame> frames,
                                          const Intrinsics& intrinsics,
                                          const std::optional<Keypoints21>& start,
                                          const HandSizeOptions& options) {
  if (const std::string problem = intrinsics.problem(); !problem.empty())
    return Error{"hand size estimate: intrinsics: " + problem};
  if (static_cast<int>(frames.size()) <= options.settleFrames)
    return Error{"hand size estimate: " + std::to_string(frames.size()) +
                 " frames; needs more than " + std::to_string(options.settleFrames)};
  if (options.length && options.width)
    return Error{"hand size estimate: length and width both given, nothing to estimate"};
  CandidateScorer scorer(frames, intrinsics, start, options);
  HandSizeEstimate e;
  if (options.length) {  // the width alone, in the default proportion to start from
    const float length = *options.length, width = kDefaultWidth * length / kDefaultLength;
    const SearchResult r = searchFactor(scorer, [&](float f) {
      return model::HandDimensions{length, width * f};
    });
    e.dimensions = {length, width * r.factor};
    e.fitScore = r.score;
  } else if (options.width) {  // the length alone
    const float width = *options.width, length = kDefaultLength * width / kDefaultWidth;
    const SearchResult r = searchFactor(scorer, [&](float f) {
      return model::HandDimensions{length * f, width};
    });
    e.dimensions = {length * r.factor, width};
    e.fitScore = r.score;
  } else {
    // 1. Uniform scale of the default proportions.
    const SearchResult scale = searchFactor(scorer, [](float f) {
      return model::HandDimensions{kDefaultLength * f, kDefaultWidth * f};
    });
    const float length = kDefaultLength * scale.factor;
    const float width = kDefaultWidth * scale.factor;
    // 2. Width alone at that length.
    const SearchResult w = refineFactor(scorer, kWidthStep, [&](float f) {
      return model::HandDimensions{length, width * f};
    });
    // 3. Length alone at that width.
    const SearchResult l = refineFactor(scorer, kLengthStep, [&](float f) {
      return model::HandDimensions{length * f, width * w.factor};
    });
    e.dimensions = {length * l.factor, width * w.factor};
    e.fitScore = std::max({scale.score, w.score, l.score});
  }
  e.framesUsed = static_cast<int>(frames.size());
  e.candidates = scorer.count();
  return e;
}

}  // namespace dynahand::track
