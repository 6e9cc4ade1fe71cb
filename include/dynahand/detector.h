/// @file
/// The learned keypoint detector: a small CNN that looks at the segmented hand's depth crop
/// (a fixed-size, depth-normalised window around the hand) and returns the 21 hand keypoints
/// in 3D with a confidence each. The tracker binds them to the model (docs/tracker.md,
/// "Learned detector"); the weights are an ONNX file run with OpenCV's DNN module
/// (models/detector/, docs/detector.md for the model card and training).
///
/// The crop is defined here once, for training data and inference alike:
///  - centre c (camera frame, m), projected to pixel (cu, cv): on the hand, the centre of its
///    keypoints' bounding box (keypointBoxCentre) as the tracker last saw it; otherwise (a
///    first frame, or last frame's detection far from the limb's end) the hand at the limb's
///    free end (limbEndHandCentre), else the segmented points' centroid (with two hands, the
///    hand's cluster centroid);
///  - a square window of kCropSizeM metres at depth c.z, i.e. half-width r = fx * kCropSizeM /
///    (2 c.z) pixels, sampled kCropPixels x kCropPixels (nearest pixel);
///  - value per crop pixel: (z - c.z) / (kCropSizeM / 2) clamped to [-1, 1] where the pixel is
///    segmented and has depth, else +1 (far);
///  - keypoints as (u, v, d): u = (pu - cu) / r, v = (pv - cv) / r, d = (z - c.z) / (kCropSizeM/2).
///  - left hands are mirrored (u -> -u) so the network only sees right hands.
///
/// Units: metres inside; camera frame as OpenCV (x right, y down, z forward).
#pragma once

#include <array>
#include <filesystem>
#include <memory>
#include <span>
#include <vector>

#include "dynahand/cloud.h"
#include "dynahand/core.h"
#include "dynahand/depth_frame.h"

namespace dynahand::detect {

/// Crop side, pixels (the network's input is 1 x kCropPixels x kCropPixels).
inline constexpr int kCropPixels = 64;
/// Crop side in metres at the hand's depth; also the depth window (+- half of it).
inline constexpr float kCropSizeM = 0.30f;
/// Keypoints the detector returns (MediaPipe order: 0 wrist, 1-4 thumb, ... 17-20 pinky).
inline constexpr int kKeypointCount = 21;

/// Where a crop lies in the image and in depth.
struct CropFrame {
  float centreU = 0.0f;     ///< pixel column of the crop centre
  float centreV = 0.0f;     ///< pixel row of the crop centre
  float halfPixels = 0.0f;  ///< half the crop's side, image pixels
  float centreZ = 0.0f;     ///< depth of the crop centre, m
  bool mirrored = false;    ///< u flipped (a left hand seen as a right one)

  /// Camera-frame point (m) of normalised crop coordinates (u, v, d).
  Vec3 toCamera(const Intrinsics& k, const Vec3& uvd) const;
  /// Normalised crop coordinates (u, v, d) of a camera-frame point (m, z > 0).
  Vec3 toCrop(const Intrinsics& k, const Vec3& p) const;
};

/// One crop: the frame and kCropPixels^2 values in [-1, 1], row-major.
struct HandCrop {
  CropFrame frame;            ///< where the crop lies in the image and in depth
  std::vector<float> pixels;  ///< (kCropPixels * kCropPixels)
};

/// The centre of the keypoints' bounding box (m, camera frame): where a crop centred on the
/// hand is centred.
Vec3 keypointBoxCentre(const std::array<Vec3, kKeypointCount>& points);

/// Two hands in one segment (HandSplitter's clusters, m, camera frame): the crop of the hand
/// whose cluster centre is `own` leaves out the pixels whose point lies nearer `other`, as the
/// split labels the cloud's points, so the network sees one hand as in its training crops.
struct CropHandSplit {
  Vec3 own = Vec3::Zero();    ///< this hand's cluster centre, m
  Vec3 other = Vec3::Zero();  ///< the other hand's cluster centre, m
};

/// Fills `out` from a processed cloud frame (its mask, depth and segment centroid). `centre`
/// overrides the centroid (m, camera frame) when given; `split`, when given, leaves the other
/// hand's pixels out. False when nothing is segmented.
bool makeCrop(const CloudFrame& cloud, bool mirrored, HandCrop& out, const Vec3* centre = nullptr,
              const CropHandSplit* split = nullptr);

/// Where a first crop is centred when the segment is a limb attached to the body
/// (CloudFrame::segment.limbEndFound): the mean of `points` (m, camera frame) within radiusM of
/// the limb's free end, which lies on the hand where the centroid lies on the forearm. False,
/// `centre` untouched, when the segment is not a limb or no point lies that near.
bool limbEndHandCentre(const CloudFrame& cloud, std::span<const Vec3> points, float radiusM,
                       Vec3& centre);

/// The detector's output for one crop.
struct DetectedKeypoints {
  bool valid = false;                         ///< the network ran on a crop (false: no detection)
  std::array<Vec3, kKeypointCount> points{};  ///< m, camera frame
  std::array<float, kKeypointCount> confidence{};  ///< [0, 1]: ~exp(-error / 20 mm)
  float meanConfidence = 0.0f;                     ///< the mean of `confidence`
};

/// The network and its buffers. One thread; no allocation per call once warm.
class KeypointDetector {
 public:
  /// Loads an ONNX file (1 x 1 x 64 x 64 input; output 1 x 84: 63 normalised uvd values, then
  /// 21 confidences). Errors name the file: missing, unreadable or of the wrong shape.
  static Result<std::unique_ptr<KeypointDetector>> load(const std::filesystem::path& onnxFile);
  ~KeypointDetector();
  KeypointDetector(const KeypointDetector&) = delete;
  KeypointDetector& operator=(const KeypointDetector&) = delete;

  /// Runs the network on a crop; keypoints returned in the camera frame of `intrinsics`.
  const DetectedKeypoints& detect(const HandCrop& crop, const Intrinsics& intrinsics);
  /// The raw output for a crop: 63 normalised (u, v, d) values and 21 confidences.
  std::span<const float> run(std::span<const float> pixels);

  /// The ONNX file the weights came from.
  const std::filesystem::path& file() const;

 private:
  struct Impl;
  explicit KeypointDetector(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

/// The weights shipped with dynahand: models/detector/detector.onnx under the source tree, or
/// under the install prefix's share/dynahand; the environment variable DYNAHAND_DETECTOR
/// overrides. Empty when none is found.
std::filesystem::path defaultDetectorFile();

}  // namespace dynahand::detect
