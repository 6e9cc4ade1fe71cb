// SyntheticSequence: clip (or pose file) -> model joint angles -> forward kinematics ->
// 21 keypoints + per-body poses (ground truth) -> render surface -> exact depth -> sensor.
#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <string>

#include "clip_library.h"
#include "dynahand/model_fit.h"
#include "dynahand/model_intel.h"
#include "dynahand/synth.h"
#include "scene.h"

namespace dynahand::synth {
namespace {

constexpr float kReferenceWidth = 0.085f;  // m, SurfaceRadii are given for this palm width
constexpr float kForearmPerLength = 1.4f;  // forearm length / hand length (elbow beyond the image)
// Head-mounted playback: the largest angle (rad) between a frame's forearm and the rest
// placement's. A pose file's 21 keypoints leave the retargeted forearm's direction free within
// the wrist's limits; seen from the eyes, a forearm swung further would pass in front of the
// hand or come from above the head.
constexpr float kHeadForearmCone = 30.0f * std::numbers::pi_v<float> / 180.0f;

// `root` (the forearm, +z from elbow to wrist) turned about the wrist by the least rotation that
// brings its axis within `cone` (rad) of `axis`; unchanged when it already is.
Pose withinForearmCone(const Pose& root, const Vec3& axis, float cone) {
  const Vec3 forearm = root.q * Vec3::UnitZ();
  const float angle = std::acos(std::clamp(forearm.dot(axis), -1.0f, 1.0f));
  if (angle <= cone) return root;
  Vec3 normal = forearm.cross(axis);
  if (normal.squaredNorm() < 1e-12f) normal = forearm.unitOrthogonal();
  Pose turned = root;
  turned.q = (Quat(Eigen::AngleAxisf(angle - cone, normal.normalized())) * root.q).normalized();
  return turned;
}

Status validate(const SynthOptions& o) {
  auto bad = [](const std::string& what) { return Status(Error{"synth options: " + what}); };
  if (o.frameCount < 1)
    return bad("frame count must be at least 1 (got " + std::to_string(o.frameCount) + ")");
  if (!(o.framesPerSecond > 0.0f && o.framesPerSecond <= 1000.0f))
    return bad("frames per second must be in (0, 1000]");
  if (!(o.speed > 0.0f && o.speed <= 100.0f)) return bad("speed must be in (0, 100]");
  if (!(o.hand.length >= 0.10f && o.hand.length <= 0.30f))
    return bad("hand length must be in [0.10, 0.30] m");
  if (!(o.hand.width >= 0.05f && o.hand.width <= 0.13f))
    return bad("hand width must be in [0.05, 0.13] m");
  if (!(o.scene.backgroundDistance >= 0.02f && o.scene.backgroundDistance <= 5.0f))
    return bad("background distance must be in [0.02, 5] m");
  if (!(o.scene.tableDrop >= 0.0f && o.scene.tableDrop <= 2.0f))
    return bad("table drop must be in [0, 2] m");
  if (!(o.scene.heldObjectSize >= 0.01f && o.scene.heldObjectSize <= 0.06f))
    return bad("held object size must be in [0.01, 0.06] m");
  if (!(o.scene.handDistance == 0.0f ||
        (o.scene.handDistance >= 0.1f && o.scene.handDistance <= 3.0f)))
    return bad("hand distance must be 0 (auto) or in [0.1, 3] m");
  if (!std::isfinite(o.scene.viewShift.x()) || !std::isfinite(o.scene.viewShift.y()))
    return bad("view shift must be finite");
  if (o.poseStart < 0) return bad("the first pose played must not be negative");
  const auto factorOk = [](float f) { return f >= 0.5f && f <= 1.5f; };
  bool proportionsOk = factorOk(o.proportions.palmThickness);
  for (std::size_t f = 0; f < 5; ++f) {
    proportionsOk = proportionsOk && factorOk(o.proportions.fingerThickness[f]);
    for (float length : o.proportions.boneLength[f])
      proportionsOk = proportionsOk && factorOk(length);
  }
  if (!proportionsOk) return bad("every hand proportion factor must be in [0.5, 1.5]");
  return Ok{};
}

// Joint angles of the default hand for each pose of a pose file (at most `maxPoses`).
Result<std::vector<model::JointAngles>> loadPlayback(const SynthOptions& o,
                                                     const model::ArticulatedModel& hand,
                                                     std::size_t maxPoses) {
  std::vector<model::JointAngles> angles;
  const std::string name = o.poseFile.string();
  if (o.poseFile.extension() == ".pose") {
    const std::filesystem::path modelPath =
        o.intelModelFile.empty() ? o.poseFile.parent_path() / "model_hand.json" : o.intelModelFile;
    Result<model::IntelModel> intel = model::importIntelModel(modelPath);
    if (!intel) return Error{name + ": needs the authors' hand model: " + intel.message()};
    if (!intel->model.hasKeypoints21())
      return Error{modelPath.string() + ": the model has no 21 hand keypoints"};
    Result<std::vector<model::ModelPose>> poses = model::loadIntelPoses(o.poseFile, intel->model);
    if (!poses) return poses.error();
    if (poses->empty()) return Error{name + ": no poses"};
    // Retarget by fitting our hand to their keypoints, each fit starting from the last.
    model::KeypointFitter fitter(hand);
    const std::size_t count = std::min(poses->size(), maxPoses);
    for (std::size_t i = 0; i < count; ++i) {
      model::FitOptions fit;
      if (!angles.empty()) fit.initial = &angles.back();
      Result<model::FitResult> r = fitter.fit21(model::keypoints21(intel->model, (*poses)[i]), fit);
      if (!r) return Error{name + ": pose " + std::to_string(i) + ": " + r.message()};
      angles.push_back(std::move(r->angles));
    }
    return angles;
  }
  Result<model::PoseSequence> poses = model::loadPoseSequence(o.poseFile);
  if (!poses) return poses.error();
  if (poses->frames.empty()) return Error{name + ": no poses"};
  if (Status s = model::checkPoseSequence(*poses, hand); !s)
    return Error{name + ": " + s.message()};
  // Same bodies and joints: the joint angles carry over to a hand of another size.
  for (const model::ModelPose& pose : poses->frames) {
    if (angles.size() == maxPoses) break;
    angles.push_back(model::jointAngles(hand, pose));
  }
  return angles;
}

// The mean root (forearm) placement of the poses frame 0..count-1 plays (from `start`,
// wrapping; each pose once): mean wrist position and the normalised mean of the
// quaternions, each on the first one's side.
Pose meanPlacement(const std::vector<model::JointAngles>& poses, int start, int count) {
  const std::size_t n = std::min(poses.size(), static_cast<std::size_t>(count));
  Vec3 position = Vec3::Zero();
  Eigen::Vector4f q = Eigen::Vector4f::Zero();
  const Quat& reference = poses[static_cast<std::size_t>(start) % poses.size()].root.q;
  for (std::size_t i = 0; i < n; ++i) {
    const Pose& root = poses[(static_cast<std::size_t>(start) + i) % poses.size()].root;
    position += root.p;
    q += (root.q.dot(reference) < 0.0f ? -1.0f : 1.0f) * root.q.coeffs();
  }
  Pose mean;
  mean.p = position / static_cast<float>(n);
  mean.q = Quat(q.w(), q.x(), q.y(), q.z()).normalized();
  return mean;
}

}  // namespace

Result<std::vector<model::JointAngles>> loadPoseAngles(const SynthOptions& options, int maxPoses) {
  if (options.poseFile.empty()) return Error{"synth options: no pose file"};
  const model::ArticulatedModel hand = model::makeDefaultHand(options.hand, model::Side::Right);
  return loadPlayback(
      options, hand,
      maxPoses > 0 ? static_cast<std::size_t>(maxPoses) : std::numeric_limits<std::size_t>::max());
}

struct SyntheticSequence::State {
  SynthOptions options;
  SensorProfile profile;
  std::vector<model::ArticulatedModel> models;  // per hand
  const detail::ClipDefinition* clip = nullptr;
  // Poses played when options.poseFile or poseAngles is set; placed by playbackPlacement.
  std::shared_ptr<const std::vector<model::JointAngles>> playback;
  Pose playbackPlacement;
  Pose rest;                        // right hand's rest placement, camera frame
  std::array<Vec3, 2> shoulders{};  // right, left: where the upper arms end, camera frame
  float surfaceScale = 1.0f;
  SurfaceRadii radii;  // options.surface with options.proportions' thickness factors
  DepthRenderer renderer;
  SensorSimulator sensor;
  // Per-frame buffers (reused).
  SyntheticFrame frame;
  std::vector<HandMotionSample> samples;
  std::vector<RoundCone> surface;

  State(const SynthOptions& o, SensorProfile p)
      : options(o), profile(p), renderer(p.intrinsics), sensor(p, o.seed) {}

  // Joint angles of hand h at frame `index`, root in the camera frame.
  void anglesAt(int index, std::vector<HandMotionSample>& out) const {
    if (playback) {
      out.resize(1);
      out[0].side = model::Side::Right;
      const std::size_t at =
          (static_cast<std::size_t>(options.poseStart) + static_cast<std::size_t>(index)) %
          playback->size();
      out[0].angles = (*playback)[at];
      out[0].angles.root = playbackPlacement * out[0].angles.root;
      if (options.scene.placement == CameraPlacement::HeadMounted)
        out[0].angles.root =
            withinForearmCone(out[0].angles.root, rest.q * Vec3::UnitZ(), kHeadForearmCone);
      return;
    }
    const float time = static_cast<float>(index) / options.framesPerSecond * options.speed;
    detail::sampleClipInto(*clip, time, out);
    for (HandMotionSample& s : out) {
      s.angles.root = rest * s.angles.root;
      if (s.side == model::Side::Left) s.angles = model::mirrorAngles(s.angles);
    }
  }

  // Scene::tableBelowHand: lowers the table where the motion would take a joint nearer to it
  // than kTableClearance (the drop given stays where it is lower already).
  void lowerTableBelowHand() {
    const Vec3 down = detail::downDirection(options.scene.placement);
    const float restHeight = down.dot(rest.p);
    float drop = options.scene.tableDrop;
    std::vector<HandMotionSample> motion;
    HandTruth truth;
    for (int f = 0; f < options.frameCount; ++f) {
      anglesAt(f, motion);
      for (std::size_t h = 0; h < motion.size(); ++h) {
        truthFor(motion[h], static_cast<int>(h), truth);
        for (const Vec3& joint : truth.keypoints)
          drop = std::max(drop, down.dot(joint) - restHeight + kTableClearance);
      }
    }
    options.scene.tableDrop = drop;
  }

  void truthFor(const HandMotionSample& sample, int hand, HandTruth& out) const {
    const model::ArticulatedModel& m = models[static_cast<std::size_t>(hand)];
    out.side = sample.side;
    model::forwardKinematicsInto(m, sample.angles, out.pose);
    out.keypoints = model::keypoints21(m, out.pose);
    applyProportions(options.proportions, out.keypoints);
  }
};

SyntheticSequence::SyntheticSequence(std::unique_ptr<State> state) : state_(std::move(state)) {}
SyntheticSequence::SyntheticSequence(SyntheticSequence&&) noexcept = default;
SyntheticSequence& SyntheticSequence::operator=(SyntheticSequence&&) noexcept = default;
SyntheticSequence::~SyntheticSequence() = default;

Result<SyntheticSequence> SyntheticSequence::create(const SynthOptions& options) {
  if (Status s = validate(options); !s) return s.error();
  Result<SensorProfile> profile = findSensorProfile(options.profile);
  if (!profile) return profile.error();
  Intrinsics& k = profile->intrinsics;
  if (std::fabs(options.scene.viewShift.x()) > static_cast<float>(k.width) ||
      std::fabs(options.scene.viewShift.y()) > static_cast<float>(k.height))
    return Error{"synth options: view shift must be within the image's width and height"};
  k.cx += options.scene.viewShift.x();
  k.cy += options.scene.viewShift.y();
  auto state = std::make_unique<State>(options, *profile);

  int handCount = 1;
  const bool playsPoses = !options.poseFile.empty() || options.poseAngles;
  if (!playsPoses) {
    state->clip = detail::findClip(options.clip);
    if (!state->clip) {
      std::string names;
      for (const ClipInfo& info : clips()) names += (names.empty() ? "" : ", ") + info.name;
      return Error{"unknown clip '" + options.clip + "' (known: " + names + ")"};
    }
    handCount = state->clip->info.handCount;
  }
  state->models.push_back(model::makeDefaultHand(options.hand, model::Side::Right));
  if (handCount == 2)
    state->models.push_back(model::makeDefaultHand(options.hand, model::Side::Left));
  if (options.poseAngles) {
    if (options.poseAngles->empty()) return Error{"synth options: no poses to play"};
    for (const model::JointAngles& a : *options.poseAngles)
      if (a.angles.size() != state->models[0].joints().size())
        return Error{"synth options: the poses to play are not of the default hand"};
    state->playback = options.poseAngles;
  } else if (!options.poseFile.empty()) {
    const auto wanted =
        static_cast<std::size_t>(options.poseStart) + static_cast<std::size_t>(options.frameCount);
    Result<std::vector<model::JointAngles>> played =
        loadPlayback(options, state->models[0], wanted);
    if (!played) return played.error();
    state->playback =
        std::make_shared<const std::vector<model::JointAngles>>(std::move(played).value());
  }

  const float handDistance = detail::resolvedHandDistance(options.scene, state->profile);
  state->rest = detail::restPlacement(options.scene.placement, handDistance);
  for (int side = 0; side < 2; ++side)
    state->shoulders[static_cast<std::size_t>(side)] =
        detail::shoulderPosition(options.scene.placement, side == 1, handDistance);
  if (state->playback && options.scene.placement == CameraPlacement::HeadMounted) {
    // One rigid transform for the whole sequence: the mean forearm placement of the poses
    // played onto the head-mounted rest placement (desk keeps the file's own placement).
    state->playbackPlacement =
        state->rest *
        meanPlacement(*state->playback, options.poseStart, options.frameCount).inverse();
  }
  if (options.scene.table && options.scene.tableBelowHand) state->lowerTableBelowHand();
  const detail::SceneGeometry geometry = detail::sceneGeometry(state->options.scene, handDistance);
  state->renderer.setBackground(geometry.planes, geometry.solids);
  state->surfaceScale = options.hand.width / kReferenceWidth;
  state->radii = scaledRadii(options.surface, options.proportions);
  state->surface.reserve(static_cast<std::size_t>(kMaxHandPrimitives * handCount));
  state->frame.hands.resize(static_cast<std::size_t>(handCount));
  return SyntheticSequence(std::move(state));
}

const SynthOptions& SyntheticSequence::options() const {
  return state_->options;
}
const SensorProfile& SyntheticSequence::profile() const {
  return state_->profile;
}
const Intrinsics& SyntheticSequence::intrinsics() const {
  return state_->profile.intrinsics;
}
int SyntheticSequence::frameCount() const {
  return state_->options.frameCount;
}
int SyntheticSequence::handCount() const {
  return static_cast<int>(state_->models.size());
}
const model::ArticulatedModel& SyntheticSequence::model(int hand) const {
  assert(hand >= 0 && hand < handCount());
  return state_->models[static_cast<std::size_t>(hand)];
}
std::span<const float> SyntheticSequence::exactDepth() const {
  return state_->renderer.depth();
}
std::span<const PixelLabel> SyntheticSequence::labels() const {
  return state_->renderer.labels();
}

HandTruth SyntheticSequence::truth(int index, int hand) const {
  assert(index >= 0 && index < frameCount() && hand >= 0 && hand < handCount());
  std::vector<HandMotionSample> samples;
  state_->anglesAt(index, samples);
  HandTruth truth;
  state_->truthFor(samples[static_cast<std::size_t>(hand)], hand, truth);
  return truth;
}

const SyntheticFrame& SyntheticSequence::frame(int index) {
  assert(index >= 0 && index < frameCount());
  State& s = *state_;
  s.anglesAt(index, s.samples);
  s.frame.index = index;
  s.renderer.clear();
  for (std::size_t h = 0; h < s.samples.size(); ++h) {
    HandTruth& truth = s.frame.hands[h];
    s.truthFor(s.samples[h], static_cast<int>(h), truth);
    HandSkeleton skeleton;
    skeleton.keypoints = truth.keypoints;
    const Pose& forearm = truth.pose.bodies[static_cast<std::size_t>(s.models[h].root())];
    skeleton.elbow =
        forearm.transform(Vec3(0.0f, 0.0f, -kForearmPerLength * s.options.hand.length));
    skeleton.leftHand = truth.side == model::Side::Left;
    skeleton.shoulder = s.shoulders[skeleton.leftHand ? 1 : 0];
    skeleton.scale = s.surfaceScale;
    s.surface.clear();
    buildHandSurface(skeleton, s.radii, s.surface);
    s.renderer.draw(s.surface, h == 0 ? PixelLabel::Hand0 : PixelLabel::Hand1);
    if (h == 0)
      detail::drawHeldObject(s.options.scene, truth.keypoints, skeleton.leftHand, s.surfaceScale,
                             s.renderer);
  }
  s.sensor.apply(s.renderer.depth(), s.renderer.labels(), index,
                 static_cast<double>(index) / static_cast<double>(s.options.framesPerSecond),
                 s.frame.depth);
  return s.frame;
}

}  // namespace dynahand::synth
