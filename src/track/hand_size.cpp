#include "dynahand/hand_size.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "dynahand/model_pose.h"
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
// Stage 4: each digit's metacarpal length factor, a coarse then a fine step about the
// estimate so far; the result keeps this share of its offset from 1: the scores differ by
// little more than their noise, and the whole offset makes more hands track worse than the
// default shape does (docs/tracker.md, "Hand size").
constexpr std::array<float, 2> kMetacarpalSteps = {0.10f, 0.05f};
constexpr float kMetacarpalShrink = 0.5f;
// Stage 4 scores only frames where the palm faces the camera: the cosine between the back of
// the hand's normal and the line of sight to the middle knuckle is at least this. From behind
// (a head-mounted camera) the error metric prefers long metacarpals whatever the hand.
constexpr float kPalmFacingCosine = 0.3f;
constexpr int kMinPalmFacingFrames = 8;  // fewer: the shape stays the default
// Seen from behind as well (the detector's palm faces the camera in fewer than
// kMinPalmFacingFrames frames), the error metric says little of the size: a hand's back
// explains the data at any size near the truth, and the estimate ran 6-11 % long from a
// head-mounted camera (each dimension alone with the other given: -19..+21 %). The size is then
// the default proportions scaled to the palm the learned detector sees (the median over the
// frames of its mean wrist-to-knuckle length), within this range, when it ran on at least
// kMinDetectedFrames frames; with a length or a width given, the other in the default
// proportion to it.
constexpr std::array<float, 2> kDetectedScaleRange = {0.75f, 1.25f};
constexpr int kMinDetectedFrames = 8;

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

// One candidate's frames: score and whether its first hand had its fingers open; for stage
// 4, its first hand's keypoints where tracked, and (restarted candidates) the paper's error,
// negative where the hand was not tracked.
struct CandidateFrames {
  std::vector<float> scores;
  std::vector<char> open;
  std::vector<std::optional<Keypoints21>> keypoints;
  std::vector<float> errors;
};

// A candidate model: the default hand at a size, with a shape.
struct CandidateHand {
  model::HandDimensions size;
  model::HandShape shape;
};

// Whether the palm of a right hand with these keypoints faces the camera (kPalmFacingCosine).
bool palmFacesCamera(const Keypoints21& k) {
  const Vec3 distal = (k[9] - k[0]).normalized();
  const Vec3 radial = (k[5] - k[17]).normalized();
  const Vec3 dorsal = distal.cross(radial).normalized();  // model frame: y = z x x
  return dorsal.dot(k[9].normalized()) >= kPalmFacingCosine;
}

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

// Where the candidates start: from these keypoints at this frame (the frames before it are not
// tracked or scored), or each acquiring the hand by itself from frame 0.
struct CandidateStart {
  std::optional<Keypoints21> keypoints;
  int frame = 0;
};

// Mean distance from the wrist to the four finger knuckles, m: the palm's length.
float palmLength(const Keypoints21& k) {
  float sum = 0.0f;
  for (std::size_t knuckle : {5u, 9u, 13u, 17u}) sum += (k[knuckle] - k[0]).norm();
  return 0.25f * sum;
}

// The hand as the tracker with the learned detector sees it over the frames (one default-size
// hand, started from the given keypoints, else acquiring).
struct DetectedHand {
  // Without start keypoints, where the candidates start: the keypoints it reports on the first
  // frame, within the first `withinFrames`, where it has the hand with a detection in use. The
  // candidates' own acquisition has no detector (their scores must come from the paper's
  // simulations alone) and so finds only an open hand facing the camera; from any other start
  // each candidate takes the hand its own way, and the sizes come out 15-23 % off
  // (HandSize.EstimatesWithoutStartKeypointsOnCapturedMotion).
  CandidateStart start;
  std::vector<float> palmLengths;  // the detector's palmLength, m, on every frame it ran
  int palmFacingFrames = 0;        // of those, frames whose detected palm faces the camera
};

// palm: also over every frame for the palm (else only until the start is found).
DetectedHand detectHand(std::span<const DepthFrame> frames, const Intrinsics& intrinsics,
                        const TrackerSettings& settings, const model::HandDimensions& size,
                        const std::optional<Keypoints21>& start, int withinFrames, bool palm) {
  DetectedHand d;
  if (!settings.detector.enabled || (start && !palm)) return d;
  TrackerSettings s = settings;
  s.keepCandidates = false;
  auto tracker = Tracker::create(model::makeDefaultHand(size), intrinsics, s);
  // Without weights the tracker runs without the detector: nothing to find.
  if (!tracker || !(*tracker)->settings().detector.enabled) return d;
  if (start && !(*tracker)->initializeFromKeypoints(*start)) return d;
  const std::size_t count =
      palm ? frames.size() : std::min(frames.size(), static_cast<std::size_t>(withinFrames));
  for (std::size_t f = 0; f < count; ++f) {
    const TrackResult& r = (*tracker)->track(frames[f]);
    if (r.hands.empty()) continue;
    const HandResult& h = r.hands.front();
    if (!start && !d.start.keypoints && h.tracked && h.detected &&
        static_cast<int>(f) < withinFrames)
      d.start = {h.keypoints21, static_cast<int>(f)};
    if (!palm && d.start.keypoints) break;
    if (!h.detected) continue;
    d.palmLengths.push_back(palmLength(h.detectorKeypoints21));
    if (palmFacesCamera(h.detectorKeypoints21)) ++d.palmFacingFrames;
  }
  return d;
}

// The scale of the default hand whose palm is as long as the median detected one.
float detectedScale(std::vector<float> palmLengths) {
  std::sort(palmLengths.begin(), palmLengths.end());
  const std::size_t n = palmLengths.size();
  const float median =
      n % 2 == 1 ? palmLengths[n / 2] : 0.5f * (palmLengths[n / 2 - 1] + palmLengths[n / 2]);
  const model::ArticulatedModel hand = model::makeDefaultHand();
  const float model =
      palmLength(model::keypoints21(hand, model::forwardKinematics(hand, model::zeroAngles(hand))));
  return std::clamp(median / model, kDetectedScaleRange[0], kDetectedScaleRange[1]);
}

class CandidateScorer {
 public:
  CandidateScorer(std::span<const DepthFrame> frames, const Intrinsics& intrinsics,
                  const CandidateStart& start, const HandSizeOptions& options)
      : frames_(frames),
        intrinsics_(intrinsics),
        start_(start),
        options_(options),
        pool_(options.threads),
        settleFrames_(start.keypoints ? start.frame : options.acquisitionFrames) {
    options_.tracker.keepCandidates = false;
    // Every candidate scored on the same segmented points, whatever its length.
    options_.tracker.scaleSegmentationToHand = false;
  }

  // The given sizes (default shape), tracked in parallel.
  std::vector<CandidateFrames> track(const std::vector<model::HandDimensions>& sizes) {
    std::vector<CandidateHand> hands;
    for (const model::HandDimensions& size : sizes) hands.push_back({size, {}});
    return run(hands, [this](const CandidateHand& hand) { return trackOne(hand); });
  }
  CandidateFrames track(const CandidateHand& hand) {
    return run({hand}, [this](const CandidateHand& h) { return trackOne(h); }).front();
  }
  // The given hands, each started afresh on every frame from the reference's keypoints of
  // that frame (where it has them) and tracked over that frame alone, in parallel.
  std::vector<CandidateFrames> restart(const std::vector<CandidateHand>& hands,
                                       const std::vector<std::optional<Keypoints21>>& reference) {
    return run(hands, [&](const CandidateHand& hand) { return restartOne(hand, reference); });
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
  template <typename TrackHand>
  std::vector<CandidateFrames> run(const std::vector<CandidateHand>& hands,
                                   const TrackHand& trackHand) {
    std::vector<CandidateFrames> tracked(hands.size());
    pool_.run(static_cast<int>(hands.size()), [&](int i) {
      tracked[static_cast<std::size_t>(i)] = trackHand(hands[static_cast<std::size_t>(i)]);
    });
    count_ += static_cast<int>(hands.size());
    return tracked;
  }

  CandidateFrames emptyFrames() const {
    CandidateFrames c;
    c.scores.assign(frames_.size(), 0.0f);
    c.open.assign(frames_.size(), 0);
    c.keypoints.assign(frames_.size(), std::nullopt);
    c.errors.assign(frames_.size(), -1.0f);
    return c;
  }

  // The candidates are scored on how well the paper's simulations alone fit each hand: the
  // detector-fit simulation would fit a wrong-sized hand to its keypoints as readily.
  Result<std::unique_ptr<Tracker>> makeTracker(const CandidateHand& hand) const {
    TrackerSettings settings = options_.tracker;
    settings.detector.enabled = false;
    return Tracker::create(model::makeDefaultHand(hand.size, model::Side::Right, hand.shape),
                           intrinsics_, settings);
  }

  CandidateFrames trackOne(const CandidateHand& hand) const {
    CandidateFrames c = emptyFrames();
    auto tracker = makeTracker(hand);
    if (!tracker) return c;
    const auto first = static_cast<std::size_t>(start_.frame);
    if (start_.keypoints && !(*tracker)->initializeFromKeypoints(*start_.keypoints)) return c;
    for (std::size_t f = first; f < frames_.size(); ++f) {
      const TrackResult& r = (*tracker)->track(frames_[f]);
      float sum = 0.0f;
      for (const HandResult& h : r.hands) sum += frameScore(h);
      c.scores[f] = r.hands.empty() ? 0.0f : sum / static_cast<float>(r.hands.size());
      c.open[f] = !r.hands.empty() && fingersOpen(r.hands.front()) ? 1 : 0;
      if (!r.hands.empty() && r.hands.front().tracked)
        c.keypoints[f] = r.hands.front().skeletonKeypoints21;
    }
    return c;
  }

  // One frame at a time from the reference: what each candidate makes of a frame from the
  // same start, free of how a whole run drifts (runs of candidates a few percent apart part
  // ways by chance, and their scores with them).
  CandidateFrames restartOne(const CandidateHand& hand,
                             const std::vector<std::optional<Keypoints21>>& reference) const {
    CandidateFrames c = emptyFrames();
    auto tracker = makeTracker(hand);
    if (!tracker) return c;
    for (std::size_t f = 0; f < frames_.size(); ++f) {
      if (!reference[f] || !(*tracker)->initializeFromKeypoints(*reference[f])) continue;
      const TrackResult& r = (*tracker)->track(frames_[f]);
      if (!r.hands.empty() && r.hands.front().tracked) c.errors[f] = r.hands.front().error;
    }
    return c;
  }

  std::span<const DepthFrame> frames_;
  Intrinsics intrinsics_;
  CandidateStart start_;
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

// Stage 4: each digit's metacarpal length factor (bone 0: where its knuckle, or the thumb's
// base, sits on the palm), at `size`. Each step tracks the estimate so far as the reference,
// then restarts it and, for each digit, the digit's factor one step either way on every frame
// where the reference's palm faces the camera, and takes the peak of the parabola through each
// digit's three mean errors (the better end when they are not concave).
model::HandShape estimateMetacarpals(CandidateScorer& scorer, const model::HandDimensions& size) {
  model::HandShape shape;
  for (const float step : kMetacarpalSteps) {
    std::vector<std::optional<Keypoints21>> reference = scorer.track({size, shape}).keypoints;
    int facing = 0;
    for (std::size_t f = 0; f < reference.size(); ++f) {
      const bool settling = static_cast<int>(f) < scorer.settleFrames();
      if (reference[f] && (settling || !palmFacesCamera(*reference[f]))) reference[f].reset();
      if (reference[f]) ++facing;
    }
    if (facing < kMinPalmFacingFrames) break;
    std::vector<CandidateHand> hands = {{size, shape}};
    for (std::size_t d = 0; d < 5; ++d)
      for (const float offset : {-step, step}) {
        hands.push_back({size, shape});
        hands.back().shape.boneLength[d][0] += offset;
      }
    const std::vector<CandidateFrames> tracked = scorer.restart(hands, reference);
    // Mean error over the frames every candidate tracked.
    std::vector<double> sums(hands.size(), 0.0);
    for (std::size_t f = 0; f < reference.size(); ++f) {
      bool all = true;
      for (const CandidateFrames& c : tracked) all = all && c.errors[f] >= 0.0f;
      if (!all) continue;
      for (std::size_t i = 0; i < tracked.size(); ++i)
        sums[i] += static_cast<double>(tracked[i].errors[f]);
    }
    // Scores: higher is better.
    const auto score = [&sums](std::size_t i) { return -static_cast<float>(sums[i]); };
    model::HandShape next = shape;
    for (std::size_t d = 0; d < 5; ++d) {
      const float below = score(1 + 2 * d), centre = score(0), above = score(2 + 2 * d);
      float offset = parabolaPeak(0.0f, step, below, centre, above);
      if (below - 2.0f * centre + above >= 0.0f) {
        const float best = std::max({below, centre, above});
        offset = best == centre ? 0.0f : best == below ? -step : step;
      }
      next.boneLength[d][0] += offset;
    }
    shape = next;
  }
  for (auto& digit : shape.boneLength) digit[0] = 1.0f + kMetacarpalShrink * (digit[0] - 1.0f);
  return shape;
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
  if (options.length && options.width && !options.metacarpals)
    return Error{
        "hand size estimate: length and width both given and the metacarpals not asked for, "
        "nothing to estimate"};
  // What is given of the hand, the rest in the default proportion: the hand the detected start
  // is found with, and where the one-dimension searches start.
  model::HandDimensions given{kDefaultLength, kDefaultWidth};
  if (options.length && options.width) {
    given = {*options.length, *options.width};
  } else if (options.length) {
    given = {*options.length, kDefaultWidth * *options.length / kDefaultLength};
  } else if (options.width) {
    given = {kDefaultLength * *options.width / kDefaultWidth, *options.width};
  }
  const bool anyGiven = options.length || options.width;
  const bool sizeWanted = !options.length || !options.width;
  const DetectedHand detected =
      detectHand(frames, intrinsics, options.tracker, given, start, leftOut, sizeWanted);
  const CandidateStart from = start ? CandidateStart{start, 0} : detected.start;
  CandidateScorer scorer(frames, intrinsics, from, options);
  const bool fromBehind = static_cast<int>(detected.palmLengths.size()) >= kMinDetectedFrames &&
                          detected.palmFacingFrames < kMinPalmFacingFrames;
  HandSizeEstimate e;
  if (!sizeWanted || fromBehind) {
    // Not searched: the size known (the metacarpals alone), or seen from behind, where the
    // searches below are far off: a given dimension with the other in the default proportion
    // to it, else the detected palm's scale.
    if (anyGiven) {
      e.dimensions = given;
    } else {
      const float scale = detectedScale(detected.palmLengths);
      e.dimensions = {kDefaultLength * scale, kDefaultWidth * scale};
    }
    e.fitScore = scorer.score({e.dimensions}).front();
  } else if (options.length) {  // the width alone, from the default proportion
    const SearchResult r = searchFactor(scorer, [&](float f) {
      return model::HandDimensions{given.length, given.width * f};
    });
    e.dimensions = {given.length, given.width * r.factor};
    e.fitScore = r.score;
  } else if (options.width) {  // the length alone
    const SearchResult r = searchFactor(scorer, [&](float f) {
      return model::HandDimensions{given.length * f, given.width};
    });
    e.dimensions = {given.length * r.factor, given.width};
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
  // 4. Each digit's metacarpal at that size.
  if (options.metacarpals) e.shape = estimateMetacarpals(scorer, e.dimensions);
  e.framesUsed = static_cast<int>(frames.size());
  e.candidates = scorer.count();
  return e;
}

}  // namespace dynahand::track
