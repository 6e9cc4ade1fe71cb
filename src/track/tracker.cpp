#include "dynahand/tracker.h"

#include <chrono>
#include <cmath>
#include <optional>

#include "dynahand/detector.h"
#include "dynahand/hand_split.h"
#include "dynahand/model_fit.h"

#include "track/finger_detector.h"
#include "track/hand_tracker.h"
#include "track/worker_pool.h"

namespace dynahand::track {

namespace {

// A crop centre this near (m) to one of the hand's points is on the hand.
constexpr float kCropOnPointsM = 0.05f;

bool liesOnPoints(const Vec3& p, const std::vector<Vec3>& points, float distanceM) {
  const float limit = distanceM * distanceM;
  for (const Vec3& q : points)
    if ((q - p).squaredNorm() <= limit) return true;
  return false;
}

// The detection `k`, made from the crop centred at `centre`, averaged with the detections of
// DetectorSettings::shiftedCrops more crops, centred shiftedCropM away along the image's
// diagonals. The network's keypoints move by several millimetres when its crop moves by a
// pixel (the crop is resampled from the depth by nearest pixel): the mean over a few crops
// is nearer the truth than any one of them (docs/tracker.md, "Learned detector").
void averageShiftedCrops(const DetectorSettings& settings, const CloudFrame& cloud,
                         detect::KeypointDetector& detector, detect::HandCrop& crop,
                         const Vec3& centre, bool mirrored, const detect::CropHandSplit* split,
                         detect::DetectedKeypoints& k) {
  const int shifted = settings.shiftedCrops;
  const float d = settings.shiftedCropM;
  if (!k.valid || shifted <= 0) return;
  const std::array<Vec3, 4> shifts = {Vec3(d, d, 0.0f), Vec3(-d, -d, 0.0f), Vec3(d, -d, 0.0f),
                                      Vec3(-d, d, 0.0f)};
  detect::DetectedKeypoints sum = k;
  int count = 1;
  for (int i = 0; i < shifted; ++i) {
    const Vec3 c = centre + shifts[static_cast<std::size_t>(i)];
    if (!detect::makeCrop(cloud, mirrored, crop, &c, split)) continue;
    const detect::DetectedKeypoints& e = detector.detect(crop, cloud.intrinsics);
    if (!e.valid) continue;
    for (std::size_t j = 0; j < sum.points.size(); ++j) {
      sum.points[j] += e.points[j];
      sum.confidence[j] += e.confidence[j];
    }
    sum.meanConfidence += e.meanConfidence;
    ++count;
  }
  const float inverse = 1.0f / static_cast<float>(count);
  for (std::size_t j = 0; j < sum.points.size(); ++j) {
    k.points[j] = sum.points[j] * inverse;
    k.confidence[j] = sum.confidence[j] * inverse;
  }
  k.meanConfidence = sum.meanConfidence * inverse;
}

}  // namespace

const char* strategyName(StrategyKind kind) {
  switch (kind) {
    case StrategyKind::Normal:
      return "normal";
    case StrategyKind::GrossMotion:
      return "gross_motion";
    case StrategyKind::GraspBias:
      return "grasp_bias";
    case StrategyKind::FingerFlip:
      return "finger_flip";
    case StrategyKind::FeatureDetection:
      return "feature_detection";
    case StrategyKind::DetectorFit:
      return "detector_fit";
  }
  return "unknown";
}

struct Tracker::Impl {
  TrackerSettings settings;
  Intrinsics intrinsics;
  model::ArticulatedModel right;
  model::ArticulatedModel left;
  CloudPipeline pipeline;
  CloudFrame cloud;
  HandSplitter splitter;
  HandSplit split;
  FingerDetector detector;
  std::unique_ptr<detect::KeypointDetector> keypointDetector;  // null: none
  // One hand: the centre of its keypoints where it was tracked last frame (the segmentation's
  // hint); none after a loss, reset() or initialize().
  std::optional<Vec3> trackedHandCentre;
  detect::HandCrop crop;
  detect::DetectedKeypoints keypoints[2];
  bool givenKeypoints[2] = {false, false};  // keypoints[h] set by setKeypoints for this frame
  std::unique_ptr<WorkerPool> pool;         // null with one thread
  std::unique_ptr<HandTracker> hands[2];    // [0] right, [1] left
  std::vector<Vec3> handPoints[2];
  TrackResult result;
  int frameIndex = 0;

  Impl(const model::ArticulatedModel& rightHand, const Intrinsics& k, const TrackerSettings& s)
      : settings(s),
        intrinsics(k),
        right(rightHand),
        left(model::mirrorModel(rightHand)),
        pipeline(k, s.cloud),
        splitter(s.split),
        pool(s.threads > 1 ? std::make_unique<WorkerPool>(s.threads) : nullptr) {}
};

Tracker::Tracker(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Tracker::~Tracker() = default;

Result<std::unique_ptr<Tracker>> Tracker::create(const model::ArticulatedModel& rightHand,
                                                 const Intrinsics& intrinsics,
                                                 const TrackerSettings& settings) {
  if (intrinsics.width <= 0 || intrinsics.height <= 0 || !(intrinsics.fx > 0) ||
      !(intrinsics.fy > 0)) {
    return Error{"invalid camera intrinsics"};
  }
  if (settings.hands != 1 && settings.hands != 2) return Error{"hands must be 1 or 2"};
  if (settings.threads < 1 || settings.threads > 64) return Error{"threads must be 1..64"};
  if (settings.substeps < 1 || settings.iterations < 1 || settings.acquisitionIterations < 1)
    return Error{"substeps, iterations and acquisitionIterations must be >= 1"};
  if (settings.relaxIterations < 0 || settings.acquisitionRelaxIterations < 0)
    return Error{"relaxIterations and acquisitionRelaxIterations must be >= 0"};
  if (settings.palmPointCap < 0) return Error{"palmPointCap must be >= 0 (0: all points)"};
  if (settings.pointSubsets < 1 || settings.pointSubsets > 16)
    return Error{"pointSubsets must be 1..16"};
  // A negative band leaves no vertex near enough: the boundary planes would silently go.
  if (!(settings.boundaryBand >= 0.0f)) return Error{"boundaryBand must be >= 0 m"};
  for (const float pull : {settings.pullForce, settings.acquisitionPullForce})
    if (!(pull >= 0.0f) || !std::isfinite(pull))
      return Error{"pullForce and acquisitionPullForce must be finite and >= 0 N"};
  TrackerSettings s = settings;
  std::unique_ptr<detect::KeypointDetector> keypointDetector;
  if (s.detector.enabled) {
    const std::filesystem::path file = s.detector.weights.empty()
                                           ? detect::defaultDetectorFile()
                                           : std::filesystem::path(s.detector.weights);
    if (!file.empty()) {
      auto loaded = detect::KeypointDetector::load(file);
      if (!loaded) return loaded.error();
      keypointDetector = std::move(*loaded);
      s.detector.weights = file.string();
    }
  }
  if (!(s.detector.minConfidence >= 0.0f && s.detector.minConfidence <= 1.0f) ||
      !(s.detector.minMeanConfidence >= 0.0f && s.detector.minMeanConfidence <= 1.0f))
    return Error{"detector confidences must be in [0, 1]"};
  if (!(s.detector.maxOffCloudM > 0.0f)) return Error{"detector maxOffCloudM must be > 0 m"};
  if (!(s.detector.disagreeDistanceM > 0.0f) || s.detector.disagreeFrames < 1)
    return Error{"detector disagreeDistanceM must be > 0 m and disagreeFrames >= 1"};
  if (!(s.detector.replaceMaxErrorRatio >= 0.0f) || std::isinf(s.detector.replaceMaxErrorRatio))
    return Error{"detector replaceMaxErrorRatio must be >= 0 and finite (0: always replace)"};
  if (s.detector.shiftedCrops < 0 || s.detector.shiftedCrops > 4 ||
      !(s.detector.shiftedCropM >= 0.0f && s.detector.shiftedCropM <= 0.05f))
    return Error{"detector shiftedCrops must be 0..4 and shiftedCropM in [0, 0.05] m"};
  if (!(s.detector.limbEndRadius >= 0.0f) || !(s.detector.limbEndCropDistanceM > 0.0f))
    return Error{"detector limbEndRadius must be >= 0 and limbEndCropDistanceM > 0 m"};
  if (!keypointDetector) s.detector.enabled = false;
  const float length = rightHand.metadata().referenceLength;
  const float referenceLength = model::HandDimensions{}.length;
  if (s.scaleSegmentationToHand && length > referenceLength)
    s.cloud.segmentation.handRadiusM *= length / referenceLength;
  if (s.hands == 2 && s.cloud.segmentation.secondRegionDepthBandM <= 0.0f)
    s.cloud.segmentation.secondRegionDepthBandM = kTwoHandDepthBandM;
  auto impl = std::make_unique<Impl>(rightHand, intrinsics, s);
  impl->keypointDetector = std::move(keypointDetector);
  auto right = HandTracker::create(impl->right, model::Side::Right, s, impl->pool.get());
  if (!right) return right.error();
  impl->hands[0] = std::move(*right);
  if (settings.hands == 2) {
    auto left = HandTracker::create(impl->left, model::Side::Left, s, impl->pool.get());
    if (!left) return left.error();
    impl->hands[1] = std::move(*left);
  }
  return std::unique_ptr<Tracker>(new Tracker(std::move(impl)));
}

void Tracker::initialize(const model::ModelPose& pose, model::Side side) {
  auto& hand = impl_->hands[side == model::Side::Right ? 0 : 1];
  if (hand) hand->initialize(pose);
  impl_->trackedHandCentre.reset();
}

Status Tracker::initializeFromKeypoints(const Keypoints21& keypoints, model::Side side) {
  const auto& m = side == model::Side::Right ? impl_->right : impl_->left;
  auto fit = model::fitToKeypoints(m, keypoints);
  if (!fit) return fit.error();
  initialize(model::forwardKinematics(m, fit->angles), side);
  return Ok{};
}

void Tracker::reset() {
  for (auto& hand : impl_->hands) {
    if (hand) hand->reset();
  }
  impl_->splitter.reset();
  impl_->trackedHandCentre.reset();
}

void Tracker::setKeypoints(const detect::DetectedKeypoints& keypoints, model::Side side) {
  const std::size_t h = side == model::Side::Right ? 0 : 1;
  if (!impl_->hands[h]) return;  // not tracked (one hand: the right one only)
  detect::DetectedKeypoints& k = impl_->keypoints[h];
  k = keypoints;
  float sum = 0.0f;
  for (const float c : k.confidence) sum += c;
  k.meanConfidence = sum / static_cast<float>(k.confidence.size());
  impl_->givenKeypoints[h] = true;
}

const CloudFrame& Tracker::lastCloud() const {
  return impl_->cloud;
}
const model::ArticulatedModel& Tracker::model(model::Side side) const {
  return side == model::Side::Right ? impl_->right : impl_->left;
}
const TrackerSettings& Tracker::settings() const {
  return impl_->settings;
}

const TrackResult& Tracker::track(const DepthFrame& frame) {
  const auto start = std::chrono::steady_clock::now();
  Impl& m = *impl_;
  TrackResult& r = m.result;
  r.frame = m.frameIndex++;
  const double time = frame.timestamp > 0.0
                          ? frame.timestamp
                          : r.frame * static_cast<double>(m.settings.stepDt) * m.settings.substeps;
  // One hand tracked last frame: the segmentation keeps to it (SegmentationConfig::hintReachM).
  const bool hinted = m.trackedHandCentre.has_value() && !m.settings.perFrame;
  HandHint hint;
  if (hinted) hint.centre = *m.trackedHandCentre;
  const Status processed = m.pipeline.process(frame, m.cloud, hinted ? &hint : nullptr);
  const bool haveCloud = processed.ok() && m.cloud.segment.found;
  const FingerDetection* detection = nullptr;
  if (haveCloud &&
      m.settings.strategies[static_cast<std::size_t>(StrategyKind::FeatureDetection)]) {
    detection = &m.detector.detect(m.cloud);
  }

  const int handCount = m.settings.hands;
  r.hands.resize(static_cast<std::size_t>(handCount));
  for (auto& pts : m.handPoints) pts.clear();
  if (haveCloud) {
    if (handCount == 1) {
      m.handPoints[0].assign(m.cloud.points.begin(), m.cloud.points.end());
    } else {
      m.splitter.split(m.cloud.points, m.split);
      for (std::size_t i = 0; i < m.cloud.points.size(); ++i) {
        const int h = m.split.label[i] == Hand::kRight ? 0 : 1;
        m.handPoints[h].push_back(m.cloud.points[i]);
      }
    }
  }
  for (int h = 0; h < handCount; ++h) {
    HandFrame in;
    if (m.givenKeypoints[h]) {
      m.givenKeypoints[h] = false;
      const detect::DetectedKeypoints& k = m.keypoints[h];
      in.keypoints = haveCloud && k.valid ? &k : nullptr;
    } else if (haveCloud && m.keypointDetector) {
      // The learned detector on this hand's crop (left hands mirrored into right ones).
      const Vec3* centre = nullptr;
      Vec3 clusterCentre;
      // Two hands found: each crop leaves out the other hand's pixels. Touching hands are one
      // segment, and the network, trained on crops that rarely hold a second hand, reads the
      // other hand's fingers as its own.
      detect::CropHandSplit handSplit;
      const detect::CropHandSplit* split = nullptr;
      if (handCount == 2) {
        const auto& cluster = m.split[h == 0 ? Hand::kRight : Hand::kLeft];
        const auto& other = m.split[h == 0 ? Hand::kLeft : Hand::kRight];
        clusterCentre = cluster.centroid;
        centre = cluster.present ? &clusterCentre : nullptr;
        if (cluster.present && other.present) {
          handSplit = {cluster.centroid, other.centroid};
          split = &handSplit;
        }
      }
      detect::DetectedKeypoints& k = m.keypoints[h];
      // The crop is centred on the hand where last frame's detection found it, while that
      // still lies on this hand's points: the network then sees the whole hand centred, as in
      // most of its training crops. Otherwise it looks from the hand's estimated centre (or
      // the centroid) first, then again centred on what it found there.
      Vec3 handCentre = k.valid ? detect::keypointBoxCentre(k.points) : Vec3::Zero();
      bool onHand = k.valid && liesOnPoints(handCentre, m.handPoints[h], kCropOnPointsM);
      // One hand whose segment is a limb: the hand is at its free end. A crop centred there
      // holds the hand, where the segment's centroid lies on the forearm (about 12 cm from
      // the hand's centre for a head-mounted camera); last frame's detection far from it was
      // read from the forearm.
      Vec3 endCentre;
      const DetectorSettings& ds = m.settings.detector;
      const float handLength = m.right.metadata().referenceLength;  // wrist to middle tip, m
      if (handCount == 1 && ds.limbEndRadius > 0.0f &&
          detect::limbEndHandCentre(m.cloud, m.handPoints[h], ds.limbEndRadius * handLength,
                                    endCentre)) {
        centre = &endCentre;
        if (onHand && (handCentre - endCentre).norm() > ds.limbEndCropDistanceM) onHand = false;
      }
      const bool mirrored = h == 1;
      k.valid = false;
      Vec3 cropCentre = handCentre;  // where the crop k came from is centred
      if (onHand) {
        if (detect::makeCrop(m.cloud, mirrored, m.crop, &handCentre, split))
          k = m.keypointDetector->detect(m.crop, m.intrinsics);
      } else if ((handCount == 1 || centre != nullptr) &&
                 detect::makeCrop(m.cloud, mirrored, m.crop, centre, split)) {
        k = m.keypointDetector->detect(m.crop, m.intrinsics);
        cropCentre = centre != nullptr ? *centre : m.cloud.segment.centroid;
        if (k.valid) {
          handCentre = detect::keypointBoxCentre(k.points);
          if (detect::makeCrop(m.cloud, mirrored, m.crop, &handCentre, split)) {
            const detect::DetectedKeypoints& centred =
                m.keypointDetector->detect(m.crop, m.intrinsics);
            if (centred.valid) {
              k = centred;
              cropCentre = handCentre;
            }
          }
        }
      }
      averageShiftedCrops(ds, m.cloud, *m.keypointDetector, m.crop, cropCentre, mirrored, split, k);
      in.keypoints = k.valid ? &k : nullptr;
    }
    in.points = m.handPoints[h];
    in.planes = m.cloud.planes;
    in.cloud = &m.cloud;
    in.time = time;
    // A detection belongs to the only hand, or to the hand whose cluster holds its tips.
    if (detection != nullptr && detection->fired) {
      if (handCount == 1) {
        in.detection = detection;
      } else {
        const Vec3 tips = (detection->tips[0] + detection->tips[4]) * 0.5f;
        const auto& mine = m.split[h == 0 ? Hand::kRight : Hand::kLeft];
        const auto& other = m.split[h == 0 ? Hand::kLeft : Hand::kRight];
        if (mine.present &&
            (!other.present || (tips - mine.centroid).norm() < (tips - other.centroid).norm())) {
          in.detection = detection;
        }
      }
    }
    m.hands[h]->track(in, r.hands[static_cast<std::size_t>(h)]);
  }
  m.trackedHandCentre.reset();
  if (handCount == 1 && r.hands.front().tracked) {
    Vec3 sum = Vec3::Zero();
    for (const Vec3& p : r.hands.front().skeletonKeypoints21) sum += p;
    m.trackedHandCentre = sum / static_cast<float>(r.hands.front().skeletonKeypoints21.size());
  }
  r.timeMs =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return r;
}

}  // namespace dynahand::track
