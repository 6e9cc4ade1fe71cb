#include "track/hand_tracker.h"

#include "track/fit_quality.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>

namespace dynahand::track {

namespace {

constexpr int kMinPoints = 20;  // fewer sample points: no hand in view
// A detected keypoint, bound to its body, pulls like this many samples (times its
// confidence).
constexpr float kDetectorLabelCap = 8.0f;
constexpr std::size_t kMinFitKeypoints = 8;  // fewer confident keypoints: no fitted pose
// A joint may lie this far (m) behind the visible surface: the fingers of a fist seen from
// behind lie up to about a fist's depth behind the back of the hand.
constexpr float kHiddenDepthM = 0.07f;
constexpr float kOffHandTipPenaltyM = 0.05f;  // acquisition: per fingertip over background
// A frame that starts within this mean distance (m) of the detector's keypoints fits them from
// its own joint angles, in at most kWarmFitIterations: it is in the right basin already, and
// a fit from scratch costs ~10x more. Farther (a flipped or lost hand) the fit starts afresh.
constexpr float kWarmFitDistanceM = 0.03f;
constexpr int kWarmFitIterations = 8;
constexpr float kForearmReachM = 0.15f;  // the forearm kept beyond the detected wrist, m

// The hand's own world (acquisition steps it); the simulations' copies take the tracking
// sweeps (HandTracker's constructor).
physics::WorldSettings worldSettings(const TrackerSettings& s) {
  physics::WorldSettings w;
  w.iterations = s.acquisitionIterations;
  w.relaxIterations = s.acquisitionRelaxIterations;
  w.surfaceErp = s.surfaceErp;
  return w;
}

SimulationSettings simulationSettings(const TrackerSettings& s) {
  SimulationSettings sim;
  sim.substeps = s.substeps;
  sim.pointSubsets = s.pointSubsets;
  sim.stepDt = s.stepDt;
  sim.pullForce = s.pullForce;
  sim.boundaryForce = s.boundaryForce;
  sim.boundaryBand = s.boundaryBand;
  sim.silhouetteForce = s.silhouetteForce;
  return sim;
}

}  // namespace

Result<std::unique_ptr<HandTracker>> HandTracker::create(const model::ArticulatedModel& model,
                                                         model::Side side,
                                                         const TrackerSettings& settings,
                                                         WorkerPool* pool) {
  RigSettings rigSettings;
  rigSettings.velocityRetention = settings.velocityRetention;
  auto rig = HandRig::create(model, worldSettings(settings), rigSettings, settings.stepDt);
  if (!rig) return rig.error();
  return std::unique_ptr<HandTracker>(
      new HandTracker(model, side, settings, std::move(*rig), pool));
}

HandTracker::HandTracker(const model::ArticulatedModel& model, model::Side side,
                         const TrackerSettings& settings, HandRig rig, WorkerPool* pool)
    : model_(&model),
      side_(side),
      settings_(settings),
      rig_(std::move(rig)),
      simulator_(simulationSettings(settings)),
      acquisitionSimulator_([&settings] {
        SimulationSettings every = simulationSettings(settings);
        every.pointSubsets = 1;
        every.pullForce = settings.acquisitionPullForce;
        return every;
      }()),
      pool_(pool),
      fitter_(model) {
  // Room for every row a frame can make: points + labels + boundary rows.
  const int rows = settings_.cloud.maxVoxels + 64 + 17 * settings_.cloud.planes.planeCount;
  rig_.world().reserveRows(rows);
  // One lane per strategy, each with its own copy of the rig, so the simulations can run
  // on any thread and give the same result on all of them.
  for (int k = 0; k < kStrategyCount; ++k) {
    if (!settings_.strategies[static_cast<std::size_t>(k)]) continue;
    lanes_.push_back(std::make_unique<Lane>(Lane{rig_,
                                                 Simulator(simulationSettings(settings)),
                                                 makeStrategy(static_cast<StrategyKind>(k)),
                                                 {},
                                                 {},
                                                 {},
                                                 {},
                                                 0.0f}));
    physics::World& world = lanes_.back()->rig.world();
    world.reserveRows(rows);
    world.settings().iterations = settings_.iterations;
    world.settings().relaxIterations = settings_.relaxIterations;
  }
  // Lanes by decreasing run length (ties in lane order), so that runs side by side end together.
  for (std::size_t k = 0; k < lanes_.size(); ++k) {
    const int steps = lanes_[k]->strategy->steps(settings_.substeps);
    auto at = runOrder_.begin();
    while (at != runOrder_.end() &&
           lanes_[static_cast<std::size_t>(*at)]->strategy->steps(settings_.substeps) >= steps)
      ++at;
    runOrder_.insert(at, static_cast<int>(k));
  }
  openAngles_ = model::zeroAngles(model);
  model::clampToLimits(model, openAngles_);
}

void HandTracker::initialize(const model::ModelPose& pose) {
  rig_.setPose(pose);
  tracked_ = true;
  badFrames_ = 0;
  lastWinner_ = -1;
}

void HandTracker::reset() {
  tracked_ = false;
  badFrames_ = 0;
  lastWinner_ = -1;
  disagreeFrames_ = 0;
}

void HandTracker::prepareDetectorEvidence(const HandFrame& frame) {
  detectorLabels_.clear();
  confidentKeypoints_.clear();
  haveDetectorPose_ = false;
  detectorPoseTried_ = false;
  keypoints_ = nullptr;
  const detect::DetectedKeypoints* d = frame.keypoints;
  const DetectorSettings& s = settings_.detector;
  if (d == nullptr || !d->valid || d->meanConfidence < s.minMeanConfidence) return;
  fitIndices_.clear();
  fitTargets_.clear();
  fitWeights_.clear();
  const auto& indices = model_->keypoints21Indices();
  for (std::size_t i = 0; i < indices.size(); ++i) {
    if (d->confidence[i] < s.minConfidence) continue;
    confidentKeypoints_.push_back(static_cast<int>(i));
    fitIndices_.push_back(indices[i]);
    fitTargets_.push_back(d->points[i]);
    fitWeights_.push_back(std::pow(d->confidence[i], s.fitConfidenceExponent));
    const int body = model_->keypoints()[static_cast<std::size_t>(indices[i])].body;
    detectorLabels_.push_back(
        {d->points[i], BodyMask{1} << body, kDetectorLabelCap * d->confidence[i]});
  }
  if (fitIndices_.size() < kMinFitKeypoints ||
      medianDistanceFromSurface(fitTargets_, frame.points) > s.maxOffCloudM) {
    detectorLabels_.clear();
    confidentKeypoints_.clear();
    return;
  }
  keypoints_ = d;
}

float HandTracker::medianDistanceFromSurface(std::span<const Vec3> keypoints,
                                             std::span<const Vec3> points) {
  if (points.empty()) return std::numeric_limits<float>::infinity();
  offCloud_.clear();
  for (const Vec3& k : keypoints) {
    float nearest2 = std::numeric_limits<float>::infinity();
    if (k.z() > 0.0f) {
      // Hidden behind the skin the camera sees is on the data; in front of it (space the
      // camera sees through) or beside it is not. The keypoint moves along its line of sight
      // to each point's depth, so what is left across is the distance from that line.
      const float inverseZ = 1.0f / k.z();
      for (const Vec3& p : points) {
        const float scale = p.z() * inverseZ;
        const float across2 = Vec2(p.x() - k.x() * scale, p.y() - k.y() * scale).squaredNorm();
        const float behind = k.z() - p.z();
        const float along = behind < 0.0f ? -behind : std::max(0.0f, behind - kHiddenDepthM);
        nearest2 = std::min(nearest2, across2 + along * along);
      }
    }
    offCloud_.push_back(nearest2);
  }
  const auto middle = offCloud_.begin() + static_cast<std::ptrdiff_t>(offCloud_.size() / 2);
  std::nth_element(offCloud_.begin(), middle, offCloud_.end());
  return std::sqrt(*middle);
}

bool HandTracker::fitDetectorPose(const model::JointAngles* warmStart) {
  if (keypoints_ == nullptr) return false;
  if (!detectorPoseTried_) {
    detectorPoseTried_ = true;
    model::FitOptions options;
    options.weights = fitWeights_;
    std::span<const int> indices = fitIndices_;
    std::span<const Vec3> targets = fitTargets_;
    const float startPoseWeight = settings_.detector.fitStartPoseWeight;
    if (warmStart != nullptr) {
      options.initial = warmStart;
      options.maxIterations = kWarmFitIterations;
      if (startPoseWeight > 0.0f) {
        // Each keypoint also where the frame starts: the motion so far outweighs the
        // detector's unsure keypoints.
        warmFitIndices_.assign(fitIndices_.begin(), fitIndices_.end());
        warmFitTargets_.assign(fitTargets_.begin(), fitTargets_.end());
        warmFitWeights_.assign(fitWeights_.begin(), fitWeights_.end());
        const auto& modelIndices = model_->keypoints21Indices();
        for (std::size_t i = 0; i < modelIndices.size(); ++i) {
          warmFitIndices_.push_back(modelIndices[i]);
          warmFitTargets_.push_back(startKeypoints_[i]);
          warmFitWeights_.push_back(startPoseWeight);
        }
        indices = warmFitIndices_;
        targets = warmFitTargets_;
        options.weights = warmFitWeights_;
      }
    }
    Result<model::FitResult> fit = fitter_.fit(indices, targets, options);
    if (fit) {
      model::forwardKinematicsInto(*model_, fit->angles, detectorPose_);
      haveDetectorPose_ = true;
    }
  }
  return haveDetectorPose_;
}

std::span<const Vec3> HandTracker::pointsOnTheDetectedHand(std::span<const Vec3> points) {
  const float reach = settings_.detector.objectDistanceM;
  if (reach <= 0.0f || keypoints_ == nullptr) return points;
  // The detected skeleton: every bone from the wrist out, the knuckles joined, and the forearm
  // beyond the wrist (the model's forearm body holds points there too).
  static constexpr std::array<std::array<int, 2>, 24> kBones = {
      {{0, 1},  {1, 2},   {2, 3},   {3, 4},   {0, 5},  {5, 6},   {6, 7},   {7, 8},
       {0, 9},  {9, 10},  {10, 11}, {11, 12}, {0, 13}, {13, 14}, {14, 15}, {15, 16},
       {0, 17}, {17, 18}, {18, 19}, {19, 20}, {1, 5},  {5, 9},   {9, 13},  {13, 17}}};
  const Keypoints21& k = keypoints_->points;
  std::array<Vec3, 25> from, to;
  for (std::size_t b = 0; b < kBones.size(); ++b) {
    from[b] = k[static_cast<std::size_t>(kBones[b][0])];
    to[b] = k[static_cast<std::size_t>(kBones[b][1])];
  }
  from[24] = k[0];
  to[24] = k[0] + kForearmReachM * (k[0] - k[9]).normalized();
  const float reach2 = reach * reach;
  handPoints_.clear();
  for (const Vec3& p : points) {
    bool near = false;
    for (std::size_t b = 0; b < from.size() && !near; ++b) {
      const Vec3 d = to[b] - from[b];
      const float t =
          std::clamp((p - from[b]).dot(d) / std::max(d.squaredNorm(), 1e-12f), 0.0f, 1.0f);
      near = (from[b] + t * d - p).squaredNorm() <= reach2;
    }
    if (near) handPoints_.push_back(p);
  }
  // Most of the points off the detected hand: the detection, not the data, is wrong.
  if (2 * handPoints_.size() < points.size()) return points;
  return handPoints_;
}

float HandTracker::agreementTerm(const Lane& lane) {
  const float weight = settings_.detector.selectionWeight;
  if (weight <= 0.0f || keypoints_ == nullptr) return 0.0f;
  lane.rig.readPose(pose_);
  scratchKeypoints_ = model::keypoints21(*model_, pose_);
  return weight * detectorDistance(scratchKeypoints_);
}

float HandTracker::detectorDistance(const Keypoints21& keypoints) const {
  if (keypoints_ == nullptr || confidentKeypoints_.empty()) return 0.0f;
  // Weighted by confidence: the detector's error grows steeply as its confidence falls.
  float sum = 0.0f;
  float weights = 0.0f;
  for (const int i : confidentKeypoints_) {
    const auto k = static_cast<std::size_t>(i);
    const float weight = keypoints_->confidence[k];
    sum += weight * (keypoints[k] - keypoints_->points[k]).norm();
    weights += weight;
  }
  return weights > 0.0f ? sum / weights : 0.0f;
}

const HandTracker::Lane* HandTracker::checkAgainstDetector(const HandFrame& frame,
                                                           const Lane* best) {
  if (best == nullptr || keypoints_ == nullptr) {
    disagreeFrames_ = 0;
    return best;
  }
  best->rig.readPose(pose_);
  scratchKeypoints_ = model::keypoints21(*model_, pose_);
  const bool disagrees = detectorDistance(scratchKeypoints_) > settings_.detector.disagreeDistanceM;
  disagreeFrames_ = disagrees ? disagreeFrames_ + 1 : 0;
  if (disagreeFrames_ < settings_.detector.disagreeFrames) return best;
  for (const auto& lane : lanes_) {
    if (lane->candidate.kind != StrategyKind::DetectorFit || !lane->candidate.ran ||
        lane.get() == best)
      continue;
    // Replaced: the detector-fit simulation's state, measured in full for the result.
    Lane& replacement = *lane;
    evaluate(replacement.simulator, replacement.rig, frame,
             metricHints(replacement.simulator, replacement.metricHints), replacement.posed,
             replacement.error);
    replacement.candidate.error = replacement.error.total;
    disagreeFrames_ = 0;
    const float ratio = settings_.detector.replaceMaxErrorRatio;
    if (ratio > 0.0f && replacement.error.total > ratio * best->error.total) return best;
    return &replacement;
  }
  return best;
}

bool HandTracker::evaluate(Simulator& simulator, const HandRig& rig, const HandFrame& frame,
                           std::span<const int> hints, PosedBodies& posed, ErrorBreakdown& error,
                           float abortAbove, std::span<const int> order) {
  simulator.pose(rig, posed);
  const CloudFrame* cloud = frame.cloud;
  return computeErrorBounded(
      posed, frame.points, [cloud](const Vec3& p) { return cloud != nullptr && cloud->isFree(p); },
      abortAbove, error, hints, order, kNearSurfaceM);
}

std::span<const int> HandTracker::metricHints(const Simulator& simulator,
                                              std::vector<int>& buffer) const {
  const std::span<const int> last = simulator.lastNearestBodies();
  if (last.size() != keptIndex_.size() || last.size() == frameStartBodies_.size()) return last;
  buffer = frameStartBodies_;
  for (std::size_t k = 0; k < keptIndex_.size(); ++k)
    buffer[static_cast<std::size_t>(keptIndex_[k])] = last[k];
  return buffer;
}

void HandTracker::thinPoints(std::span<const Vec3> points) {
  const std::span<const int> bodies = simulator_.lastNearestBodies();
  frameStartBodies_.assign(bodies.begin(), bodies.end());
  const long cap = settings_.palmPointCap;
  const std::array<int, 2> thinned = {rig_.anatomy().palm, rig_.anatomy().forearm};
  std::array<long, 2> count{}, seen{};
  auto slotOf = [&thinned](int body) {
    return body == thinned[0] ? 0 : body == thinned[1] ? 1 : -1;
  };
  for (const int b : bodies) {
    const int k = slotOf(b);
    if (k >= 0) ++count[static_cast<std::size_t>(k)];
  }
  keptIndex_.clear();
  keptPoints_.clear();
  keptWeights_.clear();
  for (std::size_t i = 0; i < points.size(); ++i) {
    const int k = slotOf(bodies[i]);
    float weight = 1.0f;
    if (k >= 0 && count[static_cast<std::size_t>(k)] > cap) {
      // The body's j-th point of c is kept when floor((j + 1) cap / c) steps up: cap of them,
      // spread evenly, each standing for c / cap.
      const long c = count[static_cast<std::size_t>(k)];
      const long j = seen[static_cast<std::size_t>(k)]++;
      if ((j + 1) * cap / c == j * cap / c) continue;
      weight = static_cast<float>(c) / static_cast<float>(cap);
    }
    keptIndex_.push_back(static_cast<int>(i));
    keptPoints_.push_back(points[i]);
    keptWeights_.push_back(weight);
  }
  simulator_.keepPoints(keptIndex_, keptPoints_);
}

void HandTracker::evaluateUntilBeaten(const HandFrame& frame) {
  // The last frame's winner first (it usually wins again), then the rest in lane order: the
  // first candidate is measured in full; each later one gives up once it is sure to lose to
  // the best so far, visiting first the points farthest from the first candidate's model (a
  // losing pose is usually off on the same points). Whatever the order, every candidate at or
  // below the best is measured in full, so the winner (least error, ties to the earlier lane)
  // and its breakdown are exactly computeError's; only the losers' lower bounds depend on it.
  float best = std::numeric_limits<float>::infinity();
  metricOrder_.clear();
  const std::size_t count = lanes_.size();
  const std::size_t first =
      lastWinner_ >= 0 && static_cast<std::size_t>(lastWinner_) < count ? lastWinner_ : 0;
  for (std::size_t k = 0; k < count; ++k) {
    // first, then 0, 1, ... without it
    const std::size_t index = k == 0 ? first : (k <= first ? k - 1 : k);
    Lane& lane = *lanes_[index];
    if (!lane.candidate.ran) continue;
    const float agreement = agreementTerm(lane);
    if (evaluate(lane.simulator, lane.rig, frame, metricHints(lane.simulator, lane.metricHints),
                 lane.posed, lane.error, best - agreement, metricOrder_))
      best = std::min(best, lane.error.total + agreement);
    lane.candidate.error = lane.error.total;
    lane.score = lane.error.total + agreement;
    if (metricOrder_.empty()) {
      const auto& distance = lane.error.pointDistance;
      metricOrder_.resize(distance.size());
      std::iota(metricOrder_.begin(), metricOrder_.end(), 0);
      const auto farFirst = [&distance](int a, int b) {
        const float da = distance[static_cast<std::size_t>(a)];
        const float db = distance[static_cast<std::size_t>(b)];
        return da > db || (da == db && a < b);
      };
      const auto head = metricOrder_.begin() +
                        static_cast<std::ptrdiff_t>(metricOrder_.size() / kMetricHeadFraction);
      std::nth_element(metricOrder_.begin(), head, metricOrder_.end(), farFirst);
    }
  }
}

float HandTracker::evaluate(Simulator& simulator, const HandFrame& frame) {
  evaluate(simulator, rig_, frame, simulator.lastNearestBodies(), posed_, error_);
  return error_.total;
}

void HandTracker::track(const HandFrame& frame, HandResult& out) {
  out.side = side_;
  out.acquired = false;
  out.candidates.clear();
  out.pointCount = static_cast<int>(frame.points.size());
  // This frame's detection is filled in below; none (not the last frame's) until then, and
  // when the hand has left the view.
  out.detected = false;
  out.detectorKeypoints21.fill(Vec3::Zero());
  out.detectorConfidence.fill(0.0f);
  out.detectorDisagreement = 0.0f;
  if (frame.points.size() < static_cast<std::size_t>(kMinPoints)) {
    // The hand left the view: lost until it comes back and is re-acquired.
    tracked_ = false;
    badFrames_ = 0;
    out.tracked = false;
    out.error = 0.0f;
    return;
  }
  prepareDetectorEvidence(frame);
  // The points the simulations pull on and the metric scores: without a held object's.
  HandFrame hand = frame;
  hand.points = pointsOnTheDetectedHand(frame.points);
  if (!tracked_ || settings_.perFrame) {
    acquire(hand, out);
  } else {
    runStrategies(hand, out);
  }
  fillResult(out);
  out.detected = keypoints_ != nullptr;
  if (hand.keypoints != nullptr && hand.keypoints->valid) {
    out.detectorKeypoints21 = hand.keypoints->points;
    out.detectorConfidence = hand.keypoints->confidence;
  }
  if (keypoints_ != nullptr) out.detectorDisagreement = detectorDistance(out.skeletonKeypoints21);
  out.disagreeingFrames = disagreeFrames_;
  if (out.tracked && hand.cloud != nullptr) {
    simulator_.pose(rig_, posed_);
    std::array<Vec3, 5> tips;
    for (std::size_t f = 0; f < 5; ++f) tips[f] = out.skeletonKeypoints21[4 + 4 * f];
    // bestBreakdown_ was measured at exactly these poses: its point distances are this
    // pose's.
    const Keypoints21& k = out.skeletonKeypoints21;
    const WristPlane wrist{k[0], (k[0] - k[9]).normalized()};
    out.quality = measureFitQuality(posed_, bestBreakdown_.pointDistance, hand.points, &wrist,
                                    *hand.cloud, rig_.anatomy().forearm, tips);
  } else {
    out.quality = FitQuality{};
  }
  if (out.tracked) blendTowardDetector(out.keypoints21);
}

void HandTracker::blendTowardDetector(Keypoints21& keypoints) const {
  const float blend = settings_.detector.reportBlend;
  const float reach = settings_.detector.reportBlendReachM;
  if (blend <= 0.0f || reach <= 0.0f || keypoints_ == nullptr) return;
  for (const int i : confidentKeypoints_) {
    const auto k = static_cast<std::size_t>(i);
    const Vec3 offset = keypoints_->points[k] - keypoints[k];
    const float nearness = std::max(0.0f, 1.0f - offset.norm() / reach);
    keypoints[k] += std::min(1.0f, blend * keypoints_->confidence[k]) * nearness * offset;
  }
}

void HandTracker::prepareFrameStart(const HandFrame& frame) {
  auto& world = rig_.world();
  world.saveState(start_);
  rig_.readPose(pose_);
  // The detector's simulations run only when the frame starts away from its keypoints: where
  // the two agree, the detector's ~1-2 cm of noise has nothing to add to the fit.
  bool engageDetector = false;
  bool warmFit = false;
  if (keypoints_ != nullptr) {
    startKeypoints_ = model::keypoints21(*model_, pose_);
    const float distance = detectorDistance(startKeypoints_);
    engageDetector = distance > settings_.detector.engageDistanceM;
    warmFit = distance < kWarmFitDistanceM;
  }
  const int forearm = rig_.anatomy().forearm;
  const Pose forearmPose = world.pose(forearm);
  forearmHold_ =
      AxisHold{forearm, Vec3::Zero(), forearmPose.p, forearmPose.rotate(rig_.anatomy().forearmAxis),
               settings_.forearmHoldForce};
  model::jointAnglesInto(*model_, pose_, startAngles_);
  const FrameInput input{frame.points,
                         frame.planes,
                         {},
                         frame.cloud,
                         settings_.forearmHoldForce > 0.0f ? &forearmHold_ : nullptr,
                         {}};
  // Every simulation's first substep maps the points at the same poses: once, shared.
  simulator_.mapFrameStart(rig_, input);
  keptIndex_.clear();
  frameStartBodies_.clear();
  // Built in place: the simulator recognises the lanes' input by its address (shared rows).
  FrameStart& start = frameStart_;
  start = FrameStart{input, false, nullptr};
  if (settings_.palmPointCap > 0) {
    thinPoints(frame.points);
    start.laneInput.points = keptPoints_;
    start.laneInput.weights = keptWeights_;
  }
  // The strategies that only change joints or welds before their first step (all but the
  // detector's) share that step's rows too.
  simulator_.prepareFrameStartRows(rig_, start.laneInput);
  // Fitted here, not in a lane: lanes may run on other threads.
  // The keypoints bound as labelled points (the feature simulation) only when the frame starts
  // far from them: nearer, pulling bones onto the detector's noisy joints made the result
  // worse than the fitted start alone (motion suite, docs/tracker.md).
  start.bindLabels = engageDetector && !warmFit;
  start.fittedStart = engageDetector && fitDetectorPose(warmFit ? &startAngles_ : nullptr)
                          ? &detectorPose_
                          : nullptr;
}

StrategyContext HandTracker::laneContext(Lane& lane, const HandFrame& frame,
                                         const FrameStart& start) const {
  return StrategyContext{
      lane.rig,
      lane.simulator,
      start.laneInput,
      settings_.substeps,
      frame.time,
      settings_.flipPeriodS,
      frame.detection,
      &startAngles_,
      start.bindLabels ? std::span<const LabelledPoint>(detectorLabels_)
                       : std::span<const LabelledPoint>(),
      start.fittedStart,
      keypoints_ != nullptr &&
          settings_.strategies[static_cast<std::size_t>(StrategyKind::DetectorFit)]};
}

void HandTracker::startLane(Lane& lane) {
  lane.rig.world().restoreState(start_);
  lane.simulator.beginFrame(&simulator_);
  lane.candidate.kind = lane.strategy->kind();
  lane.candidate.error = 0.0f;
}

void HandTracker::finishLane(Lane& lane, const HandFrame& frame) {
  if (!lane.candidate.ran || !settings_.keepCandidates) return;
  evaluate(lane.simulator, lane.rig, frame, metricHints(lane.simulator, lane.metricHints),
           lane.posed, lane.error);
  lane.candidate.error = lane.error.total;
  lane.score = lane.error.total + agreementTerm(lane);
  lane.rig.readPose(lane.candidate.pose);
}

void HandTracker::runLanes(const HandFrame& frame, const FrameStart& start) {
  const int count = static_cast<int>(lanes_.size());
  if (pool_ != nullptr) {
    pool_->run(count, [&](int index) {
      Lane& lane = *lanes_[static_cast<std::size_t>(index)];
      startLane(lane);
      StrategyContext context = laneContext(lane, frame, start);
      lane.candidate.ran = runStrategy(*lane.strategy, context);
      finishLane(lane, frame);
    });
    return;
  }
  // Up to four lanes at a time (longest runs first, so that runs side by side end together),
  // their worlds stepped side by side: the same bits as one after the other, in less time.
  const std::size_t n = runOrder_.size();
  for (std::size_t k = 0; k < n; ++k) {
    Lane& lane = *lanes_[static_cast<std::size_t>(runOrder_[k])];
    startLane(lane);
    laneContexts_[k].emplace(laneContext(lane, frame, start));
    laneStrategies_[k] = lane.strategy.get();
    laneContextPointers_[k] = &*laneContexts_[k];
  }
  runStrategiesSideBySide(std::span(laneStrategies_.data(), n),
                          std::span(laneContextPointers_.data(), n), std::span(laneRan_.data(), n));
  for (std::size_t k = 0; k < n; ++k) {
    Lane& lane = *lanes_[static_cast<std::size_t>(runOrder_[k])];
    lane.candidate.ran = laneRan_[k];
    finishLane(lane, frame);
    laneContexts_[k].reset();
  }
}

void HandTracker::pickWinner(const HandFrame& frame, HandResult& out) {
  // The winner, in strategy order (ties to the earlier strategy).
  float bestScore = std::numeric_limits<float>::infinity();
  float bestError = std::numeric_limits<float>::infinity();
  StrategyKind bestKind = StrategyKind::Normal;
  const Lane* best = nullptr;
  lastWinner_ = -1;
  for (std::size_t k = 0; k < lanes_.size(); ++k) {
    const Lane& lane = *lanes_[k];
    if (lane.candidate.ran && lane.score < bestScore) {
      bestScore = lane.score;
      bestError = lane.candidate.error;
      bestKind = lane.candidate.kind;
      best = &lane;
      lastWinner_ = static_cast<int>(k);
    }
    out.candidates.push_back(lane.candidate);
  }
  if (const Lane* kept = checkAgainstDetector(frame, best); kept != best) {
    best = kept;
    bestError = kept->candidate.error;
    bestKind = kept->candidate.kind;
    lastWinner_ = -1;
    for (auto& c : out.candidates)
      if (c.kind == bestKind) c.error = bestError;
  }
  if (best != nullptr) {
    rig_.world().restoreState(best->rig.world().state());
    bestBreakdown_ = best->error;
  } else {  // no simulation ran (all switched off): measure the state as it is
    evaluate(simulator_, frame);
    bestBreakdown_ = error_;
  }
  out.simulation = bestKind;
  const float threshold = settings_.lostErrorPerBodyM * static_cast<float>(model_->bodyCount());
  badFrames_ = bestError > threshold ? badFrames_ + 1 : 0;
  if (badFrames_ >= settings_.lostAfterFrames) tracked_ = false;
}

void HandTracker::runStrategies(const HandFrame& frame, HandResult& out) {
  prepareFrameStart(frame);
  runLanes(frame, frameStart_);
  if (!settings_.keepCandidates) evaluateUntilBeaten(frame);
  pickWinner(frame, out);
}

model::ModelPose HandTracker::canonicalPose(const HandFrame& frame, const Vec2& axisImage,
                                            const Vec2& thumbSideImage) const {
  const model::ModelPose rest = model::forwardKinematics(*model_, openAngles_);
  const auto k = model::keypoints21(*model_, rest);
  const Vec3 fingerModel = (k[9] - k[0]).normalized();
  Vec3 thumbModel = (k[5] - k[17]);
  if (side_ == model::Side::Left)
    thumbModel = -thumbModel;  // mirrored: index->pinky points away from the thumb
  thumbModel = (thumbModel - thumbModel.dot(fingerModel) * fingerModel).normalized();

  // Mean of the points and its pixel; image directions lifted to the plane z = const.
  Vec3 centroid = Vec3::Zero();
  for (const Vec3& p : frame.points) centroid += p;
  centroid /= static_cast<float>(frame.points.size());
  Vec3 fingerCam(axisImage.x(), axisImage.y(), 0.0f);
  Vec3 thumbCam(thumbSideImage.x(), thumbSideImage.y(), 0.0f);
  fingerCam.normalize();
  thumbCam = (thumbCam - thumbCam.dot(fingerCam) * fingerCam).normalized();

  Mat3 from, to;
  from << fingerModel, thumbModel, fingerModel.cross(thumbModel);
  to << fingerCam, thumbCam, fingerCam.cross(thumbCam);
  const Quat rotation(to * from.transpose());
  Vec3 handCentre = Vec3::Zero();
  for (const Vec3& p : k) handCentre += p;
  handCentre /= 21.0f;
  // The surface seen is the front of the hand; its middle lies about a centimetre behind.
  const Vec3 target = centroid + Vec3(0, 0, 0.01f);
  const Pose transform{target - rotation * handCentre, rotation.normalized()};
  model::ModelPose placed = rest;
  for (auto& body : placed.bodies) body = transform * body;
  return placed;
}

void HandTracker::acquire(const HandFrame& frame, HandResult& out) {
  auto& world = rig_.world();
  lastWinner_ = -1;
  acquisitionSimulator_.beginFrame();
  Vec2 axis(0.0f, -1.0f);
  if (frame.cloud != nullptr && frame.cloud->segment.armDirectionImage.norm() > 0.5f) {
    axis = -frame.cloud->segment.armDirectionImage.normalized();
  }
  const Vec2 across(-axis.y(), axis.x());  // thumb side of a right palm facing the camera
  struct Start {
    Vec2 axis, thumb;
    bool labelled;
    bool fitted = false;  // the pose fitted to the learned detector's keypoints
  };
  std::vector<Start> starts;
  if (fitDetectorPose()) starts.push_back({Vec2::Zero(), Vec2::Zero(), false, true});
  const float mirror = side_ == model::Side::Right ? 1.0f : -1.0f;
  const bool detected = frame.detection != nullptr && frame.detection->fired;
  if (detected) {
    starts.push_back({frame.detection->axisImage, frame.detection->thumbSideImage, true});
  }
  starts.push_back({axis, across * mirror, false});   // palm toward the camera
  starts.push_back({axis, -across * mirror, false});  // back of the hand toward the camera

  float bestError = std::numeric_limits<float>::infinity();
  float bestScore = std::numeric_limits<float>::infinity();
  std::vector<LabelledPoint> labels;
  for (const Start& s : starts) {
    rig_.setPose(s.fitted ? detectorPose_ : canonicalPose(frame, s.axis, s.thumb));
    FrameInput input{frame.points, frame.planes, {}, frame.cloud, nullptr, {}};
    int steps = settings_.acquisitionSubsteps;
    if (s.labelled) {
      labels.clear();
      for (int f = 0; f < kFingerCount; ++f) {
        const int tip = rig_.anatomy().fingers[static_cast<std::size_t>(f)][2];
        labels.push_back(
            {frame.detection->tips[static_cast<std::size_t>(f)], BodyMask{1} << tip, 20.0f});
      }
      input.labelled = labels;
      acquisitionSimulator_.run(rig_, input, steps / 2);
      input.labelled = {};
      steps -= steps / 2;
    }
    acquisitionSimulator_.run(rig_, input, steps);
    Candidate candidate;
    candidate.kind = s.fitted     ? StrategyKind::DetectorFit
                     : s.labelled ? StrategyKind::FeatureDetection
                                  : StrategyKind::Normal;
    candidate.ran = true;
    candidate.error = evaluate(acquisitionSimulator_, frame);
    // Acquisition compares starts far apart: a fingertip left over background (which the
    // paper's metric scores only through its bone's centroid) counts as kOffHandTipPenaltyM.
    float score = candidate.error;
    if (frame.cloud != nullptr) {
      rig_.readPose(pose_);
      scratchKeypoints_ = model::keypoints21(*model_, pose_);
      std::array<Vec3, 5> tips;
      for (std::size_t f = 0; f < 5; ++f) tips[f] = scratchKeypoints_[4 + 4 * f];
      score += kOffHandTipPenaltyM *
               static_cast<float>(measureFitQuality(posed_, error_.pointDistance, {}, nullptr,
                                                    *frame.cloud, rig_.anatomy().forearm, tips)
                                      .fingertipsOffHand);
    }
    if (score < bestScore) {
      bestScore = score;
      bestError = candidate.error;
      world.saveState(best_);
      bestBreakdown_ = error_;
      out.simulation = candidate.kind;
    }
    if (settings_.keepCandidates) rig_.readPose(candidate.pose);
    out.candidates.push_back(std::move(candidate));
  }
  world.restoreState(best_);
  for (int b = 0; b < world.bodyCount(); ++b) world.setVelocity(b, Vec3::Zero(), Vec3::Zero());
  const float threshold = settings_.lostErrorPerBodyM * static_cast<float>(model_->bodyCount());
  tracked_ = bestError <= threshold;
  badFrames_ = 0;
  out.acquired = tracked_;
}

void HandTracker::fillResult(HandResult& out) {
  // The world holds the winner's state, whose error was measured when it won.
  rig_.readPose(out.pose);
  const ErrorBreakdown& e = bestBreakdown_;
  out.tracked = tracked_;
  out.error = e.total;
  out.fitError = e.fitTotal;
  out.occlusionError = e.occlusionTotal;
  out.bodyError.resize(e.fit.size());
  for (std::size_t i = 0; i < e.fit.size(); ++i) out.bodyError[i] = e.fit[i] + e.occlusion[i];
  out.skeletonKeypoints21 = model::keypoints21(*model_, out.pose);
  out.keypoints21 = out.skeletonKeypoints21;
  if (model_->hasOpenXrJoints()) out.openxr26 = model::openxr26(*model_, out.pose);
}

}  // namespace dynahand::track
