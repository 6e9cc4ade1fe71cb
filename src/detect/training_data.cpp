// Synthetic detector data (dynahand/detector_data.h): one random scene per sample, rendered,
// degraded by a sensor profile, segmented and cropped by the tracker's own code.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <map>
#include <random>
#include <thread>

#include "dynahand/detector_data.h"
#include "dynahand/model.h"
#include "dynahand/model_pose.h"
#include "dynahand/synth.h"
#include "dynahand/synth_render.h"
#include "dynahand/synth_sensor.h"
#include "synth/random.h"

namespace dynahand::detect {

namespace {

constexpr float kForearmPerLength = 1.4f;  // as the synthesiser: elbow beyond the image
// Cosine of the least angle between the forearm (toward the elbow) and the line of sight.
constexpr float kArmTowardCameraCos = 0.9f;
// A head-mounted view (DataOptions::headViewShare of the draws): the forearm comes toward the
// camera, its cosine to the line of sight at least kHeadViewCos (nine head-mounted frames in
// ten lie there). At the default share, with the uniform draws that land there too and the
// redraws below, 46 % of the samples have the wrist-to-knuckle line at least that much toward
// the camera, against 23 % with uniform rotations alone.
constexpr float kHeadViewCos = 0.3f;
// Share of crops centred on the hand (its keypoint box centre, off by kCentreNoiseM per axis,
// at most kCentreNoiseLimitM), as the tracker centres them once it has seen the hand; the rest
// are centred as on a first frame: near the limb's free end, else on the segment centroid.
constexpr float kHandCentredShare = 0.75f;
// First-frame crops at a limb's end: the points within this many hand lengths (wrist to middle
// tip) of it, as the tracker's DetectorSettings::limbEndRadius.
constexpr float kLimbEndRadius = 0.6f;
// A first-frame crop centre farther than this (m) from the palm's centre is on another object.
constexpr float kFirstCentreLimitM = 0.12f;
constexpr float kCentreNoiseM = 0.012f;
constexpr float kCentreNoiseLimitM = 0.035f;
constexpr float kReferenceWidth = 0.085f;  // SurfaceRadii are for this palm width
constexpr std::uint32_t kFormatVersion = 1;
constexpr char kMagic[4] = {'D', 'H', 'K', 'D'};

using Rng = std::mt19937_64;
float uniform(Rng& rng, float a, float b) {
  return std::uniform_real_distribution<float>(a, b)(rng);
}
bool chance(Rng& rng, float p) {
  return uniform(rng, 0.0f, 1.0f) < p;
}
float normal(Rng& rng, float sigma) {
  return std::normal_distribution<float>(0.0f, sigma)(rng);
}

Quat randomRotation(Rng& rng) {
  Quat q(normal(rng, 1.0f), normal(rng, 1.0f), normal(rng, 1.0f), normal(rng, 1.0f));
  if (q.norm() < 1e-6f) return Quat::Identity();
  return q.normalized();
}

// The training clips: every single-hand clip that is not held back.
const std::vector<std::string>& trainingClips() {
  static const std::vector<std::string> kClips = [] {
    std::vector<std::string> out;
    for (const synth::ClipInfo& info : synth::clips()) {
      const auto& held = heldBackClips();
      if (info.handCount == 1 && std::find(held.begin(), held.end(), info.name) == held.end())
        out.push_back(info.name);
    }
    return out;
  }();
  return kClips;
}

// Which finger (0 thumb .. 4 pinky) a joint moves, -1 for the wrist.
std::vector<int> jointFingers(const model::ArticulatedModel& m) {
  static const char* const kNames[5] = {"thumb", "index", "middle", "ring", "pinky"};
  std::vector<int> out;
  for (const model::Joint& j : m.joints()) {
    const std::string& child = m.bodies()[static_cast<std::size_t>(j.child)].name;
    int finger = -1;
    for (int f = 0; f < 5; ++f)
      if (child.rfind(kNames[f], 0) == 0) finger = f;
    out.push_back(finger);
  }
  return out;
}

// Joint angles drawn within the limits: per finger a curl shared by its flexion joints
// (fingers are mostly straight or curled together), abduction and wrist uniform. With
// probability sharedCurlShare every digit's curl lies near one common curl (a grasp).
void randomAngles(const model::ArticulatedModel& m, const std::vector<int>& fingers,
                  float sharedCurlShare, Rng& rng, model::JointAngles& angles) {
  std::array<float, 5> curl{};
  const bool grasp = chance(rng, sharedCurlShare);
  const float shared = uniform(rng, 0.0f, 1.0f);
  for (float& c : curl) {
    if (grasp) {
      c = std::clamp(shared + normal(rng, 0.12f), 0.0f, 1.0f);
    } else {
      const float u = uniform(rng, 0.0f, 1.0f);
      c = chance(rng, 0.5f) ? u * u : 1.0f - u * u;
    }
  }
  for (std::size_t j = 0; j < m.joints().size(); ++j) {
    const model::Joint& joint = m.joints()[j];
    Vec3 a;
    for (int axis = 0; axis < 3; ++axis) {
      const float lo = joint.minAngle[axis], hi = joint.maxAngle[axis];
      float t = uniform(rng, 0.0f, 1.0f);
      if (axis == 0 && fingers[j] >= 0)
        t = std::clamp(curl[static_cast<std::size_t>(fingers[j])] + normal(rng, 0.1f), 0.0f, 1.0f);
      if (axis == 2) t = 0.5f + 0.5f * (t - 0.5f);  // twist: the middle half
      a[axis] = lo + t * (hi - lo);
    }
    angles.angles[j] = a;
  }
}

struct ProfileContext {
  synth::SensorProfile profile;
  synth::DepthRenderer renderer;
  synth::SensorSimulator sensor;
  CloudPipeline pipeline;
  CloudFrame cloud;
  DepthFrame depth;
  explicit ProfileContext(const synth::SensorProfile& p)
      : profile(p), renderer(p.intrinsics), sensor(p, 1), pipeline(p.intrinsics) {}
};

// A worker's reusable state: one pipeline per profile, hand models by size.
struct Worker {
  std::vector<std::unique_ptr<ProfileContext>> profiles;
  std::map<std::pair<int, int>, model::ArticulatedModel> models;  // by (length, width) in mm
  std::vector<synth::RoundCone> surface, solids;
  std::vector<synth::Plane> planes;
  HandCrop crop;
  // Per joint, the finger it moves (jointFingers): the same for every default hand.
  std::vector<int> fingers;

  Worker() {
    for (const synth::SensorProfile& p : synth::sensorProfiles())
      profiles.push_back(std::make_unique<ProfileContext>(p));
  }
  const model::ArticulatedModel& model(float length, float width) {
    const std::pair<int, int> key{static_cast<int>(std::lround(length * 1000.0f)),
                                  static_cast<int>(std::lround(width * 1000.0f))};
    auto it = models.find(key);
    if (it == models.end())
      it = models
               .emplace(key, model::makeDefaultHand({static_cast<float>(key.first) * 0.001f,
                                                     static_cast<float>(key.second) * 0.001f}))
               .first;
    if (fingers.empty()) fingers = jointFingers(it->second);
    return it->second;
  }
};

struct PosedHand {
  synth::HandKeypoints keypoints;
  Vec3 elbow;
};

// A random hand (size, proportions, pose) placed with its palm centre at `target`, turned by
// `rotation`. Sizes are in 5 mm steps (models are cached).
PosedHand randomHand(Worker& w, const DataOptions& o, Rng& rng, const Vec3& target,
                     const Quat& rotation, int& source, float& surfaceScale,
                     synth::SurfaceRadii& radii) {
  const auto [heldLo, heldHi] = heldBackLengthBand();
  float length = 0.0f;
  if (o.split == DataSplit::HeldBack) {
    length = uniform(rng, heldLo, heldHi);
  } else {
    do {
      length = uniform(rng, 0.15f, 0.23f);
    } while (length >= heldLo && length <= heldHi);
  }
  length = std::round(length * 200.0f) / 200.0f;
  const float width = std::round(length * uniform(rng, 0.41f, 0.50f) * 200.0f) / 200.0f;
  const model::ArticulatedModel& m = w.model(length, width);
  model::JointAngles angles = model::zeroAngles(m);
  const auto& clipNames = o.split == DataSplit::HeldBack ? heldBackClips() : trainingClips();
  const float pick = uniform(rng, 0.0f, 1.0f);
  source = o.split == DataSplit::HeldBack ? (pick < 0.5f ? 1 : 2)
                                          : (pick < 0.5f    ? 0
                                             : pick < 0.75f ? 1
                                                            : 2);
  if (source == 0) {
    randomAngles(m, w.fingers, o.sharedCurlShare, rng, angles);
  } else {
    const std::string& clip =
        clipNames[std::uniform_int_distribution<std::size_t>(0, clipNames.size() - 1)(rng)];
    auto samples = synth::sampleClip(clip, m, uniform(rng, 0.0f, 10.0f));
    if (samples && !samples->empty()) angles = (*samples)[0].angles;
    if (source == 2) {
      for (Vec3& a : angles.angles) a += Vec3(normal(rng, 0.2f), normal(rng, 0.1f), 0.0f);
      model::clampToLimits(m, angles);
    }
  }
  angles.root = Pose{};
  model::ModelPose pose = model::forwardKinematics(m, angles);
  synth::HandKeypoints k = model::keypoints21(m, pose);
  const synth::HandProportions proportions = synth::randomProportions(rng(), o.proportionSpread);
  synth::applyProportions(proportions, k);
  radii = synth::scaledRadii(synth::SurfaceRadii{}, proportions);
  surfaceScale = width / kReferenceWidth;
  Vec3 centre = Vec3::Zero();
  for (int i : {0, 5, 9, 13, 17}) centre += k[static_cast<std::size_t>(i)];
  centre /= 5.0f;
  const Pose forearm = pose.bodies[static_cast<std::size_t>(m.root())];
  const Vec3 elbow = forearm.transform(Vec3(0.0f, 0.0f, -kForearmPerLength * length));
  PosedHand out;
  for (std::size_t i = 0; i < k.size(); ++i) out.keypoints[i] = rotation * (k[i] - centre) + target;
  out.elbow = rotation * (elbow - centre) + target;
  return out;
}

void drawHand(Worker& w, ProfileContext& pc, const PosedHand& hand, float scale,
              const synth::SurfaceRadii& radii, synth::PixelLabel label) {
  synth::HandSkeleton skeleton;
  skeleton.keypoints = hand.keypoints;
  skeleton.elbow = hand.elbow;
  skeleton.scale = scale;
  w.surface.clear();
  synth::buildHandSurface(skeleton, radii, w.surface);
  pc.renderer.draw(w.surface, label);
}

// One attempt at a sample; false when the segmentation did not find this hand.
bool attempt(Worker& w, const DataOptions& o, Rng& rng, int index, DataSample& out) {
  const int profileIndex =
      std::uniform_int_distribution<int>(0, static_cast<int>(w.profiles.size()) - 1)(rng);
  ProfileContext& pc = *w.profiles[static_cast<std::size_t>(profileIndex)];
  const Intrinsics& k = pc.profile.intrinsics;
  const float nearest = std::max(0.25f, pc.profile.minRange + 0.12f);
  const float z = uniform(rng, nearest, std::min(0.75f, pc.profile.maxRange - 0.25f));
  // Anywhere in the middle 70 % of the view.
  const float u = uniform(rng, 0.15f, 0.85f) * static_cast<float>(k.width);
  const float v = uniform(rng, 0.15f, 0.85f) * static_cast<float>(k.height);
  const Vec3 target = k.deproject(u, v, z);
  // Any orientation whose forearm does not point straight at the camera: within 25 degrees of
  // it the arm would hide the hand. Forearms coming toward the camera (a head-mounted view, the
  // back of the hand seen over the arm) are included, and drawn more often than uniformly.
  const float leastToward = chance(rng, o.headViewShare) ? kHeadViewCos : -1.0f;
  Quat rotation;
  for (int tries = 0;; ++tries) {
    rotation = randomRotation(rng);
    const Vec3 arm = rotation * Vec3(0.0f, 0.0f, -1.0f);  // palm frame: forearm along -z
    const float toward = arm.dot(-target.normalized());
    if ((toward < kArmTowardCameraCos && toward >= leastToward) || tries > 40) break;
  }
  int source = 0;
  float scale = 1.0f;
  synth::SurfaceRadii radii;
  const PosedHand hand = randomHand(w, o, rng, target, rotation, source, scale, radii);
  // The forearm: keep the arm out of the camera's face (the elbow at least 10 cm deep).
  if (hand.elbow.z() < 0.1f) return false;

  w.planes.clear();
  w.solids.clear();
  if (chance(rng, 0.4f)) {  // a wall behind
    Vec3 n = (Vec3(0, 0, -1) + Vec3(normal(rng, 0.25f), normal(rng, 0.25f), 0)).normalized();
    const float behind = z + uniform(rng, 0.12f, 0.6f);
    w.planes.push_back({n, n.dot(Vec3(0, 0, behind))});
  }
  if (chance(rng, 0.25f)) {  // a table or any surface near the hand, camera on the hand's side
    Vec3 n = randomRotation(rng) * Vec3::UnitX();
    const float gap = uniform(rng, 0.02f, 0.15f);
    float offset = n.dot(target) - gap;
    if (offset >= 0.0f) {
      n = -n;
      offset = n.dot(target) - gap;
    }
    w.planes.push_back({n, offset});
  }
  if (chance(rng, 0.15f)) {  // torso-like blob behind the hand
    const Vec3 c = target + Vec3(normal(rng, 0.1f), normal(rng, 0.1f), uniform(rng, 0.2f, 0.4f));
    w.solids.push_back({c, c + Vec3(0, 0.2f, 0.05f), 0.15f, 0.17f});
  }
  pc.renderer.setBackground(w.planes, w.solids);
  pc.renderer.clear();
  drawHand(w, pc, hand, scale, radii, synth::PixelLabel::Hand0);
  if (chance(rng, o.heldObjectShare)) {  // a held object at the palm: ball, cylinder or box
    const Vec3 palm = hand.keypoints[9] - hand.keypoints[0];
    const Vec3 across = hand.keypoints[5] - hand.keypoints[17];
    const Vec3 normalDir = across.cross(palm).normalized();  // palmar side, right hand
    const float r = uniform(rng, 0.015f, 0.04f);
    const Vec3 c = 0.5f * (hand.keypoints[0] + hand.keypoints[9]) + normalDir * (r + 0.015f);
    if (o.heldObjectBoxes && chance(rng, 1.0f / 3.0f)) {
      // Long side across the palm, tilted a little about the palm's normal.
      const Vec3 side = (Eigen::AngleAxisf(normal(rng, 0.3f), normalDir) * across).normalized();
      synth::OrientedBox box;
      box.centre = c;
      box.axes.col(0) = side;
      box.axes.col(1) = normalDir;
      box.axes.col(2) = side.cross(normalDir);
      box.halfExtents = Vec3(uniform(rng, 0.03f, 0.08f), r, uniform(rng, 0.6f, 1.4f) * r);
      pc.renderer.draw(box, synth::PixelLabel::Background);
    } else {
      synth::RoundCone object{c, c, r, r};
      if (chance(rng, 0.5f)) {
        const Vec3 axis = across.normalized() * uniform(rng, 0.03f, 0.08f);
        object.a = c - axis;
        object.b = c + axis;
      }
      pc.renderer.draw(std::span(&object, 1), synth::PixelLabel::Background);
    }
  }
  if (chance(rng, 0.1f)) {  // another hand beside this one, not nearer
    const Vec3 other = target + Vec3(uniform(rng, -0.25f, 0.25f), uniform(rng, -0.2f, 0.2f),
                                     uniform(rng, 0.02f, 0.25f));
    int otherSource = 0;
    float otherScale = 1.0f;
    synth::SurfaceRadii otherRadii;
    const PosedHand second =
        randomHand(w, o, rng, other, randomRotation(rng), otherSource, otherScale, otherRadii);
    drawHand(w, pc, second, otherScale, otherRadii, synth::PixelLabel::Hand1);
  }
  pc.sensor.apply(pc.renderer.depth(), pc.renderer.labels(), index, 0.0, pc.depth);
  if (!pc.pipeline.process(pc.depth, pc.cloud).ok() || !pc.cloud.segment.found) return false;
  // The segmentation must have found this hand: most segmented pixels are its own and the
  // segment centre is near its palm.
  const auto labels = pc.renderer.labels();
  long mine = 0, all = 0;
  const PixelBox box = pc.cloud.segmentBox;
  for (int y = box.y0; y < box.y1; ++y)
    for (int x = box.x0; x < box.x1; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * static_cast<std::size_t>(k.width) +
                            static_cast<std::size_t>(x);
      if (pc.cloud.mask[i] == 0) continue;
      ++all;
      mine += labels[i] == synth::PixelLabel::Hand0 ? 1 : 0;
    }
  if (all == 0 || static_cast<float>(mine) < 0.7f * static_cast<float>(all)) return false;
  // Where the tracker centres its first crop. For a forearm coming toward the camera the
  // centroid lies on the forearm, the limb's end on the hand.
  Vec3 firstCentre = pc.cloud.segment.centroid;
  limbEndHandCentre(pc.cloud, pc.cloud.points, kLimbEndRadius * model::handLength(hand.keypoints),
                    firstCentre);
  if ((firstCentre - target).norm() > kFirstCentreLimitM) return false;
  Vec3 centre = keypointBoxCentre(hand.keypoints);
  const bool handCentred = chance(rng, kHandCentredShare);
  for (int axis = 0; axis < 3; ++axis)
    centre[axis] += std::clamp(normal(rng, kCentreNoiseM), -kCentreNoiseLimitM, kCentreNoiseLimitM);
  if (!makeCrop(pc.cloud, false, w.crop, handCentred ? &centre : &firstCentre)) return false;
  for (std::size_t i = 0; i < out.uvd.size(); ++i) {
    out.uvd[i] = w.crop.frame.toCrop(k, hand.keypoints[i]);
    if (out.uvd[i].head<2>().cwiseAbs().maxCoeff() > 1.3f) return false;
  }
  out.pixels = w.crop.pixels;
  out.keypoints = hand.keypoints;
  out.frame = w.crop.frame;
  out.profile = profileIndex;
  out.source = source;
  return true;
}

DataSample makeSampleWith(Worker& w, const DataOptions& o, int index) {
  using synth::detail::mix64;
  Rng rng(mix64(mix64(o.seed) ^ static_cast<std::uint64_t>(index)));
  DataSample sample;
  while (!attempt(w, o, rng, index, sample)) {
  }
  return sample;
}

}  // namespace

const std::vector<std::string>& heldBackClips() {
  static const std::vector<std::string> kClips = {"count", "turn-key"};
  return kClips;
}

std::pair<float, float> heldBackLengthBand() {
  return {0.200f, 0.205f};
}

DataSample makeSample(const DataOptions& options, int index) {
  Worker worker;
  return makeSampleWith(worker, options, index);
}

DetectorFigures evaluateDetector(KeypointDetector& detector, const DataOptions& options) {
  Worker worker;
  std::vector<double> errors;
  DetectorFigures f;
  double seconds = 0.0;
  const auto& profiles = synth::sensorProfiles();
  for (int i = 0; i < options.count; ++i) {
    const DataSample s = makeSampleWith(worker, options, i);
    HandCrop crop{s.frame, s.pixels};
    const auto start = std::chrono::steady_clock::now();
    const DetectedKeypoints& d =
        detector.detect(crop, profiles[static_cast<std::size_t>(s.profile)].intrinsics);
    seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    for (std::size_t j = 0; j < s.keypoints.size(); ++j)
      errors.push_back(1000.0 * static_cast<double>((d.points[j] - s.keypoints[j]).norm()));
    f.meanConfidence += static_cast<double>(d.meanConfidence);
  }
  f.samples = options.count;
  if (options.count > 0) {
    double sum = 0.0;
    for (const double e : errors) sum += e;
    f.meanMm = sum / static_cast<double>(errors.size());
    std::sort(errors.begin(), errors.end());
    f.p95Mm = errors[static_cast<std::size_t>(0.95 * static_cast<double>(errors.size() - 1))];
    f.meanConfidence /= options.count;
    f.msPerCrop = 1000.0 * seconds / options.count;
  }
  return f;
}

std::uint8_t dataPixelByte(float pixel) {
  return static_cast<std::uint8_t>(std::lround((pixel + 1.0f) * 127.5f));
}

Status forEachSampleBlock(const DataOptions& options,
                          const std::function<bool(int, std::span<const DataSample>)>& block) {
  if (options.count < 1) return Error{"detector data: count must be at least 1"};
  if (options.threads < 1 || options.threads > 64)
    return Error{"detector data: threads must be 1..64"};
  constexpr int kBlock = 64;
  std::vector<Worker> workers(static_cast<std::size_t>(options.threads));
  std::vector<DataSample> samples(kBlock);
  for (int first = 0; first < options.count; first += kBlock) {
    const int n = std::min(kBlock, options.count - first);
    std::vector<std::thread> threads;
    for (int t = 0; t < options.threads; ++t) {
      threads.emplace_back([&, t] {
        for (int i = t; i < n; i += options.threads)
          samples[static_cast<std::size_t>(i)] =
              makeSampleWith(workers[static_cast<std::size_t>(t)], options, first + i);
      });
    }
    for (std::thread& th : threads) th.join();
    if (!block(first, std::span<const DataSample>(samples.data(), static_cast<std::size_t>(n))))
      break;
  }
  return Ok{};
}

Status writeDataFile(const DataOptions& options, const std::filesystem::path& file,
                     const std::function<void(int, int)>& progress) {
  if (options.count < 1) return Error{"detector data: count must be at least 1"};
  if (options.threads < 1 || options.threads > 64)
    return Error{"detector data: threads must be 1..64"};
  const std::filesystem::path partial = file.string() + ".partial";
  std::ofstream out(partial, std::ios::binary);
  if (!out) return Error{partial.string() + ": cannot write"};
  const std::uint32_t header[4] = {kFormatVersion, static_cast<std::uint32_t>(options.count),
                                   static_cast<std::uint32_t>(kCropPixels),
                                   static_cast<std::uint32_t>(kKeypointCount)};
  out.write(kMagic, 4);
  out.write(reinterpret_cast<const char*>(header), sizeof(header));
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(kCropPixels * kCropPixels));
  const Status made =
      forEachSampleBlock(options, [&](int first, std::span<const DataSample> block) {
        for (const DataSample& s : block) {
          for (std::size_t p = 0; p < bytes.size(); ++p) bytes[p] = dataPixelByte(s.pixels[p]);
          out.write(reinterpret_cast<const char*>(bytes.data()),
                    static_cast<std::streamsize>(bytes.size()));
          std::array<float, 3 * kKeypointCount> uvd{};
          for (std::size_t j = 0; j < s.uvd.size(); ++j)
            for (int a = 0; a < 3; ++a) uvd[3 * j + static_cast<std::size_t>(a)] = s.uvd[j][a];
          out.write(reinterpret_cast<const char*>(uvd.data()), sizeof(uvd));
          const std::int32_t meta[2] = {s.profile, s.source};
          out.write(reinterpret_cast<const char*>(meta), sizeof(meta));
        }
        if (progress) progress(first + static_cast<int>(block.size()), options.count);
        return true;
      });
  if (!made) return made;
  out.close();
  if (!out) return Error{partial.string() + ": write failed"};
  std::error_code ec;
  std::filesystem::rename(partial, file, ec);
  if (ec)
    return Error{file.string() + ": cannot rename from " + partial.string() + ": " + ec.message()};
  return Ok{};
}

}  // namespace dynahand::detect
