/// @file
/// From a depth frame to the tracker's point cloud (paper: "Sampling from a Depth
/// Sensor", "Boundary Planes"). One CloudPipeline is configured once per camera; each
/// frame, process() fills a reusable CloudFrame:
///
///   1. coarse search: every `coarseStep`-th pixel, range-gated; region growing from the
///      nearest samples finds "the closest, sufficiently large volume" and its image box
///      (with a HandHint, the tracked hand's volume when the closest one does not reach it);
///   2. filtering inside that box only, at the working stride (sampleStride): range gate,
///      3x3 median, optional bilateral, flying-pixel removal at depth edges;
///   3. segmentation: the region grown from the nearest filtered sample across neighbours
///      whose depth step is small, within a hand-sized radius of that nearest point; the
///      arm is where it was cut;
///   4. voxel-grid subsampling of the segmented samples (VoxelGrid);
///   5. boundary planes around the segmented samples (BoundaryPlaneBuilder), leaving out
///      the side where the arm leaves.
/// docs/cloud.md explains each stage and parameter.
///
/// Units: metres, camera frame x right, y down, z forward. Nothing is allocated per frame
/// once a CloudFrame has seen one frame of the pipeline's size.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "dynahand/boundary_planes.h"
#include "dynahand/core.h"
#include "dynahand/depth_frame.h"
#include "dynahand/voxel_grid.h"

namespace dynahand {

/// Stage 2: filtering of the depth samples inside the coarse box.
struct DepthFilterConfig {
  float minDepthM = 0.15f;  ///< range gate: nearer samples are dropped (m)
  float maxDepthM = 2.0f;   ///< range gate: farther samples are dropped (m)
  bool median = true;       ///< 3x3 median (OpenCV), removes speckle and fills 1-pixel holes
  /// Bilateral smoothing (OpenCV, float, 5x5 window). Off by default: it adds 0.15-0.2 ms
  /// per frame here (docs/performance.md), and the voxel centroids already average several
  /// samples each. Its sigmas below.
  bool bilateral = false;
  float bilateralSigmaDepthM = 0.01f;  ///< range sigma (m)
  float bilateralSigmaPixels = 2.0f;   ///< spatial sigma (samples)
  bool removeFlyingPixels = true;      ///< drop pixels cut off from both sides (see below)
};

/// Two neighbouring samples belong to one surface when their depth step is at most
/// jumpM + slope * lateral spacing, the spacing being z * step / f (m). Scaling with
/// the spacing makes the rule the same at any resolution and distance.
struct DepthStepRule {
  float jumpM = 0.01f;  ///< step allowed on a fronto-parallel surface (noise), m
  float slope = 3.0f;   ///< extra step per metre of lateral spacing (surfaces up to ~72 deg)
};

/// Large planes near the hand (a table top, a wall) found on the coarse samples and left out
/// of the segmentation: a hand resting on a table is otherwise one surface with it.
struct SupportPlaneConfig {
  bool enabled = true;  ///< false: no plane is searched
  /// Samples within this distance (m) of a plane are the plane's. A hand on a table shows the
  /// camera its back or its side, which lie 1.5 cm or more above the table top.
  float bandM = 0.01f;
  /// Planes whose samples cover less than this (m^2, as seen by the camera) are not taken: a
  /// flat hand with its forearm covers about 0.04 m^2.
  float minAreaM2 = 0.08f;
  int hypotheses = 48;  ///< planes tried per search (three samples each)
  int maxPlanes = 2;    ///< planes left out per frame, largest first (e.g. a table and a wall)
};

/// A plane n . p = offset in the camera frame (m), n unit and facing the camera.
struct SupportPlane {
  Vec3 normal = -Vec3::UnitZ();  ///< n, unit, toward the camera
  float offset = 0.0f;           ///< m
  float areaM2 = 0.0f;           ///< its coarse samples' area as seen, m^2
};

/// Stages 1 and 3: coarse search and segmentation.
struct SegmentationConfig {
  SupportPlaneConfig supportPlanes;  ///< tables and walls left out
  DepthStepRule step;                ///< when neighbouring samples belong to one surface
  float handRadiusM = 0.18f;         ///< region kept within this distance of its nearest point (m)
  float minAreaM2 = 0.003f;          ///< smaller regions are noise: skip to the next nearest (m^2)
  int maxSeedAttempts = 16;          ///< nearest-first candidates tried before giving up
  int coarseStep = 0;                ///< coarse search stride (pixels); 0 = width / 80, >= 1
  /// A volume reaching within this many pixels of the image border continues out of
  /// view: usually the body or the other arm cut by the frame (a hand held up to the
  /// camera is seen whole). It is taken only when no volume clear of the border starts
  /// within borderPreferenceDepthM behind it. 0 = no preference.
  int borderMarginPixels = 8;
  float borderPreferenceDepthM = 0.1f;  ///< see borderMarginPixels (m)
  /// 2: at working stride 1, regions grow on every other sample (while those are at most one
  /// voxel apart) and the samples between join the region they sit in when on its surface;
  /// a quarter of the growing cost (docs/performance.md), edges at the working resolution,
  /// 4 % of the tracker's time at 320x240 and as accurate (docs/performance.md).
  /// 1: every working sample.
  int growStep = 2;
  /// Two-hand use: also take the next nearest region when its nearest point is within
  /// this depth (m) behind the first one's. 0 = one region only.
  float secondRegionDepthBandM = 0.0f;
  /// The camera's near range (m): nothing nearer is measured. A limb whose nearest point lies
  /// nearer than max(0.30, sensorMinRangeM + 0.05) m and that runs into missing data there while
  /// coming nearer is taken as cut off by the sensor (an arm reaching past a head-mounted
  /// camera) and so attached to the body at that end; the hand is at its other end.
  float sensorMinRangeM = 0.20f;
  /// One hand, with a HandHint (process): when the nearest volume comes no nearer than this
  /// (m) to the tracked hand's centre while some sample does, the volume is grown from that
  /// sample instead (a nearer surface of the same arm, or another one, whose limb end is not
  /// the tracked hand). 0 = hints are not used.
  float hintReachM = 0.06f;
};

/// Where the tracker saw the hand in the last frame (CloudPipeline::process).
struct HandHint {
  Vec3 centre = Vec3::Zero();  ///< m, camera frame: the tracked hand's centre
};

/// Everything a CloudPipeline is configured with (docs/cloud.md).
struct CloudConfig {
  DepthFilterConfig filter;         ///< stage 2: depth filtering
  SegmentationConfig segmentation;  ///< stages 1 and 3: coarse search and segmentation
  float voxelSizeM = 0.005f;        ///< voxel edge (m)
  /// Pixels between the depth samples filtered, segmented and voxelised (the working
  /// resolution). 0 = automatic: the largest stride (<= 4) whose sample spacing at the
  /// hand's depth is at most half a voxel, so every voxel still averages >= 4 samples;
  /// 2 for a hand at 0.55 m in 640x480, 1 in 320x240.
  int sampleStride = 0;
  int maxVoxels = 8192;            ///< per frame (<= 65535); extra samples are dropped and counted
  BoundaryPlaneConfig planes;      ///< stage 5: boundary planes
  float planeMarginPixels = 0.5f;  ///< boundary planes clear the pixel footprint by this much
};

/// An axis-aligned pixel box, half-open: x0 <= u < x1, y0 <= v < y1.
struct PixelBox {
  int x0 = 0;                                          ///< first column
  int y0 = 0;                                          ///< first row
  int x1 = 0;                                          ///< one past the last column
  int y1 = 0;                                          ///< one past the last row
  int width() const { return x1 - x0; }                ///< columns
  int height() const { return y1 - y0; }               ///< rows
  bool empty() const { return x1 <= x0 || y1 <= y0; }  ///< true when it holds no pixel
  /// Whether pixel (u, v) is inside.
  bool contains(int u, int v) const { return u >= x0 && u < x1 && v >= y0 && v < y1; }
};

/// What segmentation found.
struct Segment {
  bool found = false;                ///< false: no hand-sized region (no points)
  int pixelCount = 0;                ///< segmented pixels (mask bits set)
  int sampleCount = 0;               ///< segmented depth samples (about pixels / stride^2)
  float areaM2 = 0.0f;               ///< their surface area as seen by the camera, m^2
  Vec3 nearestPoint = Vec3::Zero();  ///< centre of the hand-sized ball, m
  Vec3 centroid = Vec3::Zero();      ///< mean of the segmented points, m
  /// Where the region was cut at the hand radius (the arm), as a unit vector from the
  /// centroid toward the cut; zero when nothing was cut.
  Vec3 armDirection = Vec3::Zero();
  Vec2 armDirectionImage = Vec2::Zero();  ///< the same in the image (pixels, unit)
  int cutPixelCount = 0;                  ///< connected samples just beyond the radius
  /// Region 1 is a limb attached to the body (it continues out of view, beyond two hand
  /// radii or into the sensor's near range): limbEnd is its free end (m), where the hand is,
  /// the surface point farthest along the surface from every attachment.
  bool limbEndFound = false;
  Vec3 limbEnd = Vec3::Zero();  ///< see limbEndFound; zero when not found, m
  int regionCount = 0;          ///< 1, or 2 with secondRegionDepthBandM
  /// Planes left out of the segmentation (SupportPlaneConfig), largest first.
  std::array<SupportPlane, 2> supportPlanes;
  int supportPlaneCount = 0;  ///< how many of supportPlanes were found, 0-2
};

/// The per-frame output. Reused across frames (buffers keep their capacity).
struct CloudFrame {
  Intrinsics intrinsics;    ///< the pipeline's camera
  float depthScale = 0.0f;  ///< m per raw unit of the source frame

  /// Raw depth copy (height x width), used outside the filtered box.
  std::vector<std::uint16_t> rawDepth;
  PixelBox filterBox;     ///< pixels the filtered samples cover
  int filterStride = 1;   ///< pixels between filtered samples
  int filterColumns = 0;  ///< filtered samples per row
  int filterRows = 0;     ///< rows of filtered samples
  /// Filtered depth samples of filterBox every filterStride pixels, m, 0 = none:
  /// (filterRows x filterColumns), sample (i, j) at pixel (x0 + i * stride, y0 + j * stride).
  std::vector<float> filteredDepthM;
  /// Segmentation mask (height x width): 1 = segmented. Only segmentBox can be non-zero.
  std::vector<std::uint8_t> mask;
  PixelBox segmentBox;  ///< bounding box of the segmented pixels
  Segment segment;      ///< what segmentation found

  /// The voxel cloud, parallel arrays (pointCount):
  std::vector<Vec3> points;       ///< voxel centroids, m, camera frame
  std::vector<int> pointWeights;  ///< depth samples averaged into each point
  std::vector<std::int32_t>
      pointPixels;        ///< pixel index v * width + u of the centroid's projection
  int droppedPoints = 0;  ///< segmented samples lost to a full voxel table

  std::vector<BoundaryPlane> planes;  ///< contain every point (and every segmented pixel)

  std::size_t pointCount() const { return points.size(); }  ///< number of voxel points

  /// Best depth estimate (m) at pixel (u, v): the filtered sample covering it inside
  /// filterBox, range-gated raw elsewhere; 0 = no data (also outside the image).
  float depthAt(int u, int v) const;

  /// Free-space query for the occlusion error: true when the camera ray to p is
  /// observed empty up to p, i.e. p projects into the image onto a pixel with no data or
  /// a depth farther than p.z + toleranceM. Points behind the camera or outside the
  /// image are unknown: false.
  bool isFree(const Vec3& p, float toleranceM = 0.0f) const;

 private:
  friend class CloudPipeline;
  float minDepthM_ = 0.0f;
  float maxDepthM_ = 0.0f;
};

/// Turns depth frames of one camera into CloudFrames (see the file comment).
class CloudPipeline {
 public:
  /// intrinsics must be valid (positive size and focal lengths); config values positive
  /// where they say so (asserted).
  CloudPipeline(const Intrinsics& intrinsics, const CloudConfig& config = {});
  ~CloudPipeline();
  CloudPipeline(CloudPipeline&&) noexcept;             ///< Moves the pipeline.
  CloudPipeline& operator=(CloudPipeline&&) noexcept;  ///< Moves the pipeline.
  CloudPipeline(const CloudPipeline&) = delete;
  CloudPipeline& operator=(const CloudPipeline&) = delete;

  /// Fills `out` from one frame. An error (frame size differs from the intrinsics,
  /// non-positive depth scale, buffer size wrong) leaves `out` empty. A frame with no
  /// hand (e.g. all zeros) is not an error: out.segment.found is false, no points.
  /// hint (optional): where the hand was tracked last frame (SegmentationConfig::hintReachM).
  Status process(const DepthFrame& frame, CloudFrame& out, const HandHint* hint = nullptr);

  const Intrinsics& intrinsics() const;  ///< the camera it was made for
  const CloudConfig& config() const;     ///< the configuration it was made with

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace dynahand
