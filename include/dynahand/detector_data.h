/// @file
/// Synthetic training and evaluation data for the learned keypoint detector (detector.h):
/// random hands (size, proportions, joint angles within the model's limits, clip poses and
/// perturbations of them), seen from any direction at any place in view by any sensor
/// profile, with walls, tables, held objects and a second hand; each rendered, passed through
/// the cloud pipeline and cropped exactly as the tracker crops at run time. The file format
/// is docs/formats/detector-data.md.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "dynahand/core.h"
#include "dynahand/detector.h"

namespace dynahand::detect {

/// Which poses and hands a set draws from.
enum class DataSplit {
  Train,     ///< training clips and random poses; hand lengths outside the held-back band
  HeldBack,  ///< only held-back clips (heldBackClips()) and hands in the held-back band
};

/// Which samples a data set holds and how they are made.
struct DataOptions {
  int count = 1000;                    ///< samples
  std::uint64_t seed = 1;              ///< sample i is a function of (seed, i) alone
  DataSplit split = DataSplit::Train;  ///< training or held-back poses and hands
  int threads = 1;                     ///< worker threads (the bytes do not depend on it)
  float proportionSpread = 0.15f;      ///< per-bone / per-finger factors in [1 - s, 1 + s]
  float heldObjectShare = 0.15f;       ///< share of samples with an object held at the palm
  /// Held objects may be boxes (a third of them) as well as balls and cylinders; off, the
  /// samples are those of the generator without boxes, byte for byte.
  bool heldObjectBoxes = false;
  /// Share of the random poses whose digits, thumb included, share one curl (a grasp: each
  /// near a common curl); the others curl each digit on its own. Real hands move their
  /// fingers together (neighbouring digits' curls correlate 0.8-0.98 in captured motion), so
  /// a higher share shows the network hidden fingers curled like the visible ones.
  float sharedCurlShare = 0.3f;
  /// Share of the draws seen as from a head-mounted camera: the forearm comes toward the
  /// camera (its direction toward the elbow at least 0.3 in cosine toward it); the others turn
  /// the hand uniformly. The default 0.45 gives 46 % of the samples that view.
  float headViewShare = 0.45f;
};

/// Clips never used for training (the held-back motions).
const std::vector<std::string>& heldBackClips();
/// Hand lengths (m) in [first, second] are never used for training (held-back shapes).
std::pair<float, float> heldBackLengthBand();

/// One sample: the crop and its 21 keypoints in normalised crop coordinates (u, v, d).
struct DataSample {
  std::vector<float> pixels;               ///< (kCropPixels^2) in [-1, 1]
  std::array<Vec3, kKeypointCount> uvd{};  ///< keypoints in crop coordinates (CropFrame::toCrop)
  std::array<Vec3, kKeypointCount> keypoints{};  ///< the same in the camera frame, m
  CropFrame frame;                               ///< where the crop lies
  int profile = 0;                               ///< index into synth::sensorProfiles()
  int source = 0;  ///< 0 random pose, 1 clip pose, 2 perturbed clip pose
};

/// Makes sample `index` of a set (deterministic).
DataSample makeSample(const DataOptions& options, int index);

/// What evaluateDetector measured.
struct DetectorFigures {
  int samples = 0;           ///< samples evaluated
  double meanMm = 0.0,       ///< mean keypoint error, mm
      p95Mm = 0.0,           ///< 95th-percentile keypoint error, mm
      meanConfidence = 0.0;  ///< mean of the detector's mean confidence per crop
  double msPerCrop = 0.0;    ///< network time per crop, ms (one thread)
};
/// The detector on `count` samples of a set: mean and 95th-percentile keypoint error (mm,
/// camera frame) and the mean confidence.
DetectorFigures evaluateDetector(KeypointDetector& detector, const DataOptions& options);

/// A sample's crop pixel (in [-1, 1]) as the data file stores it: one byte, round((p + 1) 127.5).
std::uint8_t dataPixelByte(float pixel);

/// Makes samples 0 .. options.count - 1 in blocks, each block in parallel on options.threads
/// workers (each reusing its renderers and hand models), and hands every block to
/// `block(first, samples)` in order: samples[i] is sample first + i. Stops with the error of a
/// bad option, or as soon as `block` returns false (then returns Ok).
Status forEachSampleBlock(const DataOptions& options,
                          const std::function<bool(int, std::span<const DataSample>)>& block);

/// Writes `options.count` samples to `file` (format: docs/formats/detector-data.md).
/// progress(done, total) after each block of samples when given.
Status writeDataFile(const DataOptions& options, const std::filesystem::path& file,
                     const std::function<void(int, int)>& progress = {});

}  // namespace dynahand::detect
