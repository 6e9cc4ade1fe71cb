#include "dynahand/tools/bench_suite.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <mutex>
#include <optional>
#include <random>
#include <thread>

#include <time.h>

#include "dynahand/hand_size.h"
#include "dynahand/model_fit.h"
#include "dynahand/synth.h"

namespace dynahand::eval {

namespace {

// 5 s at 30 fps: every default clip at least once through (count is 5 s long; at 2 s a clip
// showed only part of its motion and single items swung by several mm between builds). The
// suite still runs in a few minutes on 2 cores.
constexpr int kDefaultFrames = 150;
constexpr int kQuickFrames = 8;

// Motion suite: frames per clip item (3 s: every one-hand clip at least once through at
// 2.5x speed) and the clips' speed.
constexpr int kMotionFrames = 90;
constexpr float kMotionSpeed = 2.5f;
constexpr float kMotionProportionSpread = 0.15f;
// The objects of the held-object rows.
// The table rows' table: this far (m) below the wrist, which the fingers of a hand that
// reaches down touch; lower where the segment's motion would take the hand into it
// (synth::Scene::tableBelowHand).
constexpr float kTableDropM = 0.08f;
constexpr synth::HeldObject kHeldObjects[] = {synth::HeldObject::Ball, synth::HeldObject::Cylinder,
                                              synth::HeldObject::Box};

// The image-border rows: the scene moved in the image (pixels, x right, y down) so that the
// palm's centre, at about (160, 125) of the 320 x 240 view, lands about 30 pixels from the top,
// the left or the right border, and the fingers or one side of the hand go on out of view;
// the clips take these in turn.
constexpr float kBorderShifts[][2] = {{0.0f, -95.0f}, {-130.0f, 0.0f}, {130.0f, 0.0f}};

// A joint this far (m) or more behind the table or wall its pixel shows is hidden by it.
constexpr float kHiddenBehindSceneM = 0.01f;

// The joints of the last frame rendered that the scene does not hide: whose pixel shows
// neither the held object nor the background (a table, a wall) in front of them. A synthetic
// hand moved by captured motion can pass through a table; what it hides there is not scored.
// outsideTheImage: whether joints outside the image count as hidden too.
std::array<bool, 21> notHiddenByTheScene(const synth::SyntheticSequence& seq,
                                         const synth::SyntheticFrame& frame,
                                         const Keypoints21& keypoints, bool outsideTheImage) {
  const Intrinsics& k = seq.intrinsics();
  std::array<bool, 21> scored;
  scored.fill(true);
  for (std::size_t j = 0; j < keypoints.size(); ++j) {
    if (!(keypoints[j].z() > 0.0f)) continue;
    const Vec2 uv = k.project(keypoints[j]);
    const auto u = static_cast<int>(std::lround(uv.x()));
    const auto v = static_cast<int>(std::lround(uv.y()));
    if (u < 0 || v < 0 || u >= k.width || v >= k.height) {
      scored[j] = !outsideTheImage;
      continue;
    }
    const std::size_t pixel = static_cast<std::size_t>(v) * k.width + u;
    const synth::PixelLabel label = seq.labels()[pixel];
    const float z = frame.depth.metres(u, v);
    scored[j] = label != synth::PixelLabel::HeldObject &&
                !(label == synth::PixelLabel::Background && z > 0.0f &&
                  z < keypoints[j].z() - kHiddenBehindSceneM);
  }
  return scored;
}

// The standard items the ablations are compared with.
bool isAblationBaseline(const SuiteItem& item) {
  return !item.ablation && item.group.empty() && item.profile == "tof" &&
         item.size.name == "medium" && !item.autoInit;
}

double threadCpuMs() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return 1e3 * static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_nsec);
}

}  // namespace

const std::vector<HandSize>& benchHandSizes() {
  // Adult hands: ~5th, 50th and 95th percentile hand length (wrist crease to middle tip).
  static const std::vector<HandSize> kSizes = {
      {"small", {0.165f, 0.075f}}, {"medium", {0.19f, 0.085f}}, {"large", {0.215f, 0.095f}}};
  return kSizes;
}

const std::vector<std::string>& targetedAblationClips() {
  static const std::vector<std::string> kClips = {"fast-translation", "finger-flips",
                                                  "grasp-cylinder"};
  return kClips;
}

std::vector<SuiteItem> standardSuite(const SuiteOptions& options) {
  const int frames =
      options.frames > 0 ? options.frames : (options.quick ? kQuickFrames : kDefaultFrames);
  std::vector<std::string> clipNames = synth::defaultClipSet();
  std::vector<std::string> profiles;
  for (const auto& p : synth::sensorProfiles()) profiles.push_back(p.name);
  std::vector<HandSize> sizes = benchHandSizes();
  if (options.quick) {
    clipNames = {"pinch", "wave"};
    profiles = {"tof", "structured-light"};
    sizes = {benchHandSizes()[1]};
  }
  std::vector<SuiteItem> items;
  for (std::size_t s = 0; s < sizes.size(); ++s) {
    for (std::size_t p = 0; p < profiles.size(); ++p) {
      for (bool autoInit : {false, true}) {
        for (std::size_t c = 0; c < clipNames.size(); ++c) {
          SuiteItem item;
          item.clip = clipNames[c];
          item.profile = profiles[p];
          item.size = sizes[s];
          item.autoInit = autoInit;
          item.frames = frames;
          item.seed = 1 + c + 10 * p + 100 * s;  // the same noise for a clip in every variant
          items.push_back(item);
        }
      }
    }
  }
  // Ablations on tof, medium hand, ground-truth start: each strategy off in turn, then
  // "normal only". Their baseline is the standard tof / medium / gt row.
  const HandSize medium = benchHandSizes()[1];
  const std::size_t tofIndex = static_cast<std::size_t>(
      std::find(profiles.begin(), profiles.end(), "tof") - profiles.begin());
  // variant -1: all strategies, the baseline for the targeted clips (for the default clips
  // the standard tof / medium / gt items are the baseline).
  for (int variant = -1; variant <= track::kStrategyCount; ++variant) {
    SuiteItem base;
    base.ablation = true;
    base.profile = "tof";
    base.size = medium;
    base.frames = frames;
    if (variant < 0) {
      base.variant = "all";
    } else if (variant < track::kStrategyCount) {
      base.variant =
          std::string("no ") + track::strategyName(static_cast<track::StrategyKind>(variant));
      base.tracker.strategies[static_cast<std::size_t>(variant)] = false;
    } else {
      base.variant = "normal only";
      base.tracker.strategies = {true, false, false, false, false};
    }
    const std::size_t mediumIndex = options.quick ? 0 : 1;
    for (std::size_t c = 0; c < clipNames.size() && variant >= 0; ++c) {
      if (options.quick && c > 0) break;  // one clip is enough to exercise the block
      SuiteItem item = base;
      item.clip = clipNames[c];
      item.seed = 1 + c + 10 * tofIndex + 100 * mediumIndex;
      items.push_back(item);
    }
    if (options.quick) continue;
    const auto& targeted = targetedAblationClips();
    for (std::size_t c = 0; c < targeted.size(); ++c) {
      SuiteItem item = base;
      item.targeted = true;
      item.clip = targeted[c];
      item.seed = 1 + clipNames.size() + c + 10 * tofIndex + 100 * mediumIndex;
      items.push_back(item);
    }
  }
  return items;
}

std::vector<int> findCuts(const std::vector<Keypoints21>& keypoints) {
  std::vector<int> cuts;
  for (std::size_t i = 1; i < keypoints.size(); ++i) {
    const Keypoints21& a = keypoints[i - 1];
    const Keypoints21& b = keypoints[i];
    bool cut = (b[0] - a[0]).norm() > kCutWristM;
    for (std::size_t k = 0; k < a.size() && !cut; ++k) cut = (b[k] - a[k]).norm() > kCutKeypointM;
    if (cut) cuts.push_back(static_cast<int>(i));
  }
  return cuts;
}

namespace {

// A stable seed from a name (FNV-1a): the same clip or segment gets the same hand shape in
// every profile, placement and start, so rows compare like with like.
std::uint64_t nameSeed(const std::string& name) {
  std::uint64_t h = 1469598103934665603ull;
  for (unsigned char c : name) h = (h ^ c) * 1099511628211ull;
  return h;
}

// Ground-truth keypoints as a detection: each coordinate plus Gaussian noise of standard
// deviation sigma (m), every confidence 1.
detect::DetectedKeypoints noisyTruth(const Keypoints21& truth, float sigma, std::mt19937& rng) {
  detect::DetectedKeypoints k;
  k.valid = true;
  std::normal_distribution<float> normal(0.0f, 1.0f);
  for (std::size_t j = 0; j < truth.size(); ++j) {
    Vec3 offset = Vec3::Zero();
    if (sigma > 0.0f) offset = sigma * Vec3(normal(rng), normal(rng), normal(rng));
    k.points[j] = truth[j] + offset;
    k.confidence[j] = 1.0f;
  }
  return k;
}

const char* placementName(synth::CameraPlacement p) {
  return p == synth::CameraPlacement::HeadMounted ? "head" : "desk";
}

}  // namespace

namespace {

// What the motion suite's stages share: the clip frames, profiles and placements.
struct MotionPlan {
  HandSize medium = benchHandSizes()[1];
  int clipFrames = kMotionFrames;
  std::vector<std::string> clipNames;  // one-hand clips
  std::vector<std::string> profiles;
  std::array<synth::CameraPlacement, 2> placements = {synth::CameraPlacement::DeskFacing,
                                                      synth::CameraPlacement::HeadMounted};
  bool quick = false;
};

MotionPlan motionPlan(const MotionSuiteOptions& options) {
  MotionPlan plan;
  plan.quick = options.quick;
  plan.clipFrames =
      options.frames > 0 ? options.frames : (options.quick ? kQuickFrames : kMotionFrames);
  for (const synth::ClipInfo& c : synth::clips())
    if (c.handCount == 1) plan.clipNames.push_back(c.name);
  for (const auto& p : synth::sensorProfiles()) plan.profiles.push_back(p.name);
  if (options.quick) {
    plan.clipNames = {"pinch", "wave"};
    plan.profiles = {"tof"};
  }
  return plan;
}

// An item of `group` on `clip` with the medium hand shaped unlike the model (the same shape for
// the same clip or segment name in every row).
SuiteItem motionItem(const MotionPlan& plan, std::string group, std::string clip,
                     const std::string& profile, synth::CameraPlacement placement, bool autoInit,
                     std::uint64_t seed) {
  SuiteItem item;
  item.group = std::move(group);
  item.clip = std::move(clip);
  item.profile = profile;
  item.size = plan.medium;
  item.autoInit = autoInit;
  item.seed = seed;
  item.placement = placement;
  item.proportionSpread = kMotionProportionSpread;
  item.proportionSeed = nameSeed(item.clip);
  return item;
}

// Every one-hand clip at kMotionSpeed, on every profile, placement and start.
void addClipItems(const MotionPlan& plan, MotionSuite& suite) {
  for (std::size_t p = 0; p < plan.profiles.size(); ++p) {
    for (synth::CameraPlacement placement : plan.placements) {
      for (bool autoInit : {false, true}) {
        for (std::size_t c = 0; c < plan.clipNames.size(); ++c) {
          SuiteItem item =
              motionItem(plan,
                         fmt::format("clips x{} / {} / {} / {}", kMotionSpeed, plan.profiles[p],
                                     placementName(placement), autoInit ? "auto" : "gt"),
                         plan.clipNames[c], plan.profiles[p], placement, autoInit, 1 + c + 10 * p);
          item.frames = plan.clipFrames;
          item.speed = kMotionSpeed;
          suite.items.push_back(std::move(item));
        }
      }
    }
  }
}

// Held objects (tof, gt start): the grasping clips with each object.
void addHeldObjectClipItems(const MotionPlan& plan, MotionSuite& suite) {
  for (synth::CameraPlacement placement : plan.placements) {
    for (const char* clip : {"grasp-cylinder", "reach-grasp-lift"}) {
      for (std::size_t o = 0; o < std::size(kHeldObjects); ++o) {
        if (plan.quick && o > 0) continue;
        SuiteItem item = motionItem(plan,
                                    fmt::format("held objects: clips x{} / tof / {} / gt",
                                                kMotionSpeed, placementName(placement)),
                                    clip, "tof", placement, false, 3000 + o);
        item.frames = plan.clipFrames;
        item.speed = kMotionSpeed;
        item.heldObject = kHeldObjects[o];
        suite.items.push_back(std::move(item));
      }
    }
  }
}

// A hand reaching past the image border (tof, gt start): every clip with the scene moved
// toward the top, the left or the right border in turn (kBorderShifts).
void addImageBorderClipItems(const MotionPlan& plan, MotionSuite& suite) {
  for (synth::CameraPlacement placement : plan.placements) {
    for (std::size_t c = 0; c < plan.clipNames.size(); ++c) {
      SuiteItem item = motionItem(plan,
                                  fmt::format("image border: clips x{} / tof / {} / gt",
                                              kMotionSpeed, placementName(placement)),
                                  plan.clipNames[c], "tof", placement, false, 3300 + c);
      item.frames = plan.clipFrames;
      item.speed = kMotionSpeed;
      const auto* shift = kBorderShifts[c % std::size(kBorderShifts)];
      item.viewShift = Vec2(shift[0], shift[1]);
      suite.items.push_back(std::move(item));
    }
  }
}

// The animbank poses for the medium hand and where they jump (cuts between takes).
struct Animbank {
  std::shared_ptr<const std::vector<model::JointAngles>> poses;
  std::vector<int> cuts;
  std::vector<int> bounds;  // 0, the cuts, the pose count: segment g is [bounds[g], bounds[g+1])
};

Result<Animbank> loadAnimbank(const std::filesystem::path& file, const HandSize& size) {
  synth::SynthOptions load;
  load.poseFile = file;
  load.hand = size.dimensions;
  Result<std::vector<model::JointAngles>> angles = synth::loadPoseAngles(load);
  if (!angles) return Error{"animbank: " + angles.message()};
  const model::ArticulatedModel hand = model::makeDefaultHand(size.dimensions);
  std::vector<Keypoints21> keypoints;
  keypoints.reserve(angles->size());
  for (const model::JointAngles& a : *angles)
    keypoints.push_back(model::keypoints21(hand, model::forwardKinematics(hand, a)));
  Animbank animbank;
  animbank.cuts = findCuts(keypoints);
  animbank.bounds = {0};
  animbank.bounds.insert(animbank.bounds.end(), animbank.cuts.begin(), animbank.cuts.end());
  animbank.bounds.push_back(static_cast<int>(angles->size()));
  animbank.poses = std::make_shared<const std::vector<model::JointAngles>>(std::move(*angles));
  return animbank;
}

// An item playing animbank segment g.
SuiteItem segmentItem(const MotionPlan& plan, const Animbank& animbank, int g, std::string group,
                      const std::string& profile, synth::CameraPlacement placement, bool autoInit,
                      std::uint64_t seed) {
  const int first = animbank.bounds[static_cast<std::size_t>(g)];
  const int end = animbank.bounds[static_cast<std::size_t>(g) + 1];
  SuiteItem item = motionItem(plan, std::move(group), fmt::format("animbank {}-{}", first, end - 1),
                              profile, placement, autoInit, seed);
  item.frames = plan.quick ? std::min(end - first, kQuickFrames) : end - first;
  item.poses = animbank.poses;
  item.poseStart = first;
  return item;
}

// Every animbank segment on every profile, placement and start; with held objects; and the
// whole file through its cuts.
void addAnimbankItems(const MotionPlan& plan, const Animbank& animbank, MotionSuite& suite) {
  const int segments = static_cast<int>(animbank.bounds.size()) - 1;
  const int segmentsUsed = plan.quick ? std::min(2, segments) : segments;
  for (std::size_t p = 0; p < plan.profiles.size(); ++p) {
    for (synth::CameraPlacement placement : plan.placements) {
      // The file's own (desk) placement keeps the hand at 0.18-0.55 m: mostly nearer than
      // structured light's 0.5 m minimum range.
      if (plan.profiles[p] == "structured-light" && placement == synth::CameraPlacement::DeskFacing)
        continue;
      for (bool autoInit : {false, true}) {
        for (int g = 0; g < segmentsUsed; ++g) {
          suite.items.push_back(
              segmentItem(plan, animbank, g,
                          fmt::format("animbank segments / {} / {} / {}", plan.profiles[p],
                                      placementName(placement), autoInit ? "auto" : "gt"),
                          plan.profiles[p], placement, autoInit,
                          1000 + static_cast<std::uint64_t>(g) + 100 * p));
        }
      }
    }
  }
  // Held objects: every segment with one of the objects in turn (tof, gt start).
  for (synth::CameraPlacement placement : plan.placements) {
    for (int g = 0; g < segmentsUsed; ++g) {
      SuiteItem item = segmentItem(
          plan, animbank, g,
          fmt::format("held objects: animbank segments / tof / {} / gt", placementName(placement)),
          "tof", placement, false, 3100 + static_cast<std::uint64_t>(g));
      item.heldObject = kHeldObjects[static_cast<std::size_t>(g) % std::size(kHeldObjects)];
      suite.items.push_back(std::move(item));
    }
  }
  // A table close under the hand: every segment (tof, gt start).
  for (synth::CameraPlacement placement : plan.placements) {
    for (int g = 0; g < segmentsUsed; ++g) {
      SuiteItem item = segmentItem(
          plan, animbank, g,
          fmt::format("table: animbank segments / tof / {} / gt", placementName(placement)), "tof",
          placement, false, 3200 + static_cast<std::uint64_t>(g));
      item.tableDropM = kTableDropM;
      suite.items.push_back(std::move(item));
    }
  }
  const int poseCount = static_cast<int>(animbank.poses->size());
  for (synth::CameraPlacement placement : plan.placements) {
    SuiteItem item = motionItem(
        plan, fmt::format("animbank continuous / tof / {} / gt", placementName(placement)),
        "animbank", "tof", placement, false, 2000);
    item.frames = plan.quick && !animbank.cuts.empty() ? std::min(poseCount, animbank.cuts[0] + 10)
                                                       : poseCount;
    item.poses = animbank.poses;
    for (int c : animbank.cuts)
      if (c < item.frames) item.cuts.push_back(c);
    suite.items.push_back(std::move(item));
  }
}

}  // namespace

Result<MotionSuite> motionSuite(const MotionSuiteOptions& options) {
  MotionSuite suite;
  const MotionPlan plan = motionPlan(options);
  addClipItems(plan, suite);
  addHeldObjectClipItems(plan, suite);
  addImageBorderClipItems(plan, suite);
  const std::filesystem::path file = options.data / "intel" / "animbank.pose";
  std::error_code ec;
  if (options.data.empty() || !std::filesystem::is_regular_file(file, ec)) {
    suite.skipped = "animbank rows skipped: " + (options.data.empty()
                                                     ? std::string("no data folder (--data DIR)")
                                                     : file.string() + " not found");
    return suite;
  }
  Result<Animbank> animbank = loadAnimbank(file, plan.medium);
  if (!animbank) return animbank.error();
  suite.animbankPoses = static_cast<int>(animbank->poses->size());
  suite.animbankSegments = static_cast<int>(animbank->bounds.size()) - 1;
  addAnimbankItems(plan, *animbank, suite);
  return suite;
}

namespace {

// The model's pose nearest to a frame's true keypoints (SuiteItemResult::misfitKeypoints):
// fitted from the pose the hand was rendered in, whose keypoints the rendered hand's
// proportions moved. nullopt when the fit fails.
std::optional<Keypoints21> fittedToTruth(const model::ArticulatedModel& handModel,
                                         model::KeypointFitter& fitter,
                                         const model::ModelPose& renderedPose,
                                         const Keypoints21& truth) {
  const model::JointAngles start = model::jointAngles(handModel, renderedPose);
  model::FitOptions options;
  options.initial = &start;
  const Result<model::FitResult> fit = fitter.fit21(truth, options);
  if (!fit) return std::nullopt;
  return model::keypoints21(handModel, model::forwardKinematics(handModel, fit->angles));
}

// Mean joint error (mm) over the frames with a prediction; NaN when there are none.
double meanErrorMm(const Result<KeypointMetrics>& metrics) {
  return metrics && metrics->evaluatedFrames > 0 ? metrics->meanMm
                                                 : std::numeric_limits<double>::quiet_NaN();
}

// Appends `from`'s frames to `to` (one row's items pooled).
void append(SequenceKeypoints& to, const SequenceKeypoints& from) {
  to.groundTruth.insert(to.groundTruth.end(), from.groundTruth.begin(), from.groundTruth.end());
  to.predicted.insert(to.predicted.end(), from.predicted.begin(), from.predicted.end());
  to.scored.insert(to.scored.end(), from.scored.begin(), from.scored.end());
}

}  // namespace

model::HandShape trackerShape(const synth::HandProportions& proportions, TrueShape part) {
  model::HandShape shape;
  if (part == TrueShape::None) return shape;
  for (std::size_t d = 0; d < shape.boneLength.size(); ++d)
    for (std::size_t b = 0; b < shape.boneLength[d].size(); ++b) {
      const bool metacarpal = b == 0;
      if (part == TrueShape::All || (part == TrueShape::Metacarpals && metacarpal) ||
          (part == TrueShape::Phalanges && !metacarpal))
        shape.boneLength[d][b] = proportions.boneLength[d][b];
    }
  if (part == TrueShape::All || part == TrueShape::Thickness) {
    shape.fingerThickness = proportions.fingerThickness;
    shape.palmThickness = proportions.palmThickness;
  }
  return shape;
}

Result<SuiteItemResult> runSuiteItem(const SuiteItem& item) {
  synth::SynthOptions so;
  so.clip = item.clip;
  so.scene.placement = item.placement;
  so.proportions = synth::randomProportions(item.proportionSeed, item.proportionSpread);
  so.poseAngles = item.poses;
  so.poseStart = item.poseStart;
  so.profile = item.profile;
  so.frameCount = item.frames;
  so.seed = item.seed;
  so.speed = item.speed;
  so.hand = item.size.dimensions;
  so.scene.heldObject = item.heldObject;
  so.scene.viewShift = item.viewShift;
  so.scene.table = item.tableDropM > 0.0f;
  if (so.scene.table) {
    so.scene.tableDrop = item.tableDropM;
    so.scene.tableBelowHand = true;
  }
  auto seq = synth::SyntheticSequence::create(so);
  if (!seq) return Error{seq.message()};
  track::TrackerSettings settings = item.tracker;
  settings.keepCandidates = false;  // no pictures here
  settings.cloud.segmentation.sensorMinRangeM = seq->profile().minRange;
  const model::ArticulatedModel& handModel = seq->model(0);
  const model::Side side = handModel.metadata().handedness == model::Handedness::Left
                               ? model::Side::Left
                               : model::Side::Right;
  model::ArticulatedModel shapedModel =
      item.trueShape == TrueShape::None
          ? handModel
          : model::makeDefaultHand(so.hand, side, trackerShape(so.proportions, item.trueShape));
  if (item.handEstimate != HandEstimate::None) {
    std::vector<DepthFrame> head;
    for (int f = 0; f < std::min(item.frames, kHandEstimateFrames); ++f)
      head.push_back(seq->frame(f).depth);
    track::HandSizeOptions options;
    options.tracker = settings;
    options.metacarpals = item.handEstimate == HandEstimate::Metacarpals;
    const std::optional<Keypoints21> start =
        item.autoInit ? std::nullopt : std::optional<Keypoints21>(seq->frame(0).hands[0].keypoints);
    auto estimate = track::estimateHandSize(head, seq->intrinsics(), start, options);
    if (!estimate) return Error{"hand estimate: " + estimate.message()};
    shapedModel = model::makeDefaultHand(estimate->dimensions, side, estimate->shape);
  }
  auto tracker = track::Tracker::create(shapedModel, seq->intrinsics(), settings);
  if (!tracker) return Error{tracker.message()};
  SuiteItemResult result;
  result.item = item;
  result.keypoints.fps = static_cast<double>(so.framesPerSecond);
  std::mt19937 noise(static_cast<std::uint32_t>(nameSeed(item.clip) ^ item.seed));
  model::KeypointFitter misfitFitter(handModel);
  for (int f = 0; f < item.frames; ++f) {
    const synth::SyntheticFrame& frame = seq->frame(f);
    result.misfitKeypoints.predicted.push_back(
        fittedToTruth(handModel, misfitFitter, frame.hands[0].pose, frame.hands[0].keypoints));
    if (f == 0 && !item.autoInit) {
      if (item.handEstimate == HandEstimate::None) {
        (*tracker)->initialize(frame.hands[0].pose);
      } else if (Status s = (*tracker)->initializeFromKeypoints(frame.hands[0].keypoints); !s) {
        return Error{"hand estimate: " + s.message()};  // another model: fitted, as --init gt
      }
    }
    if (item.truthKeypointsNoiseM >= 0.0f)
      (*tracker)->setKeypoints(
          noisyTruth(frame.hands[0].keypoints, item.truthKeypointsNoiseM, noise));
    const double cpuBefore = threadCpuMs();
    const track::TrackResult& r = (*tracker)->track(frame.depth);
    result.frameCpuMs.push_back(threadCpuMs() - cpuBefore);
    const track::HandResult& h = r.hands.front();
    result.frameMs.push_back(r.timeMs);
    result.keypoints.groundTruth.push_back(frame.hands[0].keypoints);
    // Given keypoints come at confidence 1, so the report's blend would copy them: what the
    // tracking makes of them is the skeleton's own keypoints.
    const Keypoints21& tracked =
        item.truthKeypointsNoiseM >= 0.0f ? h.skeletonKeypoints21 : h.keypoints21;
    result.keypoints.predicted.push_back(h.tracked ? std::optional<Keypoints21>(tracked)
                                                   : std::nullopt);
    result.detectorKeypoints.predicted.push_back(
        h.detected ? std::optional<Keypoints21>(h.detectorKeypoints21) : std::nullopt);
    const bool shifted = item.viewShift != Vec2::Zero();
    if (item.heldObject != synth::HeldObject::None || item.tableDropM > 0.0f || shifted)
      result.keypoints.scored.push_back(
          notHiddenByTheScene(*seq, frame, frame.hands[0].keypoints, shifted));
  }
  auto metrics = computeKeypointMetrics(result.keypoints);
  if (!metrics) return Error{metrics.message()};
  result.metrics = std::move(*metrics);
  for (SequenceKeypoints* k : {&result.detectorKeypoints, &result.misfitKeypoints}) {
    k->groundTruth = result.keypoints.groundTruth;
    k->scored = result.keypoints.scored;
    k->fps = result.keypoints.fps;
  }
  result.detectorMeanMm = meanErrorMm(computeKeypointMetrics(result.detectorKeypoints));
  result.misfitMm = meanErrorMm(computeKeypointMetrics(result.misfitKeypoints));
  const std::vector<double>& maxMm = result.metrics.perFrameMaxMm;
  const auto within = [&](std::size_t f) {
    return !std::isnan(maxMm[f]) && maxMm[f] <= kAcquiredMaxJointMm;
  };
  for (std::size_t f = 0; f < maxMm.size(); ++f) {
    if (within(f)) {
      result.framesToAcquire = static_cast<int>(f);
      break;
    }
  }
  for (std::size_t c = 0; c < item.cuts.size(); ++c) {
    const auto from = static_cast<std::size_t>(item.cuts[c]);
    const std::size_t to =
        c + 1 < item.cuts.size() ? static_cast<std::size_t>(item.cuts[c + 1]) : maxMm.size();
    int frames = -1;
    for (std::size_t f = from; f < std::min(to, maxMm.size()); ++f) {
      if (within(f)) {
        frames = static_cast<int>(f - from);
        break;
      }
    }
    result.framesToReacquire.push_back(frames);
  }
  return result;
}

Result<std::vector<SuiteItemResult>> runSuite(const std::vector<SuiteItem>& items, int threads,
                                              const std::function<void(int, int)>& progress,
                                              const std::atomic<bool>* stop) {
  std::vector<std::optional<SuiteItemResult>> slots(items.size());
  std::atomic<std::size_t> next{0};
  std::mutex mutex;  // guards firstError, done and the progress callback
  std::optional<Error> firstError;
  int done = 0;
  auto worker = [&] {
    for (;;) {
      if (stop != nullptr && stop->load()) return;
      const std::size_t i = next.fetch_add(1);
      if (i >= items.size()) return;
      auto r = runSuiteItem(items[i]);
      std::lock_guard<std::mutex> lock(mutex);
      if (!r) {
        if (!firstError)
          firstError = Error{items[i].clip + " / " + items[i].profile + ": " + r.message()};
        continue;
      }
      slots[i] = std::move(*r);
      ++done;
      if (progress) progress(done, static_cast<int>(items.size()));
    }
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < std::max(1, threads); ++t) pool.emplace_back(worker);
  worker();
  for (auto& t : pool) t.join();
  if (firstError) return *firstError;
  std::vector<SuiteItemResult> results;
  for (auto& s : slots) {
    if (s) results.push_back(std::move(*s));
  }
  return results;
}

std::string rowLabel(const SuiteItem& item) {
  if (!item.group.empty()) return item.group;
  if (item.ablation) return "ablation: " + item.variant;
  return fmt::format("{} / {} / {}", item.profile, item.size.name, item.autoInit ? "auto" : "gt");
}

std::vector<SuiteRow> summarizeSuite(const std::vector<SuiteItemResult>& results) {
  std::vector<std::string> order;
  std::map<std::string, std::vector<const SuiteItemResult*>> groups;
  auto add = [&](const std::string& label, const SuiteItemResult& r) {
    if (!groups.contains(label)) order.push_back(label);
    groups[label].push_back(&r);
  };
  for (const auto& r : results) {
    if (!r.item.group.empty()) add(rowLabel(r.item), r);
  }
  for (const auto& r : results) {
    if (!r.item.ablation && r.item.group.empty()) add(rowLabel(r.item), r);
  }
  for (const auto& r : results) {
    if (isAblationBaseline(r.item)) add("ablation: all (= tof / medium / gt)", r);
  }
  for (const auto& r : results) {
    if (r.item.ablation && !r.item.targeted) add(rowLabel(r.item), r);
  }
  std::vector<SuiteRow> rows;
  for (const std::string& label : order) {
    SuiteRow row;
    row.label = label;
    SequenceKeypoints all, detector, misfit;
    std::vector<double> times, cpuTimes;
    double acquireSum = 0;
    int acquired = 0;
    std::vector<double> reacquire;  // never: infinity
    for (const SuiteItemResult* r : groups[label]) {
      ++row.items;
      append(all, r->keypoints);
      append(detector, r->detectorKeypoints);
      append(misfit, r->misfitKeypoints);
      times.insert(times.end(), r->frameMs.begin(), r->frameMs.end());
      cpuTimes.insert(cpuTimes.end(), r->frameCpuMs.begin(), r->frameCpuMs.end());
      for (int frames : r->framesToReacquire) {
        ++row.cuts;
        if (frames < 0) ++row.neverReacquired;
        reacquire.push_back(frames < 0 ? std::numeric_limits<double>::infinity() : frames);
      }
      if (r->item.autoInit) {
        ++row.autoItems;
        if (r->framesToAcquire < 0) {
          ++row.neverAcquired;
        } else {
          acquireSum += r->framesToAcquire;
          ++acquired;
          if (r->framesToAcquire <= kPromptAcquireFrames) ++row.promptlyAcquired;
          row.maxFramesToAcquire = std::max(row.maxFramesToAcquire, r->framesToAcquire);
        }
      }
    }
    row.frames = static_cast<int>(times.size());
    if (auto m = computeKeypointMetrics(all); m) {
      row.meanMm = m->meanMm;
      row.p95Mm = m->p95Mm;
      row.success30 = m->successFraction[2];  // thresholds 10, 20, 30, 40, 50 mm
    }
    const Result<KeypointMetrics> detectorMetrics = computeKeypointMetrics(detector);
    row.detectorMeanMm = meanErrorMm(detectorMetrics);
    if (detectorMetrics && detectorMetrics->visibleFrames > 0)
      row.detectorRan =
          static_cast<double>(detectorMetrics->evaluatedFrames) / detectorMetrics->visibleFrames;
    row.misfitMm = meanErrorMm(computeKeypointMetrics(misfit));
    row.p50Ms = percentile(times, 0.5);
    row.p99Ms = percentile(times, 0.99);
    row.p50CpuMs = percentile(cpuTimes, 0.5);
    double totalMs = 0;
    for (double t : times) totalMs += t;
    row.framesPerSecond = totalMs > 0 ? 1000.0 * row.frames / totalMs : 0.0;
    row.meanFramesToAcquire = acquired > 0 ? acquireSum / acquired : 0.0;
    if (!reacquire.empty()) {
      std::sort(reacquire.begin(), reacquire.end());
      const std::size_t n = reacquire.size();
      row.medianFramesToReacquire =
          n % 2 == 1 ? reacquire[n / 2] : 0.5 * (reacquire[n / 2 - 1] + reacquire[n / 2]);
    }
    rows.push_back(row);
  }
  return rows;
}

namespace {

std::string acquireText(const SuiteRow& r) {
  if (r.autoItems == 0) return "-";
  if (r.autoItems == r.neverAcquired) return fmt::format("never ({})", r.neverAcquired);
  std::string s = fmt::format("{:.1f} / {}", r.meanFramesToAcquire, r.maxFramesToAcquire);
  if (r.neverAcquired > 0) s += fmt::format(", {} never", r.neverAcquired);
  s += fmt::format("; {:.0f}% <= {}", 100.0 * r.promptlyAcquired / r.autoItems,
                   kPromptAcquireFrames);
  return s;
}

}  // namespace

namespace {

std::string reacquireText(const SuiteRow& r) {
  if (r.cuts == 0) return "-";
  std::string s = std::isinf(r.medianFramesToReacquire)
                      ? std::string("never")
                      : fmt::format("{:g}", r.medianFramesToReacquire);
  s += fmt::format(" / {} cuts", r.cuts);
  if (r.neverReacquired > 0) s += fmt::format(", {} never", r.neverReacquired);
  return s;
}

}  // namespace

namespace {

// The detector alone: its mean error and, when it did not run on every frame, on how many.
std::string detectorText(const SuiteRow& r) {
  if (std::isnan(r.detectorMeanMm)) return "-";
  std::string s = fmt::format("{:.1f}", r.detectorMeanMm);
  if (r.detectorRan < 0.995) s += fmt::format(" ({:.0f}%)", 100.0 * r.detectorRan);
  return s;
}

}  // namespace

std::string motionTableText(const std::vector<SuiteRow>& rows) {
  std::string s = fmt::format(
      "{:<44} {:>5} {:>6} {:>8} {:>8} {:>7} {:>11} {:>9} {:>28} {:>22} {:>7}\n", "motion row",
      "items", "frames", "mean mm", "p95 mm", "<=30mm", "detector mm", "misfit mm",
      fmt::format("acquire mean/max; <={}", kPromptAcquireFrames), "re-acquire median", "p50 ms");
  for (const auto& r : rows) {
    s += fmt::format(
        "{:<44} {:>5} {:>6} {:>8.1f} {:>8.1f} {:>6.1f}% {:>11} {:>9.1f} {:>28} {:>22} {:>7.2f}\n",
        r.label, r.items, r.frames, r.meanMm, r.p95Mm, 100.0 * r.success30, detectorText(r),
        r.misfitMm, acquireText(r), reacquireText(r), r.p50Ms);
  }
  return s;
}

std::string motionTableMarkdown(const std::vector<SuiteRow>& rows) {
  std::string s = fmt::format(
      "| motion row | items | frames | mean error (mm) | p95 (mm) | frames max joint <= 30 mm | "
      "detector alone: mean error (mm) | model misfit: mean error (mm) | auto init: frames to "
      "acquire (mean / max; share of items within {}) | frames to re-acquire after a cut (median / "
      "cuts) | p50 ms |\n"
      "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n",
      kPromptAcquireFrames);
  for (const auto& r : rows) {
    s += fmt::format(
        "| {} | {} | {} | {:.1f} | {:.1f} | {:.1f}% | {} | {:.1f} | {} | {} | {:.2f} |\n", r.label,
        r.items, r.frames, r.meanMm, r.p95Mm, 100.0 * r.success30, detectorText(r), r.misfitMm,
        acquireText(r), reacquireText(r), r.p50Ms);
  }
  return s;
}

std::string suiteTableText(const std::vector<SuiteRow>& rows) {
  std::string s =
      fmt::format("{:<40} {:>5} {:>6} {:>8} {:>8} {:>7} {:>22} {:>7} {:>7} {:>7} {:>7}\n",
                  "suite row", "items", "frames", "mean mm", "p95 mm", "<=30mm",
                  fmt::format("acquire mean/max; <={}", kPromptAcquireFrames), "p50 ms", "p99 ms",
                  "CPU p50", "frame/s");
  for (const auto& r : rows) {
    s += fmt::format(
        "{:<40} {:>5} {:>6} {:>8.1f} {:>8.1f} {:>6.1f}% {:>22} {:>7.2f} {:>7.2f} {:>7.2f} "
        "{:>7.1f}\n",
        r.label, r.items, r.frames, r.meanMm, r.p95Mm, 100.0 * r.success30, acquireText(r), r.p50Ms,
        r.p99Ms, r.p50CpuMs, r.framesPerSecond);
  }
  return s;
}

std::string suiteTableMarkdown(const std::vector<SuiteRow>& rows) {
  std::string s = fmt::format(
      "| suite row | items | frames | mean error (mm) | p95 (mm) | frames max joint <= 30 mm | "
      "auto init: frames to acquire (mean / max; share of items within {}) | p50 ms | p99 ms | "
      "p50 CPU ms | frames/s |\n"
      "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n",
      kPromptAcquireFrames);
  for (const auto& r : rows) {
    s += fmt::format(
        "| {} | {} | {} | {:.1f} | {:.1f} | {:.1f}% | {} | {:.2f} | {:.2f} | {:.2f} | {:.1f} |\n",
        r.label, r.items, r.frames, r.meanMm, r.p95Mm, 100.0 * r.success30, acquireText(r), r.p50Ms,
        r.p99Ms, r.p50CpuMs, r.framesPerSecond);
  }
  return s;
}

std::string ablationByClipMarkdown(const std::vector<SuiteItemResult>& results) {
  std::vector<std::string> variants, clips;
  std::map<std::pair<std::string, std::string>, const SuiteItemResult*> cell;
  auto note = [&](const std::string& variant, const SuiteItemResult& r) {
    if (std::find(variants.begin(), variants.end(), variant) == variants.end())
      variants.push_back(variant);
    if (std::find(clips.begin(), clips.end(), r.item.clip) == clips.end())
      clips.push_back(r.item.clip);
    cell[{variant, r.item.clip}] = &r;
  };
  for (const auto& r : results) {
    if (isAblationBaseline(r.item)) note("all", r);
  }
  for (const auto& r : results) {
    if (r.item.ablation) note(r.item.variant, r);
  }
  if (variants.empty()) return {};
  std::string s = "| clip |";
  std::string rule = "| --- |";
  for (const auto& v : variants) {
    s += " " + v + " |";
    rule += " ---: |";
  }
  s += "\n" + rule + "\n";
  for (const auto& clip : clips) {
    s += "| " + clip + " |";
    for (const auto& v : variants) {
      const auto it = cell.find({v, clip});
      s += it == cell.end() ? " - |"
                            : fmt::format(" {:.1f} ({:.0f}%) |", it->second->metrics.meanMm,
                                          100.0 * it->second->metrics.successFraction[2]);
    }
    s += '\n';
  }
  return s;
}

}  // namespace dynahand::eval
