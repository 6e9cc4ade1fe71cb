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

// Whether the hand's fingers are out straight: at least three of index..pinky reach 90 % of
// their length from MCP to tip. Only then does the data show how long they are: a too-long
// model finger curls into a fist as well as the right one (it even scores a little better,
// the rendered fist being bulkier than the model's), which drew the length estimate up.
bool fingersOpen(const HandResult& hand) {
  if (!hand.tracked) return false;
  constexpr float kStraight = 0.9f;
  int straight = 0;
  for (std::size_t mcp : {5u, 9u, 13u, 17u}) {
    const auto& k = hand.skeletonKeypoints21;
    const float along = (k[mcp + 1] - k[mcp]).norm() + (k[mcp + 2] - k[mcp + 1]).norm() +
                        (k[mcp + 3] - k[mcp + 2]).norm();
    if ((k[mcp + 3] - k[mcp]).norm() >= kStraight * along) ++straight;
  }
  return straight >= 3;
}

// One candidate's frames: score and whether its first hand had its fingers open.
struct CandidateFrames {
  std::vector<float> scores;
  std::vector<char> open;
};

// Mean score over the frames `use` marks (all when empty); frames while settling left out.
float meanScore(const CandidateFrames& c, int settleFrames, const std::vector<char>& use = {}) {
  double sum = 0.0;
  int count = 0;
  for (std::size_t f = static_cast<std::size_t>(settleFrames); f < c.scores.size(); ++f) {
    if (!use.empty() && use[f] == 0) continue;
    sum += static_cast<double>(c.scores[f]);
    ++count;
  }
  return count > 0 ? static_cast<float>(sum / count) : 0.0f;
}

class CandidateScorer {
 public:
  CandidateScorer(std::span<const DepthFrame> frames, const Intrinsics& intrinsics,
                  const std::optional<Keypoints21>& start, const HandSizeOptions& options)
      : frames_(frames),
        intrinsics_(intrinsics),
        start_(start),
        options_(options),
        pool_(options.threads),
        settleFrames_(start ? 0 : options.acquisitionFrames) {
    options_.tracker.keepCandidates = false;
    // Every candidate scored on the same segmented points, whatever its length.
    options_.tracker.scaleSegmentationToHand = false;
  }

  // The given sizes, tracked in parallel.
  std::vector<CandidateFrames> track(const std::vector<model::HandDimensions>& sizes) {
    std::vector<CandidateFrames> tracked(sizes.size());
    pool_.run(static_cast<int>(sizes.size()), [&](int i) {
      tracked[static_cast<std::size_t>(i)] = trackOne(sizes[static_cast<std::size_t>(i)]);
    });
    count_ += static_cast<int>(sizes.size());
    return tracked;
  }
  // Their mean scores over all frames.
  std::vector<float> score(const std::vector<model::HandDimensions>& sizes) {
    std::vector<float> scores;
    for (const CandidateFrames& c : track(sizes)) scores.push_back(meanScore(c, settleFrames()));
    return scores;
  }
  int count() const { return count_; }
  // Frames left out of the scores at the start.
  int settleFrames() const { return settleFrames_; }

 private:
  CandidateFrames trackOne(const model::HandDimensions& size) const {
    CandidateFrames c;
    c.scores.assign(frames_.size(), 0.0f);
    c.open.assign(frames_.size(), 0);
    // The candidates are scored on how well the paper's simulations alone fit each size: the
    // detector-fit simulation would fit a wrong-sized hand to its keypoints as readily.
    TrackerSettings settings = options_.tracker;
    settings.detector.enabled = false;
    auto tracker = Tracker::create(model::makeDefaultHand(size), intrinsics_, settings);
    if (!tracker) return c;
    if (start_ && !(*tracker)->initializeFromKeypoints(*start_)) return c;
    for (std::size_t f = 0; f < frames_.size(); ++f) {
      const TrackResult& r = (*tracker)->track(frames_[f]);
      float sum = 0.0f;
      for (const HandResult& h : r.hands) sum += frameScore(h);
      c.scores[f] = r.hands.empty() ? 0.0f : sum / static_cast<float>(r.hands.size());
      c.open[f] = !r.hands.empty() && fingersOpen(r.hands.front()) ? 1 : 0;
    }
    return c;
  }

  std::span<const DepthFrame> frames_;
  Intrinsics intrinsics_;
  std::optional<Keypoints21> start_;
  HandSizeOptions options_;
  WorkerPool pool_;
  int settleFrames_ = 0;
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

// Steps 2 and 3: the peak of sizeAt(1 - step), sizeAt(1), sizeAt(1 + step). openOnly: scored
// over the frames where the middle candidate's fingers are open (if at least kMinOpenFrames).
constexpr int kMinOpenFrames = 3;
template <typename SizeAt>
SearchResult refineFactor(CandidateScorer& scorer, float step, bool openOnly,
                          const SizeAt& sizeAt) {
  const std::vector<CandidateFrames> c =
      scorer.track({sizeAt(1.0f - step), sizeAt(1.0f), sizeAt(1.0f + step)});
  std::vector<char> use;
  if (openOnly) {
    use = c[1].open;
    const int open = static_cast<int>(
        std::count(use.begin() + std::min<std::ptrdiff_t>(scorer.settleFrames(),
                                                          static_cast<std::ptrdiff_t>(use.size())),
                   use.end(), 1));
    if (open < kMinOpenFrames) use.clear();
  }
  std::array<float, 3> s{}, all{};
  for (std::size_t i = 0; i < 3; ++i) {
    s[i] = meanScore(c[i], scorer.settleFrames(), use);
    all[i] = meanScore(c[i], scorer.settleFrames());
  }
  return {parabolaPeak(1.0f, step, s[0], s[1], s[2]), *std::max_element(all.begin(), all.end())};
}

}  // namespace

Result<HandSizeEstimate> estimateHandSize(std::span<const DepthFrame> frames,
                                          const Intrinsics& intrinsics,
                                          const std::optional<Keypoints21>& start,
                                          const HandSizeOptions& options) {
  if (const std::string problem = intrinsics.problem(); !problem.empty())
    return Error{"hand size estimate: intrinsics: " + problem};
  const int leftOut = start ? 0 : options.acquisitionFrames;
  if (static_cast<int>(frames.size()) <= leftOut || frames.empty())
    return Error{"hand size estimate: " + std::to_string(frames.size()) +
                 " frames; needs more than " + std::to_string(leftOut) +
                 (start ? "" : " (the frames a candidate may take to acquire the hand)")};
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
    const SearchResult w = refineFactor(scorer, kWidthStep, false, [&](float f) {
      return model::HandDimensions{length, width * f};
    });
    // 3. Length alone at that width, judged where the fingers are open.
    const SearchResult l = refineFactor(scorer, kLengthStep, true, [&](float f) {
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
