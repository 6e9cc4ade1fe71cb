// TrackerSettings' fields by their dotted names (setTrackerSetting, namedSettings): what the
// commands' `--set` (track, bench, serve, play) and Python's Tracker(settings=...) take, so
// every setting the docs compare can be tried without a rebuild.
#include <charconv>
#include <cmath>
#include <variant>

#include "dynahand/tracker.h"

namespace dynahand::track {
namespace {

// One field: where it lives in a TrackerSettings, and what it is (as the docs' settings
// tables say it, with its unit).
struct SettingField {
  const char* name;
  std::variant<float& (*)(TrackerSettings&), int& (*)(TrackerSettings&),
               bool& (*)(TrackerSettings&)>
      field;
  const char* description;
};

// A field accessor from a member path: DYNAHAND_FIELD(float, detector.selectionWeight).
#define DYNAHAND_FIELD(type, path) +[](TrackerSettings& s) -> type& { return s.path; }

// clang-format off
const SettingField kFields[] = {
  {"substeps", DYNAHAND_FIELD(int, substeps), "physics steps per simulation per frame"},
  {"pointSubsets", DYNAHAND_FIELD(int, pointSubsets), "interleaved point subsets, one per physics step in turn (1: every point every step)"},
  {"palmPointCap", DYNAHAND_FIELD(int, palmPointCap), "points pulled on the palm, and on the forearm (0: all)"},
  {"stepDt", DYNAHAND_FIELD(float, stepDt), "s per physics step"},
  {"iterations", DYNAHAND_FIELD(int, iterations), "Gauss-Seidel sweeps per step of the simulations"},
  {"relaxIterations", DYNAHAND_FIELD(int, relaxIterations), "bias-removal sweeps per step of the simulations"},
  {"acquisitionSubsteps", DYNAHAND_FIELD(int, acquisitionSubsteps), "physics steps when fitting from a canonical pose"},
  {"acquisitionIterations", DYNAHAND_FIELD(int, acquisitionIterations), "sweeps per step while acquiring"},
  {"acquisitionRelaxIterations", DYNAHAND_FIELD(int, acquisitionRelaxIterations), "bias-removal sweeps per step while acquiring"},
  {"pullForce", DYNAHAND_FIELD(float, pullForce), "N, total surface-row force of a step"},
  {"acquisitionPullForce", DYNAHAND_FIELD(float, acquisitionPullForce), "N, the pull while acquiring"},
  {"boundaryForce", DYNAHAND_FIELD(float, boundaryForce), "N, cap of each boundary row"},
  {"boundaryBand", DYNAHAND_FIELD(float, boundaryBand), "m, boundary rows at hull vertices this close to the body's deepest one"},
  {"surfaceErp", DYNAHAND_FIELD(float, surfaceErp), "fraction of a surface row's gap closed per step, [0, 1]"},
  {"velocityRetention", DYNAHAND_FIELD(float, velocityRetention), "prior motion kept per physics step"},
  {"forearmHoldForce", DYNAHAND_FIELD(float, forearmHoldForce), "N, cap of the row holding the forearm along its axis"},
  {"silhouetteForce", DYNAHAND_FIELD(float, silhouetteForce), "N, fingertip free-space pull (0: off)"},
  {"lostErrorPerBodyM", DYNAHAND_FIELD(float, lostErrorPerBodyM), "m, loss test on the winner's error per body"},
  {"lostAfterFrames", DYNAHAND_FIELD(int, lostAfterFrames), "frames above lostErrorPerBodyM before the hand is lost"},
  {"flipPeriodS", DYNAHAND_FIELD(float, flipPeriodS), "s, finger flip's finger set cycles this often"},
  {"perFrame", DYNAHAND_FIELD(bool, perFrame), "every frame a fresh acquisition"},
  {"scaleSegmentationToHand", DYNAHAND_FIELD(bool, scaleSegmentationToHand), "segmentation ball scaled up with a longer model hand"},
  {"detector.enabled", DYNAHAND_FIELD(bool, detector.enabled), "run the learned detector every frame"},
  {"detector.minConfidence", DYNAHAND_FIELD(float, detector.minConfidence), "keypoints below this confidence are not used"},
  {"detector.minMeanConfidence", DYNAHAND_FIELD(float, detector.minMeanConfidence), "a detection is used when its mean confidence reaches this"},
  {"detector.fitConfidenceExponent", DYNAHAND_FIELD(float, detector.fitConfidenceExponent), "the fit weighs each keypoint by its confidence to this power"},
  {"detector.fitStartPoseWeight", DYNAHAND_FIELD(float, detector.fitStartPoseWeight), "weight of the frame-start pose's keypoints in the fit from that pose"},
  {"detector.engageDistanceM", DYNAHAND_FIELD(float, detector.engageDistanceM), "m, the detector-fit simulation runs when the frame starts farther than this from the keypoints"},
  {"detector.maxOffCloudM", DYNAHAND_FIELD(float, detector.maxOffCloudM), "m, a detection farther than this from the hand's points (median) is not used"},
  {"detector.disagreeDistanceM", DYNAHAND_FIELD(float, detector.disagreeDistanceM), "m, loss test: tracked keypoints this far from the detector's"},
  {"detector.disagreeFrames", DYNAHAND_FIELD(int, detector.disagreeFrames), "loss test: frames in a row beyond disagreeDistanceM"},
  {"detector.replaceMaxErrorRatio", DYNAHAND_FIELD(float, detector.replaceMaxErrorRatio), "loss test: no replacement whose error is more than this times the winner's (0: always)"},
  {"detector.selectionWeight", DYNAHAND_FIELD(float, detector.selectionWeight), "winner's score: error plus this times its keypoints' distance from the detector's (0: the metric alone)"},
  {"detector.objectDistanceM", DYNAHAND_FIELD(float, detector.objectDistanceM), "m, points farther than this from the detected skeleton are left out (0: none)"},
  {"detector.reportBlend", DYNAHAND_FIELD(float, detector.reportBlend), "reported keypoints moved toward the detector's by this times the confidence"},
  {"detector.reportBlendReachM", DYNAHAND_FIELD(float, detector.reportBlendReachM), "m, the blend fades to nothing at this distance"},
  {"detector.shiftedCrops", DYNAHAND_FIELD(int, detector.shiftedCrops), "the detection is the mean over its crop and this many more, shifted (0..4)"},
  {"detector.shiftedCropM", DYNAHAND_FIELD(float, detector.shiftedCropM), "m, the shifted crops' centres this far off along x and y"},
  {"detector.limbEndRadius", DYNAHAND_FIELD(float, detector.limbEndRadius), "hand lengths: a new crop is centred on the points this near the limb's free end (0: off)"},
  {"detector.limbEndCropDistanceM", DYNAHAND_FIELD(float, detector.limbEndCropDistanceM), "m, last frame's detection centres the crop while this near that mean"},
  {"cloud.voxelSizeM", DYNAHAND_FIELD(float, cloud.voxelSizeM), "m, voxel edge"},
  {"cloud.sampleStride", DYNAHAND_FIELD(int, cloud.sampleStride), "pixels between the depth samples used (0: automatic)"},
  {"cloud.maxVoxels", DYNAHAND_FIELD(int, cloud.maxVoxels), "sample points per frame at most"},
  {"cloud.planeMarginPixels", DYNAHAND_FIELD(float, cloud.planeMarginPixels), "pixels, boundary planes clear the pixel footprint by this much"},
  {"cloud.planes.planeCount", DYNAHAND_FIELD(int, cloud.planes.planeCount), "boundary planes' supporting directions"},
  {"cloud.filter.minDepthM", DYNAHAND_FIELD(float, cloud.filter.minDepthM), "m, nearer samples are dropped"},
  {"cloud.filter.maxDepthM", DYNAHAND_FIELD(float, cloud.filter.maxDepthM), "m, farther samples are dropped"},
  {"cloud.filter.median", DYNAHAND_FIELD(bool, cloud.filter.median), "3x3 median filter"},
  {"cloud.filter.bilateral", DYNAHAND_FIELD(bool, cloud.filter.bilateral), "bilateral filter"},
  {"cloud.filter.removeFlyingPixels", DYNAHAND_FIELD(bool, cloud.filter.removeFlyingPixels), "drop pixels cut off from both sides"},
  {"cloud.segmentation.handRadiusM", DYNAHAND_FIELD(float, cloud.segmentation.handRadiusM), "m, region kept within this distance of its nearest point"},
  {"cloud.segmentation.minAreaM2", DYNAHAND_FIELD(float, cloud.segmentation.minAreaM2), "m^2, smaller regions are noise"},
  {"cloud.segmentation.borderMarginPixels", DYNAHAND_FIELD(int, cloud.segmentation.borderMarginPixels), "pixels: a volume this near the image border continues out of view (0: no preference)"},
  {"cloud.segmentation.borderPreferenceDepthM", DYNAHAND_FIELD(float, cloud.segmentation.borderPreferenceDepthM), "m, see borderMarginPixels"},
  {"cloud.segmentation.growStep", DYNAHAND_FIELD(int, cloud.segmentation.growStep), "regions grow on every this-th working sample"},
  {"cloud.segmentation.secondRegionDepthBandM", DYNAHAND_FIELD(float, cloud.segmentation.secondRegionDepthBandM), "m, two hands: the second region up to this far behind the first"},
  {"cloud.segmentation.sensorMinRangeM", DYNAHAND_FIELD(float, cloud.segmentation.sensorMinRangeM), "m, the camera's near range"},
  {"cloud.segmentation.hintReachM", DYNAHAND_FIELD(float, cloud.segmentation.hintReachM), "m, the tracked hand's hint reach (0: hints not used)"},
  {"cloud.segmentation.supportPlanes.enabled", DYNAHAND_FIELD(bool, cloud.segmentation.supportPlanes.enabled), "tables and walls left out"},
  {"cloud.segmentation.supportPlanes.maxPlanes", DYNAHAND_FIELD(int, cloud.segmentation.supportPlanes.maxPlanes), "planes left out per frame"},
};
// clang-format on
#undef DYNAHAND_FIELD

const SettingField* findField(std::string_view name) {
  for (const SettingField& f : kFields)
    if (name == f.name) return &f;
  return nullptr;
}

std::string valueText(const SettingField& f, TrackerSettings& s) {
  if (const auto* get = std::get_if<float& (*)(TrackerSettings&)>(&f.field)) {
    char text[32];
    const auto end = std::to_chars(text, text + sizeof text, (*get)(s));
    return std::string(text, end.ptr);
  }
  if (const auto* get = std::get_if<int& (*)(TrackerSettings&)>(&f.field))
    return std::to_string((*get)(s));
  return std::get<bool& (*)(TrackerSettings&)>(f.field)(s) ? "true" : "false";
}

}  // namespace

Status setTrackerSetting(TrackerSettings& settings, std::string_view name, std::string_view value) {
  const SettingField* f = findField(name);
  if (f == nullptr)
    return Error{"unknown tracker setting '" + std::string(name) +
                 "' (`dynahand settings` lists them)"};
  const auto bad = [&](const char* expected) {
    return Error{"tracker setting " + std::string(name) + ": '" + std::string(value) + "' is not " +
                 expected};
  };
  const char* first = value.data();
  const char* last = value.data() + value.size();
  if (auto* floatField = std::get_if<float& (*)(TrackerSettings&)>(&f->field)) {
    float v = 0.0f;
    const auto [end, ec] = std::from_chars(first, last, v);
    if (ec != std::errc() || end != last || !std::isfinite(v)) return bad("a number");
    (*floatField)(settings) = v;
  } else if (auto* intField = std::get_if<int& (*)(TrackerSettings&)>(&f->field)) {
    int v = 0;
    const auto [end, ec] = std::from_chars(first, last, v);
    if (ec != std::errc() || end != last) return bad("a whole number");
    (*intField)(settings) = v;
  } else {
    bool& field = std::get<bool& (*)(TrackerSettings&)>(f->field)(settings);
    if (value == "true" || value == "1")
      field = true;
    else if (value == "false" || value == "0")
      field = false;
    else
      return bad("true or false");
  }
  return Ok{};
}

Status setTrackerSetting(TrackerSettings& settings, std::string_view assignment) {
  const std::size_t equals = assignment.find('=');
  if (equals == std::string_view::npos)
    return Error{"tracker setting '" + std::string(assignment) + "': expected NAME=VALUE"};
  return setTrackerSetting(settings, assignment.substr(0, equals), assignment.substr(equals + 1));
}

std::vector<NamedSetting> namedSettings(const TrackerSettings& settings) {
  TrackerSettings copy = settings;  // read through the fields' (mutable) accessors
  std::vector<NamedSetting> out;
  out.reserve(std::size(kFields));
  for (const SettingField& f : kFields) out.push_back({f.name, valueText(f, copy), f.description});
  return out;
}

}  // namespace dynahand::track
