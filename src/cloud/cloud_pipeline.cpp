#include <algorithm>
#include <cassert>
#include <cmath>
#include <numbers>
#include <string>

#include "cloud/depth_filter.h"
#include "cloud/limb_end.h"
#include "cloud/region_grow.h"
#include "dynahand/cloud.h"

namespace dynahand {

using cloud::CellLabel;
using cloud::DepthGrid;
using cloud::GrownRegion;

namespace {

constexpr float kCoarseRadiusFactor = 1.1f;
constexpr int kMaxBoxRetries = 2;
constexpr int kCandidateRounds = 3;
// A limb is explored this many hand radii around its nearest point: far enough to see the
// forearm leave toward the body and the hand end free.
constexpr float kLimbRadiusFactor = 2.0f;
// A ball moved toward a limb's free end stops with the end this far (in hand radii) from
// its centre.
constexpr float kEndInsideBall = 0.75f;
// The limb is explored again from its free end at most this many times, while the end moves
// more than kLimbEndMoveFactor hand radii.
constexpr int kLimbEndRounds = 2;
constexpr float kLimbEndMoveFactor = 0.5f;
// A limb cut off by the sensor's near range is cut within this depth (m) of its nearest point.
constexpr float kNearCutDepthM = 0.03f;
// ... and nearer than this (m), or than kNearCutAboveRangeM beyond the sensor's near range
// (SegmentationConfig::sensorMinRangeM) when that is farther: a hand tracked that near is rare,
// and a hole in a hand farther away is missing data, not a cut (the surface that a cut ends
// comes within a centimetre or two of the near range; 10 cm took holes in fingers pointing at
// a structured-light camera 0.55-0.6 m away for cuts).
constexpr float kNearCutMaxDepthM = 0.30f;
constexpr float kNearCutAboveRangeM = 0.05f;
// Pieces of a hand broken up by missing data (fingers seen edge-on by a structured-light
// camera), in metres: taken together as one volume when at most kPieceDepthM behind the nearest
// of them (the depth of a hand seen edge-on, fingers curled); joining a volume taken when at
// most kPieceFrontM in front of its nearest point (a finger held out towards the camera; a
// speck farther in front is something else) and kFragmentDepthM behind it (about level).
constexpr float kPieceDepthM = 0.06f;
constexpr float kPieceFrontM = 0.15f;
constexpr float kFragmentDepthM = 0.02f;
// Pieces smaller than this share of minAreaM2 are specks (flying pixels, noise): no part of
// anything.
constexpr float kFragmentMinShare = 0.05f;

// Widens region's cell box to hold piece's too.
void includeBox(GrownRegion& region, const GrownRegion& piece) {
  region.minI = std::min(region.minI, piece.minI);
  region.maxI = std::max(region.maxI, piece.maxI);
  region.minJ = std::min(region.minJ, piece.minJ);
  region.maxJ = std::max(region.maxJ, piece.maxJ);
}

// Nearest integer for x >= -0.5 (pixel coordinates), without a libm call.
int roundToInt(float x) {
  return static_cast<int>(x + 0.5f);
}

template <int N>
Eigen::Matrix<float, N, 1> normalisedOrZero(const Eigen::Matrix<float, N, 1>& v) {
  const float n = v.norm();
  return n > 0.0f ? Eigen::Matrix<float, N, 1>(v / n) : Eigen::Matrix<float, N, 1>::Zero();
}

}  // namespace

struct CloudPipeline::Impl {
  Intrinsics k;
  CloudConfig config;
  int coarseStep = 1;
  VoxelGrid voxels;
  BoundaryPlaneBuilder planeBuilder;
  cloud::FilterScratch filterScratch;
  cloud::RegionGrower coarseGrower;
  cloud::RegionGrower fineGrower;
  cloud::LimbEndFinder limbEnd;
  std::vector<float> coarseDepth;        // (coarse height x coarse width), m
  std::vector<std::uint8_t> coarseNear;  // coarse labels dilated by one cell
  std::vector<int> boxColumnCell;        // (box width) coarse column of each box column
  std::vector<int> boxRowCell;           // (box height) coarse row of each box row
  std::vector<Vec2> hullPoints;          // row extremes of the segment, normalised image plane
  std::vector<float> segmentDepth;       // every other working sample of the box, m (see run)
  std::vector<float> boxColumnX;         // (box width) x / z of each box column
  std::vector<VoxelGrid::Key> rowKeys;   // (box width) voxel of each sample of a row
  std::vector<int> columnVoxel;          // (box width) voxel of the last run over each column
  // The fine pass's pieces passed over as too small: the region and its cells (a range of
  // fragmentCells), to join the volume taken when they lie within its ball.
  struct Fragment {
    GrownRegion region;
    std::size_t begin, end;
  };
  bool isSpeck(const Fragment& f) const {
    return f.region.areaM2 < kFragmentMinShare * config.segmentation.minAreaM2;
  }
  // Whether piece f joins a volume whose nearest point is `nearest`: not a speck, within the
  // hand's ball, at most kPieceFrontM in front of that point and `behindM` behind it.
  bool joins(const Fragment& f, const Vec3& nearest, float behindM) const {
    const float dz = f.region.nearestPoint.z() - nearest.z();
    return !isSpeck(f) &&
           (f.region.nearestPoint - nearest).norm() <= config.segmentation.handRadiusM &&
           dz >= -kPieceFrontM && dz <= behindM;
  }
  std::vector<Fragment> fragments;
  std::vector<std::int32_t> fragmentCells;
  std::vector<const Fragment*> joining;  // mergePieces' scratch

  Impl(const Intrinsics& intrinsics, const CloudConfig& cfg)
      : k(intrinsics), config(cfg), voxels(cfg.voxelSizeM, cfg.maxVoxels) {
    // At most one piece per seed attempt, and a fine grid's cells once (more are not kept).
    fragments.reserve(static_cast<std::size_t>(std::max(1, cfg.segmentation.maxSeedAttempts)));
    joining.reserve(fragments.capacity());
    fragmentCells.reserve(static_cast<std::size_t>(intrinsics.width) *
                          static_cast<std::size_t>(std::max(0, intrinsics.height)));
  }

  // The pieces skipped so far (fragments) that make a volume together: the nearest one that
  // is not a speck and those joining it (joins, kPieceDepthM behind at most), their cells
  // within its ball, each counted once, reaching minAreaM2. Labels them `label` in fineGrower
  // and writes their region (no cut: no arm direction); false, labels unchanged, otherwise.
  // The hand seen edge-on in missing data, which would otherwise lose to a forearm or body
  // behind it.
  bool mergePieces(CellLabel label, GrownRegion& region);
  void sampleCoarse(const DepthFrame& frame, DepthGrid& grid);
  // True when the coarse region's cell box reaches within borderMarginPixels of the
  // image border.
  bool atBorder(const DepthGrid& grid, const GrownRegion& r) const {
    const int margin = config.segmentation.borderMarginPixels;
    if (margin <= 0) return false;
    return grid.originU + r.minI * grid.step < margin ||
           grid.originV + r.minJ * grid.step < margin ||
           grid.originU + r.maxI * grid.step >= k.width - margin ||
           grid.originV + r.maxJ * grid.step >= k.height - margin;
  }
  // The free end (m) of the limb that the coarse volume r, grown from seed, belongs to
  // (LimbEndFinder); false when r is no limb attached to the body.
  bool findLimbEnd(const DepthGrid& grid, int seed, const GrownRegion& r, Vec3& end);
  Status run(const DepthFrame& frame, CloudFrame& out);
};

bool CloudPipeline::Impl::findLimbEnd(const DepthGrid& grid, int seed, const GrownRegion& r,
                                      Vec3& end) {
  const SegmentationConfig& seg = config.segmentation;
  const float coarseRadius = seg.handRadiusM * kCoarseRadiusFactor;
  // More than half the ball's cross-section is a body, not a limb (as in RegionGrower::grow).
  if (r.areaM2 > 0.5f * std::numbers::pi_v<float> * coarseRadius * coarseRadius) return false;
  const float limbRadius = kLimbRadiusFactor * seg.handRadiusM;
  // A near cut is where the limb is nearest (within kNearCutDepthM of its nearest point) and
  // near the camera (nearCutMax).
  const float nearCutMax = std::max(kNearCutMaxDepthM, seg.sensorMinRangeM + kNearCutAboveRangeM);
  const float nearCut = std::min(r.nearestPoint.z() + kNearCutDepthM, nearCutMax);
  int cell = limbEnd.find(grid, k, seed, seg.step, limbRadius, seg.borderMarginPixels, nearCut);
  if (cell < 0) return false;
  end = grid.point(k, cell % grid.width, cell / grid.width);
  // A forearm seen along its length (a head-mounted camera, the elbow nearest) may be longer
  // than the ball: the hand then leaves the ball too and the end found lies between it and the
  // border. Explored again from that end, the ball holds the hand and the fingers end free.
  for (int round = 0; round < kLimbEndRounds; ++round) {
    const int next =
        limbEnd.find(grid, k, cell, seg.step, limbRadius, seg.borderMarginPixels, nearCut);
    if (next < 0) break;
    const Vec3 nextEnd = grid.point(k, next % grid.width, next / grid.width);
    const bool moved = (nextEnd - end).norm() > kLimbEndMoveFactor * seg.handRadiusM;
    cell = next;
    end = nextEnd;
    if (!moved) break;
  }
  return true;
}

CloudPipeline::CloudPipeline(const Intrinsics& intrinsics, const CloudConfig& config)
    : impl_(std::make_unique<Impl>(intrinsics, config)) {
  // Region growing packs cell coordinates into 16 bits each.
  assert(intrinsics.width < 32768 && intrinsics.height < 32768 && "image too large");
  assert(intrinsics.width > 0 && intrinsics.height > 0 && intrinsics.fx > 0.0f &&
         intrinsics.fy > 0.0f && "intrinsics must be valid");
  const SegmentationConfig& s = config.segmentation;
  assert(s.handRadiusM > 0.0f && s.minAreaM2 >= 0.0f && s.maxSeedAttempts > 0 && s.coarseStep >= 0);
  assert((s.growStep == 1 || s.growStep == 2) && "growStep is 1 or 2");
  assert(config.filter.minDepthM < config.filter.maxDepthM);
  impl_->coarseStep = s.coarseStep > 0 ? s.coarseStep : std::max(1, intrinsics.width / 80);
  const auto pixels = static_cast<std::size_t>(intrinsics.width) * intrinsics.height;
  const auto coarseCells = static_cast<std::size_t>(intrinsics.width / impl_->coarseStep + 1) *
                           static_cast<std::size_t>(intrinsics.height / impl_->coarseStep + 1);
  impl_->filterScratch.reserve(pixels);
  impl_->coarseGrower.reserve(coarseCells, intrinsics.width, intrinsics.height);
  impl_->limbEnd.reserve(coarseCells, intrinsics.width, intrinsics.height);
  impl_->fineGrower.reserve(pixels, intrinsics.width, intrinsics.height);
  impl_->coarseDepth.reserve(coarseCells);
  impl_->coarseNear.reserve(coarseCells);
  impl_->boxColumnCell.reserve(static_cast<std::size_t>(intrinsics.width));
  impl_->boxRowCell.reserve(static_cast<std::size_t>(intrinsics.height));
  impl_->hullPoints.reserve(2 * static_cast<std::size_t>(intrinsics.height));
  impl_->segmentDepth.reserve(pixels / 4 + static_cast<std::size_t>(intrinsics.width));
  impl_->boxColumnX.reserve(static_cast<std::size_t>(intrinsics.width));
  impl_->rowKeys.reserve(static_cast<std::size_t>(intrinsics.width));
  impl_->columnVoxel.reserve(static_cast<std::size_t>(intrinsics.width));
  // Voxel keys are computed without range checks: every range-gated point must fit.
  [[maybe_unused]] const float maxX =
      std::max(intrinsics.cx, static_cast<float>(intrinsics.width) - intrinsics.cx);
  [[maybe_unused]] const float maxY =
      std::max(intrinsics.cy, static_cast<float>(intrinsics.height) - intrinsics.cy);
  assert(impl_->voxels.inRange(config.filter.maxDepthM *
                               std::max({1.0f, maxX / intrinsics.fx, maxY / intrinsics.fy})) &&
         "voxel size too small for the depth range");
}

CloudPipeline::~CloudPipeline() = default;
CloudPipeline::CloudPipeline(CloudPipeline&&) noexcept = default;
CloudPipeline& CloudPipeline::operator=(CloudPipeline&&) noexcept = default;

const Intrinsics& CloudPipeline::intrinsics() const {
  return impl_->k;
}
const CloudConfig& CloudPipeline::config() const {
  return impl_->config;
}

Status CloudPipeline::process(const DepthFrame& frame, CloudFrame& out) {
  const Intrinsics& k = impl_->k;
  out.points.clear();
  out.pointWeights.clear();
  out.pointPixels.clear();
  out.planes.clear();
  out.segment = {};
  out.droppedPoints = 0;
  out.filterBox = {};
  out.filterStride = 1;
  out.filterColumns = 0;
  out.filterRows = 0;
  out.filteredDepthM.clear();
  // Only last frame's segment box can hold mask bits.
  const int lastWidth = out.intrinsics.width;
  for (int v = out.segmentBox.y0; v < out.segmentBox.y1; ++v) {
    auto row = out.mask.begin() + static_cast<std::ptrdiff_t>(v) * lastWidth;
    std::fill(row + out.segmentBox.x0, row + out.segmentBox.x1, std::uint8_t{0});
  }
  out.segmentBox = {};
  if (frame.width != k.width || frame.height != k.height) {
    return Error{"depth frame is " + std::to_string(frame.width) + " x " +
                 std::to_string(frame.height) + " but the camera intrinsics are " +
                 std::to_string(k.width) + " x " + std::to_string(k.height)};
  }
  const auto pixels = static_cast<std::size_t>(k.width) * k.height;
  if (frame.depth.size() != pixels) {
    return Error{"depth frame holds " + std::to_string(frame.depth.size()) + " values, expected " +
                 std::to_string(k.width) + " x " + std::to_string(k.height) + " = " +
                 std::to_string(pixels)};
  }
  if (!std::isfinite(frame.depthScale) || frame.depthScale <= 0.0f) {
    return Error{"depth scale " + std::to_string(frame.depthScale) +
                 " is not a positive number of metres per unit"};
  }
  return impl_->run(frame, out);
}

bool CloudPipeline::Impl::mergePieces(CellLabel label, GrownRegion& region) {
  const SegmentationConfig& seg = config.segmentation;
  const auto lead = std::find_if(fragments.begin(), fragments.end(),
                                 [&](const Fragment& f) { return !isSpeck(f); });
  if (lead == fragments.end()) return false;
  const Vec3 centre = lead->region.nearestPoint;
  joining.clear();        // the pieces that join the lead one (itself included), decided once
  float estimate = 0.0f;  // pieces may overlap: an upper bound
  for (const Fragment& f : fragments) {
    if (!joins(f, centre, kPieceDepthM)) continue;
    joining.push_back(&f);
    estimate += f.region.areaM2;
  }
  if (estimate < seg.minAreaM2) return false;
  auto relabel = [&](CellLabel to) {
    float area = 0.0f;
    for (const Fragment* f : joining)
      area += fineGrower.labelCellsWithin(fragmentCells.data() + f->begin, f->end - f->begin, to,
                                          centre, seg.handRadiusM);
    return area;
  };
  const float area = relabel(label);
  if (area < seg.minAreaM2) {  // overlapping pieces: not a volume after all
    relabel(cloud::kTried);    // as they were (every piece was passed over)
    return false;
  }
  GrownRegion merged = lead->region;
  merged.areaM2 = area;
  merged.cellCount = 0;
  merged.pointSum = Vec3::Zero();
  merged.pixelSum = Vec2::Zero();
  merged.cutCount = 0;
  merged.cutPointSum = Vec3::Zero();
  merged.cutPixelSum = Vec2::Zero();
  for (const Fragment* f : joining) {
    merged.cellCount += f->region.cellCount;
    includeBox(merged, f->region);
  }
  region = merged;
  return true;
}

void CloudPipeline::Impl::sampleCoarse(const DepthFrame& frame, DepthGrid& grid) {
  const int step = coarseStep;
  grid.step = step;
  grid.originU = step / 2;
  grid.originV = step / 2;
  grid.width = (k.width - grid.originU + step - 1) / step;
  grid.height = (k.height - grid.originV + step - 1) / step;
  coarseDepth.resize(static_cast<std::size_t>(grid.width) * grid.height);
  const float scale = frame.depthScale;
  const float lo = config.filter.minDepthM;
  const float hi = config.filter.maxDepthM;
  for (int j = 0; j < grid.height; ++j) {
    const std::uint16_t* src =
        frame.depth.data() + static_cast<std::size_t>(grid.originV + j * step) * k.width;
    float* dst = coarseDepth.data() + static_cast<std::size_t>(j) * grid.width;
    for (int i = 0; i < grid.width; ++i) {
      const float z = static_cast<float>(src[grid.originU + i * step]) * scale;
      dst[i] = z >= lo && z <= hi ? z : 0.0f;
    }
  }
  grid.depth = coarseDepth.data();
}

Status CloudPipeline::Impl::run(const DepthFrame& frame, CloudFrame& out) {
  const SegmentationConfig& seg = config.segmentation;
  const auto pixels = static_cast<std::size_t>(k.width) * k.height;
  // --- output buffers (allocated on the first frame only) ---
  out.intrinsics = k;
  out.depthScale = frame.depthScale;
  out.minDepthM_ = config.filter.minDepthM;
  out.maxDepthM_ = config.filter.maxDepthM;
  out.rawDepth.assign(frame.depth.begin(), frame.depth.end());
  if (out.mask.size() != pixels) out.mask.assign(pixels, 0);
  out.filteredDepthM.reserve(pixels);
  out.points.reserve(static_cast<std::size_t>(config.maxVoxels));
  out.pointWeights.reserve(static_cast<std::size_t>(config.maxVoxels));
  out.pointPixels.reserve(static_cast<std::size_t>(config.maxVoxels));
  out.planes.reserve(static_cast<std::size_t>(config.planes.planeCount));

  // --- 1. coarse search for the closest, sufficiently large volume ---
  DepthGrid coarse;
  sampleCoarse(frame, coarse);
  coarseGrower.reset(coarse, k);
  // A coarse volume can fail at full resolution (e.g. a speckle cluster whose coarse area
  // was overestimated): it is retired and the search goes on with the next candidate.
  GrownRegion fineRegion[2];
  bool fineFound[2] = {false, false};
  PixelBox box;
  int stride = 1;
  int segmentFactor = 1;  // segmentation samples every segmentFactor working samples
  int regionCount = 0;
  Vec3 handEnd = Vec3::Zero();
  bool haveHandEnd = false;
  for (int round = 0; round < kCandidateRounds && !fineFound[0]; ++round) {
    // The coarse ball is wider than the hand radius: the full-resolution nearest point
    // (the final ball's centre) differs from the coarse one by up to a few cm, and the
    // filter box must hold the whole final region.
    const float coarseRadius = seg.handRadiusM * kCoarseRadiusFactor;
    regionCount = 0;
    GrownRegion first;
    // Nearest-first; a candidate at the image border is remembered and passed over (see
    // SegmentationConfig::borderMarginPixels), and used when nothing better follows.
    int borderSeed = -1;
    float borderDepth = 0.0f;
    int firstSeed = -1;
    int attempts = 0;
    while (regionCount == 0 && attempts++ < seg.maxSeedAttempts) {
      const float depthLimit = borderSeed >= 0 ? borderDepth + seg.borderPreferenceDepthM : 0.0f;
      const int seed = coarseGrower.nearestFreeCell(depthLimit);
      if (seed < 0) break;
      const GrownRegion r = coarseGrower.grow(seed, seg.step, coarseRadius, seg.minAreaM2);
      if (r.areaM2 < seg.minAreaM2 || r.inFrontOfSurface) {
        coarseGrower.reject();
        continue;
      }
      // Every volume at the border is passed over (a table or wall reaching the border nearer
      // than the hand, below an arm that does too); the nearest of them is kept.
      if (atBorder(coarse, r)) {
        if (borderSeed < 0) {
          borderSeed = seed;
          borderDepth = r.nearestPoint.z();
        }
        coarseGrower.reject();
        continue;
      }
      coarseGrower.accept(cloud::kRegion1);
      first = r;
      firstSeed = seed;
      regionCount = 1;
    }
    if (regionCount == 0 && borderSeed >= 0) {
      coarseGrower.reset(coarse, k);  // forget the passed-over labels
      first = coarseGrower.grow(borderSeed, seg.step, coarseRadius, seg.minAreaM2);
      coarseGrower.accept(cloud::kRegion1);
      firstSeed = borderSeed;
      regionCount = 1;
    }
    if (regionCount == 0) return Ok{};  // no hand: valid, empty
    haveHandEnd = findLimbEnd(coarse, firstSeed, first, handEnd);
    int minI = first.minI, maxI = first.maxI, minJ = first.minJ, maxJ = first.maxJ;
    if (seg.secondRegionDepthBandM > 0.0f) {
      attempts = 0;
      while (regionCount == 1 && attempts++ < seg.maxSeedAttempts) {
        const int seed = coarseGrower.nearestFreeCell(
            first.nearestPoint.z() + seg.secondRegionDepthBandM, &first.nearestPoint, coarseRadius);
        if (seed < 0) break;
        const GrownRegion r = coarseGrower.grow(seed, seg.step, coarseRadius, seg.minAreaM2);
        if (r.areaM2 >= seg.minAreaM2 && !r.inFrontOfSurface && !r.touchesEarlierRegion) {
          coarseGrower.accept(cloud::kRegion2);
          regionCount = 2;
          minI = std::min(minI, r.minI);
          maxI = std::max(maxI, r.maxI);
          minJ = std::min(minJ, r.minJ);
          maxJ = std::max(maxJ, r.maxJ);
        } else {
          coarseGrower.reject();
        }
      }
    }

    // --- 2. filter only the box around the coarse regions ---
    // Margin: a coarse cell covers step pixels; the median and flying-pixel tests need one
    // more pixel each.
    const int step = coarse.step;
    const int margin = 2 * step + 2;
    box.x0 = std::max(0, coarse.originU + minI * step - margin);
    box.y0 = std::max(0, coarse.originV + minJ * step - margin);
    box.x1 = std::min(k.width, coarse.originU + maxI * step + margin + 1);
    box.y1 = std::min(k.height, coarse.originV + maxJ * step + margin + 1);

    // Working resolution: samples no closer than half a voxel at the hand's depth.
    const float pixelPitch = first.nearestPoint.z() / std::min(k.fx, k.fy);  // m
    stride = config.sampleStride;
    if (stride <= 0) {
      stride = std::clamp(static_cast<int>(0.5f * config.voxelSizeM / pixelPitch), 1, 4);
    }
    // Region growing costs per sample and needs fewer of them than the voxels: with growStep
    // 2, at stride 1 it takes every other sample while those stay within one voxel of each
    // other (a finger is then still >= 3 samples wide). The voxels take every working sample.
    segmentFactor =
        seg.growStep == 2 && stride == 1 && 2.0f * pixelPitch <= config.voxelSizeM ? 2 : 1;
    const int segmentStride = stride * segmentFactor;

    // --- 3. full-resolution segmentation, seeded inside each coarse region ---
    // With two regions, each pixel knows which coarse region its cell (or a neighbouring
    // cell: cells are sampled at their centre, so edges may disagree) belongs to.
    const bool twoRegions = regionCount == 2;
    if (twoRegions) {
      const std::vector<std::uint8_t>& coarseLabels = coarseGrower.labels();
      coarseNear.assign(coarseLabels.size(), 0);
      for (int j = 0; j < coarse.height; ++j) {
        for (int i = 0; i < coarse.width; ++i) {
          const std::uint8_t label = coarseLabels[static_cast<std::size_t>(j) * coarse.width + i];
          if (label != cloud::kRegion1 && label != cloud::kRegion2) continue;
          for (int dj = std::max(0, j - 1); dj <= std::min(coarse.height - 1, j + 1); ++dj) {
            for (int di = std::max(0, i - 1); di <= std::min(coarse.width - 1, i + 1); ++di) {
              std::uint8_t& near = coarseNear[static_cast<std::size_t>(dj) * coarse.width + di];
              if (near == 0) near = label;
            }
          }
        }
      }
    }
    // Filtering and growing run on the box; a region that reaches a box edge (not an
    // image edge) was cut by the box, so the box is widened and the pass repeated.
    for (int pass = 0;; ++pass) {
      out.filterBox = box;
      cloud::filterBox(frame, box, stride, config.filter, seg.step, k.fx, k.fy, filterScratch,
                       out.filteredDepthM);

      // The segmentation grid: the working samples, or every other one of them.
      const int bw = cloud::samplesAlong(box.width(), segmentStride);
      const int bh = cloud::samplesAlong(box.height(), segmentStride);
      const float* segmentGrid = out.filteredDepthM.data();
      if (segmentFactor > 1) {
        const int workingColumns = cloud::samplesAlong(box.width(), stride);
        segmentDepth.resize(static_cast<std::size_t>(bw) * bh);
        for (int v = 0; v < bh; ++v) {
          const float* src = out.filteredDepthM.data() +
                             static_cast<std::size_t>(v * segmentFactor) * workingColumns;
          float* dst = segmentDepth.data() + static_cast<std::size_t>(v) * bw;
          for (int u = 0; u < bw; ++u) dst[u] = src[u * segmentFactor];
        }
        segmentGrid = segmentDepth.data();
      }
      // Coarse cell column / row of each box column / row.
      boxColumnCell.resize(static_cast<std::size_t>(bw));
      boxRowCell.resize(static_cast<std::size_t>(bh));
      for (int u = 0; u < bw; ++u) {
        boxColumnCell[static_cast<std::size_t>(u)] =
            std::min(coarse.width - 1, (box.x0 + u * segmentStride) / step);
      }
      for (int v = 0; v < bh; ++v) {
        boxRowCell[static_cast<std::size_t>(v)] =
            std::min(coarse.height - 1, (box.y0 + v * segmentStride) / step);
      }

      DepthGrid fine;
      fine.depth = segmentGrid;
      fine.width = bw;
      fine.height = bh;
      fine.originU = box.x0;
      fine.originV = box.y0;
      fine.step = segmentStride;
      fineGrower.reset(fine, k);
      fragments.clear();
      fragmentCells.clear();
      fineFound[0] = fineFound[1] = false;
      // The coarse pass accepted these volumes; at full resolution a filtered speck may still
      // be nearest (e.g. a fingertip in front of the palm), so small regions are skipped too.
      for (int r = 0; r < regionCount; ++r) {
        const auto label = static_cast<std::uint8_t>(r == 0 ? cloud::kRegion1 : cloud::kRegion2);
        attempts = 0;
        while (!fineFound[r] && attempts++ < seg.maxSeedAttempts) {
          // Region 1 may start anywhere in the box but in region 2's cells: when its coarse
          // volume splits at full resolution (a fingertip in front of the palm), the palm
          // beside it is still the nearest large volume. Region 2 starts in its own cells.
          const int seed =
              !twoRegions
                  ? fineGrower.nearestFreeCell()
                  : fineGrower.nearestFreeCellWhere([&](int u, int v) {
                      const std::uint8_t coarseLabel = coarseNear
                          [static_cast<std::size_t>(boxRowCell[static_cast<std::size_t>(v)]) *
                               coarse.width +
                           static_cast<std::size_t>(boxColumnCell[static_cast<std::size_t>(u)])];
                      return label == cloud::kRegion1 ? coarseLabel != cloud::kRegion2
                                                      : coarseLabel == cloud::kRegion2;
                    });
          if (seed < 0) break;
          GrownRegion g = fineGrower.grow(seed, seg.step, seg.handRadiusM, seg.minAreaM2);
          const Vec3 toNearest = g.nearestPoint - handEnd;
          if (r == 0 && haveHandEnd && toNearest.norm() > seg.handRadiusM) {
            // The ball around the nearest sample leaves out the limb's free end: that sample
            // is on a forearm pointing at the camera. The ball moves toward the free end
            // until it holds it with a quarter radius to spare.
            const Vec3 centre =
                handEnd + toNearest.normalized() * (kEndInsideBall * seg.handRadiusM);
            const int endSeed = fineGrower.closestFreeCell(centre);
            if (endSeed >= 0)
              g = fineGrower.grow(endSeed, seg.step, seg.handRadiusM, seg.minAreaM2);
          }
          if (g.areaM2 >= seg.minAreaM2 && !g.inFrontOfSurface) {
            fineGrower.accept(static_cast<CellLabel>(label));
            fineRegion[r] = g;
            fineFound[r] = true;
            // Pieces passed over as too small that lie within this volume's ball, in front
            // of it or about as near: a hand broken up by missing data (fingers seen edge-on
            // with a structured-light camera), whose pieces belong to it.
            if (r == 0 && !twoRegions) {
              for (const Fragment& f : fragments) {
                if (!joins(f, g.nearestPoint, kFragmentDepthM)) continue;
                // Only its cells within the region's ball (the hand-radius rule), and only
                // those not in the region already (it may have grown into the piece).
                GrownRegion& taken = fineRegion[r];
                taken.areaM2 += fineGrower.labelCellsWithin(
                    fragmentCells.data() + f.begin, f.end - f.begin, static_cast<CellLabel>(label),
                    g.nearestPoint, seg.handRadiusM);
                includeBox(taken, f.region);  // a piece cut by the box widens it
              }
            }
          } else {
            // Recorded only while it fits the reserved buffers (no allocation per frame).
            bool piece = r == 0 && !twoRegions && !g.inFrontOfSurface &&
                         fragments.size() < fragments.capacity();
            if (piece) {
              Fragment f{g, fragmentCells.size(), 0};
              piece = fineGrower.appendLastRegion(fragmentCells);
              f.end = fragmentCells.size();
              if (piece) fragments.push_back(f);
            }
            fineGrower.reject();
            // Pieces that together make a volume are taken as one (mergePieces).
            if (piece && mergePieces(static_cast<CellLabel>(label), fineRegion[r]))
              fineFound[r] = true;
          }
        }
      }
      if (pass == kMaxBoxRetries || !fineFound[0]) break;
      const int extra = std::max(box.width(), box.height()) / 2;
      PixelBox wider = box;
      for (int r = 0; r < 2; ++r) {
        if (!fineFound[r]) continue;
        const GrownRegion& g = fineRegion[r];
        if (g.minI == 0 && box.x0 > 0) wider.x0 = std::max(0, box.x0 - extra);
        if (g.minJ == 0 && box.y0 > 0) wider.y0 = std::max(0, box.y0 - extra);
        if (g.maxI == bw - 1 && box.x1 < k.width) wider.x1 = std::min(k.width, box.x1 + extra);
        if (g.maxJ == bh - 1 && box.y1 < k.height) wider.y1 = std::min(k.height, box.y1 + extra);
      }
      if (wider.x0 == box.x0 && wider.y0 == box.y0 && wider.x1 == box.x1 && wider.y1 == box.y1) {
        break;
      }
      box = wider;
    }
    if (!fineFound[0]) coarseGrower.retireAccepted();
  }
  if (!fineFound[0]) return Ok{};
  const int bw = cloud::samplesAlong(box.width(), stride);
  const int bh = cloud::samplesAlong(box.height(), stride);
  out.filterStride = stride;
  out.filterColumns = bw;
  out.filterRows = bh;

  // --- 4. mask, voxel grid and hull points in one scan (row-major: deterministic) ---
  voxels.clear();
  hullPoints.clear();
  const std::vector<std::uint8_t>& fineLabels = fineGrower.labels();
  const float invFx = 1.0f / k.fx;
  const float invFy = 1.0f / k.fy;
  // Each sample stands for the stride x stride pixel block around it (offset stride / 2).
  const int blockOffset = stride / 2;
  PixelBox segBox{k.width, k.height, 0, 0};
  int maskPixels = 0;
  int segmentedSamples = 0;
  Vec3 segmentedSum = Vec3::Zero();  // m
  boxColumnX.resize(static_cast<std::size_t>(bw));
  for (int u = 0; u < bw; ++u) {
    boxColumnX[static_cast<std::size_t>(u)] =
        (static_cast<float>(box.x0 + u * stride) - k.cx) * invFx;
  }
  rowKeys.resize(static_cast<std::size_t>(bw));
  columnVoxel.assign(static_cast<std::size_t>(bw), -1);
  // Voxels are met in runs along a row: a run's points are summed here and added at once.
  // The run's first column usually held the same voxel one row up: that voxel is the hint
  // that spares the voxel table's lookup (cache misses).
  VoxelGrid::Run run;
  bool runOpen = false;
  int runBegin = 0;  // first column of the run
  int runEnd = 0;    // one past its last column
  const auto closeRun = [&] {
    voxels.endRun(run);
    std::fill(columnVoxel.begin() + runBegin, columnVoxel.begin() + runEnd, run.voxel);
    runOpen = false;
  };
  // With segmentFactor 2 a working sample takes the label of the segmentation sample at the
  // top left of its 2 x 2 group when it lies on the same surface (the step rule between
  // segmentation neighbours): silhouette edges stay at the working resolution.
  const int segmentShift = segmentFactor == 2 ? 1 : 0;
  const int segmentColumns = cloud::samplesAlong(box.width(), stride * segmentFactor);
  const float* segmentGrid = segmentFactor == 2 ? segmentDepth.data() : out.filteredDepthM.data();
  const float handRadius2 = seg.handRadiusM * seg.handRadiusM;
  const float segmentSpacing =
      static_cast<float>(stride * segmentFactor) / std::min(k.fx, k.fy);  // m per m of depth
  for (int v = 0; v < bh; ++v) {
    const int pv = box.y0 + v * stride;
    const std::size_t segmentRow = static_cast<std::size_t>(v >> segmentShift) * segmentColumns;
    const std::uint8_t* labelRow = fineLabels.data() + segmentRow;
    const float* segmentDepthRow = segmentGrid + segmentRow;
    const bool segmentSampleRow = (v & segmentShift) == 0;
    const float* depthRow = out.filteredDepthM.data() + static_cast<std::size_t>(v) * bw;
    const int blockV0 = std::max(0, pv - blockOffset);
    const int blockV1 = std::min(k.height, pv - blockOffset + stride);
    const float ny = (static_cast<float>(pv) - k.cy) * invFy;
    int rowMin = -1;
    int rowMax = -1;
    voxels.keysOfRow(boxColumnX.data(), ny, depthRow, bw, rowKeys.data());
    // Segmented samples [spanBegin, u) in a row: their blocks make one pixel span.
    int spanBegin = -1;
    const auto closeSpan = [&](int spanEnd) {
      const int pixel0 = std::max(0, box.x0 + spanBegin * stride - blockOffset);
      const int pixel1 = std::min(k.width, box.x0 + (spanEnd - 1) * stride - blockOffset + stride);
      for (int mv = blockV0; mv < blockV1; ++mv) {
        std::uint8_t* maskRow = out.mask.data() + static_cast<std::size_t>(mv) * k.width;
        std::fill(maskRow + pixel0, maskRow + pixel1, std::uint8_t{1});
      }
      maskPixels += (blockV1 - blockV0) * (pixel1 - pixel0);
      spanBegin = -1;
    };
    for (int u = 0; u < bw; ++u) {
      const std::uint8_t label = labelRow[u >> segmentShift];
      const float z = depthRow[u];
      bool segmented = label == cloud::kRegion1 || label == cloud::kRegion2;
      if (segmented && !(segmentSampleRow && (u & segmentShift) == 0)) {
        const float zs = segmentDepthRow[u >> segmentShift];
        const Vec3 p(boxColumnX[static_cast<std::size_t>(u)] * z, ny * z, z);
        segmented = z > 0.0f &&
                    std::fabs(z - zs) <= cloud::maxDepthStep(seg.step, zs, segmentSpacing) &&
                    (p - fineRegion[label - 1].nearestPoint).squaredNorm() <= handRadius2;
      }
      if (!segmented) {
        if (spanBegin >= 0) closeSpan(u);
        continue;
      }
      if (spanBegin < 0) spanBegin = u;
      ++segmentedSamples;
      const int pu = box.x0 + u * stride;
      const Vec3 p(boxColumnX[static_cast<std::size_t>(u)] * z, ny * z, z);
      const VoxelGrid::Key key = rowKeys[static_cast<std::size_t>(u)];
      segmentedSum += p;
      if (!runOpen || key != run.key) {
        if (runOpen) closeRun();
        run = voxels.beginRun(key, pv * k.width + pu, columnVoxel[static_cast<std::size_t>(u)]);
        runOpen = true;
        runBegin = u;
      }
      VoxelGrid::addToRun(run, p);
      runEnd = u + 1;
      if (rowMin < 0) rowMin = pu;
      rowMax = pu;
    }
    if (spanBegin >= 0) closeSpan(bw);
    if (runOpen) closeRun();  // runs end with the row: their columns are in it
    if (rowMin < 0) continue;
    hullPoints.emplace_back((static_cast<float>(rowMin) - k.cx) * invFx, ny);
    if (rowMax != rowMin) hullPoints.emplace_back((static_cast<float>(rowMax) - k.cx) * invFx, ny);
    segBox.x0 = std::min(segBox.x0, std::max(0, rowMin - blockOffset));
    segBox.x1 = std::max(segBox.x1, std::min(k.width, rowMax - blockOffset + stride));
    segBox.y0 = std::min(segBox.y0, blockV0);
    segBox.y1 = blockV1;
  }
  out.segmentBox = segBox;
  out.droppedPoints = voxels.droppedPoints();
  const int voxelCount = voxels.voxelCount();
  for (int i = 0; i < voxelCount; ++i) {
    const Vec3 c = voxels.centroid(i);
    out.points.push_back(c);
    out.pointWeights.push_back(voxels.count(i));
    const Vec2 pixel = k.project(c);
    const int pu = std::clamp(roundToInt(pixel.x()), 0, k.width - 1);
    const int pv = std::clamp(roundToInt(pixel.y()), 0, k.height - 1);
    out.pointPixels.push_back(pv * k.width + pu);
  }

  // --- 5. segment summary; the arm is where region 1 was cut at the hand radius ---
  Segment& s = out.segment;
  s.found = true;
  s.regionCount = fineFound[1] ? 2 : 1;
  s.nearestPoint = fineRegion[0].nearestPoint;
  s.pixelCount = maskPixels;
  s.sampleCount = segmentedSamples;
  s.areaM2 = fineRegion[0].areaM2;
  if (fineFound[1]) s.areaM2 += fineRegion[1].areaM2;
  s.centroid = segmentedSum / static_cast<float>(segmentedSamples);
  s.limbEndFound = haveHandEnd;
  s.limbEnd = haveHandEnd ? handEnd : Vec3::Zero();
  const GrownRegion& hand = fineRegion[0];
  s.cutPixelCount = hand.cutCount;
  if (hand.cutCount > 0) {
    const auto cuts = static_cast<float>(hand.cutCount);
    const auto cells = static_cast<float>(hand.cellCount);
    s.armDirection = normalisedOrZero<3>(hand.cutPointSum / cuts - hand.pointSum / cells);
    s.armDirectionImage = normalisedOrZero<2>(hand.cutPixelSum / cuts - hand.pixelSum / cells);
  }

  // --- 6. boundary planes around the segmented pixels ---
  BoundaryPlaneConfig planeConfig = config.planes;
  // The planes go through the samples; the mask blocks reach blockOffset pixels beyond.
  planeConfig.margin +=
      (config.planeMarginPixels + static_cast<float>(blockOffset)) / std::min(k.fx, k.fy);
  const Vec2 armInPlane(s.armDirectionImage.x() * invFx, s.armDirectionImage.y() * invFy);
  planeBuilder.build(hullPoints, planeConfig, armInPlane, out.planes);
  return Ok{};
}

float CloudFrame::depthAt(int u, int v) const {
  if (u < 0 || v < 0 || u >= intrinsics.width || v >= intrinsics.height) return 0.0f;
  if (filterBox.contains(u, v)) {
    // The sample whose stride x stride block (offset stride / 2) holds the pixel.
    const int offset = filterStride / 2;
    const int i = std::min(filterColumns - 1, (u - filterBox.x0 + offset) / filterStride);
    const int j = std::min(filterRows - 1, (v - filterBox.y0 + offset) / filterStride);
    return filteredDepthM[static_cast<std::size_t>(j) * filterColumns +
                          static_cast<std::size_t>(i)];
  }
  const float z =
      static_cast<float>(
          rawDepth[static_cast<std::size_t>(v) * intrinsics.width + static_cast<std::size_t>(u)]) *
      depthScale;
  return z >= minDepthM_ && z <= maxDepthM_ ? z : 0.0f;
}

bool CloudFrame::isFree(const Vec3& p, float toleranceM) const {
  if (!(p.z() > 0.0f) || rawDepth.empty()) return false;
  const Vec2 pixel = intrinsics.project(p);
  if (!intrinsics.contains(pixel.x(), pixel.y())) return false;
  const float z = depthAt(roundToInt(pixel.x()), roundToInt(pixel.y()));
  return z == 0.0f || z > p.z() + toleranceM;
}

}  // namespace dynahand
