#include <algorithm>
#include <cassert>
#include <cmath>
#include <numbers>
#include <span>
#include <string>

#include "cloud/depth_filter.h"
#include "cloud/limb_end.h"
#include "cloud/region_grow.h"
#include "cloud/support_plane.h"
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
// its centre. It moves whenever the end lies farther than that from the nearest sample: an
// end near the ball's edge leaves out the fingers beside it that reach farther (a thumb or
// index tip a few cm beyond the end found).
constexpr float kEndInsideBall = 0.75f;
// The limb is explored again from its free end at most this many times, while the end moves
// more than kLimbEndMoveFactor hand radii.
constexpr int kLimbEndRounds = 2;
constexpr float kLimbEndMoveFactor = 0.5f;
// A limb's free end within this many hand radii of the tracked hand's centre (HandHint) is
// that hand: the end lies at its fingertips, about 10 cm from the centre of a hand pointing away
// from a head-mounted camera (an elbow taken for the hand puts it 30 cm or more away).
constexpr float kHintLimbEndReach = 1.0f;
// ... unless the end lies this much (m) nearer the camera than that centre while the hand's
// surface is still there, apart from the limb: an arm seen along its length from a
// head-mounted camera whose surface breaks at a steep wrist (the back of the hand turned away
// from the camera) ends at the break, 10-15 cm in front of the hand.
constexpr float kHintEndInFrontM = 0.10f;
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
  const HandHint* hint = nullptr;  // this frame's (process), or none
  cloud::RegionGrower coarseGrower;
  cloud::RegionGrower fineGrower;
  cloud::LimbEndFinder limbEnd;
  cloud::SupportPlaneFinder planeFinder;
  std::vector<float> coarseDepth;  // (coarse height x coarse width), m
  // (coarse cells) 1: a support plane's sample; empty when this frame left out no plane
  std::vector<std::uint8_t> coarseOnPlane;
  std::vector<std::uint8_t> coarseNear;  // coarse labels dilated by one cell
  std::vector<int> boxColumnCell;        // (box width) coarse column of each box column
  std::vector<int> boxRowCell;           // (box height) coarse row of each box row
  std::vector<Vec2> hullPoints;          // row extremes of the segment, normalised image plane
  // The segmentation samples of the box (every working sample or every other one), m, when
  // they differ from the working samples: subsampled, or support planes left out (segmentFine).
  std::vector<float> segmentDepth;
  std::vector<float> boxColumnX;        // (box width) x / z of each box column
  std::vector<VoxelGrid::Key> rowKeys;  // (box width) voxel of each sample of a row
  std::vector<int> columnVoxel;         // (box width) voxel of the last run over each column
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
  // Finds the support planes (tables, walls) on the coarse grid, records them in out.segment
  // and takes their samples out of the grid; segmentationGrid and scanRow leave them out too.
  void leaveOutSupportPlanes(DepthGrid& grid, CloudFrame& out);
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

  // One frame's search, shared by run()'s stages.
  struct Search {
    DepthGrid coarse;
    GrownRegion first;       // region 1's coarse volume
    int firstSeed = -1;      // its seed cell
    bool hintTried = false;  // keepToTheTrackedHand ran (first round only)
    // keepToTheTrackedHand took the hint's volume over a limb end in front of it.
    bool hintBehindEnd = false;
    int regionCount = 0;                         // coarse volumes accepted: 0, 1 or 2
    int minI = 0, maxI = 0, minJ = 0, maxJ = 0;  // their cell box
    // Each region's limb's free end, when haveHandEnd (region 2's with two regions).
    Vec3 handEnd[2] = {Vec3::Zero(), Vec3::Zero()};
    bool haveHandEnd[2] = {false, false};
    PixelBox box;           // filtered and segmented
    int stride = 1;         // pixels between working samples
    int segmentFactor = 1;  // segmentation samples every segmentFactor working samples
    GrownRegion fineRegion[2];
    bool fineFound[2] = {false, false};
    bool segmentCopy = false;  // the segmentation samples are in segmentDepth
  };
  // Stage 4's running state over the rows of the box.
  struct Scan {
    int columns = 0;         // working samples per row of the box
    int blockOffset = 0;     // each sample stands for the stride x stride block from here (px)
    int segmentShift = 0;    // 1: segmentation grid at every other working sample
    int segmentColumns = 0;  // segmentation samples per row
    const float* segmentGrid = nullptr;
    std::span<const SupportPlane> planes;  // support planes left out
    float planeBandM = 0.0f;               // m
    float handRadius2 = 0.0f;              // m^2
    float segmentSpacing = 0.0f;           // m per m of depth between segmentation samples
    float invFx = 0.0f, invFy = 0.0f;
    PixelBox segmentBox;
    int maskPixels = 0;
    int segmentedSamples = 0;
    Vec3 segmentedSum = Vec3::Zero();  // m
  };

  // run()'s stages, in order.
  void prepareOutput(const DepthFrame& frame, CloudFrame& out);
  // 1. The closest sufficiently large coarse volume (and a second within the band); false
  //    when there is none.
  bool findCoarseRegions(Search& s);
  // The hint's volume in place of region 1 when region 1 (its limb's free end, if it is a
  // limb) does not reach the hint, or when that end lies kHintEndInFrontM in front of the hint
  // with the hint's surface apart from the limb (one hand); true when region 1 was grown again
  // (from the hint's sample, or from its own seed when there is no volume there), so its limb
  // end is to be found again.
  bool keepToTheTrackedHand(Search& s);
  // The free coarse cell closest to the hint's centre when it lies within hintReachM of it,
  // else -1.
  int hintSample(const DepthGrid& grid) const;
  // Whether the hint's sample (hintSample) lies off the surface the last limb search reached
  // (the tracked hand, still there apart from the limb).
  bool surfaceApartFromLimb(const Search& s) const;
  // 2. The filter box around the coarse volumes and the working resolution.
  void chooseBoxAndStride(Search& s) const;
  // With two regions, each coarse cell's region or a neighbour's (cells are sampled at their
  // centre, so edges may disagree).
  void markCoarseNeighbourhood(const Search& s);
  // 3. Filtering and full-resolution growing on the box, widened while a region reaches a box
  //    edge that is not an image edge.
  void segmentFine(const DepthFrame& frame, Search& s, CloudFrame& out);
  DepthGrid segmentationGrid(Search& s, const CloudFrame& out);
  void growFineRegions(Search& s, const DepthGrid& fine);
  bool widenBox(Search& s, int columns, int rows) const;
  // 4. Mask, voxel grid and hull points in one scan (row-major: deterministic).
  Scan scanSegmented(const Search& s, CloudFrame& out);
  void scanRow(const Search& s, int v, Scan& scan, CloudFrame& out);
  void emitVoxels(CloudFrame& out);
  // 5. The segment summary; the arm is where region 1 was cut at the hand radius.
  void summariseSegment(const Search& s, const Scan& scan, CloudFrame& out) const;
  // 6. Boundary planes around the segmented pixels.
  void buildPlanes(const Scan& scan, CloudFrame& out);
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
  const std::uint8_t* planeCells = coarseOnPlane.empty() ? nullptr : coarseOnPlane.data();
  int cell = limbEnd.find(grid, k, seed, seg.step, limbRadius, seg.borderMarginPixels, nearCut,
                          planeCells);
  if (cell < 0) return false;
  end = grid.point(k, cell % grid.width, cell / grid.width);
  // A forearm seen along its length (a head-mounted camera, the elbow nearest) may be longer
  // than the ball: the hand then leaves the ball too and the end found lies between it and the
  // border. Explored again from that end, the ball holds the hand and the fingers end free.
  for (int round = 0; round < kLimbEndRounds; ++round) {
    const int next = limbEnd.find(grid, k, cell, seg.step, limbRadius, seg.borderMarginPixels,
                                  nearCut, planeCells);
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
  impl_->coarseOnPlane.reserve(coarseCells);
  impl_->coarseNear.reserve(coarseCells);
  impl_->boxColumnCell.reserve(static_cast<std::size_t>(intrinsics.width));
  impl_->boxRowCell.reserve(static_cast<std::size_t>(intrinsics.height));
  impl_->hullPoints.reserve(2 * static_cast<std::size_t>(intrinsics.height));
  impl_->segmentDepth.reserve(pixels);
  impl_->planeFinder.reserve(coarseCells);
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

Status CloudPipeline::process(const DepthFrame& frame, CloudFrame& out, const HandHint* hint) {
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
  impl_->hint = hint;
  const Status status = impl_->run(frame, out);
  impl_->hint = nullptr;
  return status;
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

void CloudPipeline::Impl::leaveOutSupportPlanes(DepthGrid& grid, CloudFrame& out) {
  const SupportPlaneConfig& c = config.segmentation.supportPlanes;
  Segment& segment = out.segment;
  segment.supportPlaneCount = planeFinder.find(grid, k, c, segment.supportPlanes);
  // Empty when no plane was left out (findLimbEnd then has no plane contacts to look for).
  coarseOnPlane.clear();
  if (segment.supportPlaneCount == 0) return;
  coarseOnPlane.assign(coarseDepth.size(), 0);
  for (int p = 0; p < segment.supportPlaneCount; ++p) {
    cloud::removePlaneSamples(segment.supportPlanes[static_cast<std::size_t>(p)], c.bandM, k,
                              grid.originU, grid.originV, grid.step, grid.width, grid.height,
                              coarseDepth.data(), coarseOnPlane.data());
  }
}

void CloudPipeline::Impl::prepareOutput(const DepthFrame& frame, CloudFrame& out) {
  const auto pixels = static_cast<std::size_t>(k.width) * k.height;
  // Allocated on the first frame only.
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
}

bool CloudPipeline::Impl::findCoarseRegions(Search& s) {
  const SegmentationConfig& seg = config.segmentation;
  // The coarse ball is wider than the hand radius: the full-resolution nearest point (the
  // final ball's centre) differs from the coarse one by up to a few cm, and the filter box
  // must hold the whole final region.
  const float coarseRadius = seg.handRadiusM * kCoarseRadiusFactor;
  s.regionCount = 0;
  s.first = GrownRegion{};
  s.firstSeed = -1;
  // Nearest-first; a candidate at the image border is remembered and passed over (see
  // SegmentationConfig::borderMarginPixels), and used when nothing better follows.
  int borderSeed = -1;
  float borderDepth = 0.0f;
  int attempts = 0;
  while (s.regionCount == 0 && attempts++ < seg.maxSeedAttempts) {
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
    if (atBorder(s.coarse, r)) {
      if (borderSeed < 0) {
        borderSeed = seed;
        borderDepth = r.nearestPoint.z();
      }
      coarseGrower.reject();
      continue;
    }
    coarseGrower.accept(cloud::kRegion1);
    s.first = r;
    s.firstSeed = seed;
    s.regionCount = 1;
  }
  if (s.regionCount == 0 && borderSeed >= 0) {
    coarseGrower.reset(s.coarse, k);  // forget the passed-over labels
    s.first = coarseGrower.grow(borderSeed, seg.step, coarseRadius, seg.minAreaM2);
    coarseGrower.accept(cloud::kRegion1);
    s.firstSeed = borderSeed;
    s.regionCount = 1;
  }
  if (s.regionCount == 0) return false;
  s.haveHandEnd[0] = findLimbEnd(s.coarse, s.firstSeed, s.first, s.handEnd[0]);
  if (keepToTheTrackedHand(s)) {
    s.haveHandEnd[0] = findLimbEnd(s.coarse, s.firstSeed, s.first, s.handEnd[0]);
    // The hand behind a limb end in front of it, seen apart from its arm (no limb end of its
    // own): its sample is the limb's free end, so that the final ball moves onto it rather
    // than staying on the nearest sample of the box, which is the arm's.
    if (s.hintBehindEnd && !s.haveHandEnd[0]) {
      s.haveHandEnd[0] = true;
      s.handEnd[0] = s.coarse.point(k, s.firstSeed % s.coarse.width, s.firstSeed / s.coarse.width);
    }
  }
  s.haveHandEnd[1] = false;
  s.minI = s.first.minI;
  s.maxI = s.first.maxI;
  s.minJ = s.first.minJ;
  s.maxJ = s.first.maxJ;
  if (seg.secondRegionDepthBandM > 0.0f) {
    attempts = 0;
    while (s.regionCount == 1 && attempts++ < seg.maxSeedAttempts) {
      const int seed =
          coarseGrower.nearestFreeCell(s.first.nearestPoint.z() + seg.secondRegionDepthBandM,
                                       &s.first.nearestPoint, coarseRadius);
      if (seed < 0) break;
      const GrownRegion r = coarseGrower.grow(seed, seg.step, coarseRadius, seg.minAreaM2);
      if (r.areaM2 >= seg.minAreaM2 && !r.inFrontOfSurface && !r.touchesEarlierRegion) {
        coarseGrower.accept(cloud::kRegion2);
        s.regionCount = 2;
        // The second hand's limb too (a forearm nearer the camera than its hand).
        s.haveHandEnd[1] = findLimbEnd(s.coarse, seed, r, s.handEnd[1]);
        s.minI = std::min(s.minI, r.minI);
        s.maxI = std::max(s.maxI, r.maxI);
        s.minJ = std::min(s.minJ, r.minJ);
        s.maxJ = std::max(s.maxJ, r.maxJ);
      } else {
        coarseGrower.reject();
      }
    }
  }
  return true;
}

int CloudPipeline::Impl::hintSample(const DepthGrid& grid) const {
  const int cell = coarseGrower.closestFreeCell(hint->centre);
  if (cell < 0) return -1;
  const float reach = config.segmentation.hintReachM;
  const Vec3 p = grid.point(k, cell % grid.width, cell / grid.width);
  return (p - hint->centre).squaredNorm() <= reach * reach ? cell : -1;
}

bool CloudPipeline::Impl::surfaceApartFromLimb(const Search& s) const {
  const int cell = hintSample(s.coarse);
  return cell >= 0 && !limbEnd.reached(cell);
}

bool CloudPipeline::Impl::keepToTheTrackedHand(Search& s) {
  const SegmentationConfig& seg = config.segmentation;
  if (hint == nullptr || s.hintTried || seg.hintReachM <= 0.0f || seg.secondRegionDepthBandM > 0.0f)
    return false;
  s.hintTried = true;
  const DepthGrid& grid = s.coarse;
  const float reach2 = seg.hintReachM * seg.hintReachM;
  // A limb: the hand is at its free end (a forearm seen along its length holds the hand beyond
  // the ball, found there); the hint is within a few cm of the end when it is right.
  if (s.haveHandEnd[0] &&
      (s.handEnd[0] - hint->centre).norm() <= kHintLimbEndReach * seg.handRadiusM) {
    if (hint->centre.z() - s.handEnd[0].z() < kHintEndInFrontM || !surfaceApartFromLimb(s))
      return false;
    s.hintBehindEnd = true;
  }
  // A hint on the volume (a tracker gone astray onto the forearm, say) changes nothing either.
  const std::vector<std::uint8_t>& labels = coarseGrower.labels();
  for (int j = s.first.minJ; j <= s.first.maxJ; ++j) {
    for (int i = s.first.minI; i <= s.first.maxI; ++i) {
      if (labels[static_cast<std::size_t>(j) * grid.width + i] != cloud::kRegion1) continue;
      if ((grid.point(k, i, j) - hint->centre).squaredNorm() <= reach2) return false;
    }
  }
  // Grown from the tracked hand's sample, over labels forgotten as for a border volume (a
  // volume passed over before may hold it).
  const float coarseRadius = seg.handRadiusM * kCoarseRadiusFactor;
  coarseGrower.reset(grid, k);
  const int seed = hintSample(grid);
  bool taken = false;
  if (seed >= 0) {
    const GrownRegion r = coarseGrower.grow(seed, seg.step, coarseRadius, seg.minAreaM2);
    taken = r.areaM2 >= seg.minAreaM2 && !r.inFrontOfSurface;
    if (taken) {
      coarseGrower.accept(cloud::kRegion1);
      s.first = r;
      s.firstSeed = seed;
    } else {
      coarseGrower.reject();
      coarseGrower.reset(grid, k);
    }
  }
  if (!taken) {  // no volume there (the hand has left it): the nearest volume again
    s.first = coarseGrower.grow(s.firstSeed, seg.step, coarseRadius, seg.minAreaM2);
    coarseGrower.accept(cloud::kRegion1);
  }
  return true;
}

void CloudPipeline::Impl::chooseBoxAndStride(Search& s) const {
  // Margin: a coarse cell covers step pixels; the median and flying-pixel tests need one
  // more pixel each.
  const DepthGrid& coarse = s.coarse;
  const int step = coarse.step;
  const int margin = 2 * step + 2;
  s.box.x0 = std::max(0, coarse.originU + s.minI * step - margin);
  s.box.y0 = std::max(0, coarse.originV + s.minJ * step - margin);
  s.box.x1 = std::min(k.width, coarse.originU + s.maxI * step + margin + 1);
  s.box.y1 = std::min(k.height, coarse.originV + s.maxJ * step + margin + 1);

  // Working resolution: samples no closer than half a voxel at the hand's depth.
  const float pixelPitch = s.first.nearestPoint.z() / std::min(k.fx, k.fy);  // m
  s.stride = config.sampleStride;
  if (s.stride <= 0)
    s.stride = std::clamp(static_cast<int>(0.5f * config.voxelSizeM / pixelPitch), 1, 4);
  // Region growing costs per sample and needs fewer of them than the voxels: with growStep
  // 2, at stride 1 it takes every other sample while those stay within one voxel of each
  // other (a finger is then still >= 3 samples wide). The voxels take every working sample.
  s.segmentFactor =
      config.segmentation.growStep == 2 && s.stride == 1 && 2.0f * pixelPitch <= config.voxelSizeM
          ? 2
          : 1;
}

void CloudPipeline::Impl::markCoarseNeighbourhood(const Search& s) {
  const DepthGrid& coarse = s.coarse;
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

DepthGrid CloudPipeline::Impl::segmentationGrid(Search& s, const CloudFrame& out) {
  const PixelBox& box = s.box;
  const int segmentStride = s.stride * s.segmentFactor;
  // The segmentation grid: the working samples, or every other one of them.
  const int bw = cloud::samplesAlong(box.width(), segmentStride);
  const int bh = cloud::samplesAlong(box.height(), segmentStride);
  const float* grid = out.filteredDepthM.data();
  s.segmentCopy = s.segmentFactor > 1 || out.segment.supportPlaneCount > 0;
  if (s.segmentFactor == 1 && s.segmentCopy) {
    segmentDepth.assign(out.filteredDepthM.begin(), out.filteredDepthM.end());
    grid = segmentDepth.data();
  } else if (s.segmentFactor > 1) {
    const int workingColumns = cloud::samplesAlong(box.width(), s.stride);
    segmentDepth.resize(static_cast<std::size_t>(bw) * bh);
    for (int v = 0; v < bh; ++v) {
      const float* src = out.filteredDepthM.data() +
                         static_cast<std::size_t>(v * s.segmentFactor) * workingColumns;
      float* dst = segmentDepth.data() + static_cast<std::size_t>(v) * bw;
      for (int u = 0; u < bw; ++u) dst[u] = src[u * s.segmentFactor];
    }
    grid = segmentDepth.data();
  }
  for (int p = 0; p < out.segment.supportPlaneCount; ++p) {
    cloud::removePlaneSamples(out.segment.supportPlanes[static_cast<std::size_t>(p)],
                              config.segmentation.supportPlanes.bandM, k, box.x0, box.y0,
                              segmentStride, bw, bh, segmentDepth.data());
  }
  // Coarse cell column / row of each box column / row.
  const int step = s.coarse.step;
  boxColumnCell.resize(static_cast<std::size_t>(bw));
  boxRowCell.resize(static_cast<std::size_t>(bh));
  for (int u = 0; u < bw; ++u) {
    boxColumnCell[static_cast<std::size_t>(u)] =
        std::min(s.coarse.width - 1, (box.x0 + u * segmentStride) / step);
  }
  for (int v = 0; v < bh; ++v) {
    boxRowCell[static_cast<std::size_t>(v)] =
        std::min(s.coarse.height - 1, (box.y0 + v * segmentStride) / step);
  }
  DepthGrid fine;
  fine.depth = grid;
  fine.width = bw;
  fine.height = bh;
  fine.originU = box.x0;
  fine.originV = box.y0;
  fine.step = segmentStride;
  return fine;
}

void CloudPipeline::Impl::growFineRegions(Search& s, const DepthGrid& fine) {
  const SegmentationConfig& seg = config.segmentation;
  const bool twoRegions = s.regionCount == 2;
  fineGrower.reset(fine, k);
  fragments.clear();
  fragmentCells.clear();
  s.fineFound[0] = s.fineFound[1] = false;
  // The coarse pass accepted these volumes; at full resolution a filtered speck may still be
  // nearest (e.g. a fingertip in front of the palm), so small regions are skipped too.
  for (int r = 0; r < s.regionCount; ++r) {
    const auto label = static_cast<std::uint8_t>(r == 0 ? cloud::kRegion1 : cloud::kRegion2);
    int attempts = 0;
    while (!s.fineFound[r] && attempts++ < seg.maxSeedAttempts) {
      // Region 1 may start anywhere in the box but in region 2's cells: when its coarse
      // volume splits at full resolution (a fingertip in front of the palm), the palm beside
      // it is still the nearest large volume. Region 2 starts in its own cells.
      const int seed =
          !twoRegions
              ? fineGrower.nearestFreeCell()
              : fineGrower.nearestFreeCellWhere([&](int u, int v) {
                  const std::uint8_t coarseLabel =
                      coarseNear[static_cast<std::size_t>(boxRowCell[static_cast<std::size_t>(v)]) *
                                     s.coarse.width +
                                 static_cast<std::size_t>(
                                     boxColumnCell[static_cast<std::size_t>(u)])];
                  return label == cloud::kRegion1 ? coarseLabel != cloud::kRegion2
                                                  : coarseLabel == cloud::kRegion2;
                });
      if (seed < 0) break;
      GrownRegion g = fineGrower.grow(seed, seg.step, seg.handRadiusM, seg.minAreaM2);
      const Vec3 toNearest = g.nearestPoint - s.handEnd[r];
      if (s.haveHandEnd[r] && toNearest.norm() > kEndInsideBall * seg.handRadiusM) {
        // The ball around the nearest sample leaves out the limb's free end, or holds it
        // with less than a quarter radius to spare: that sample is on a forearm pointing at
        // the camera. The ball moves toward the free end until it holds it with a quarter
        // radius to spare.
        const Vec3 centre =
            s.handEnd[r] + toNearest.normalized() * (kEndInsideBall * seg.handRadiusM);
        const int endSeed = fineGrower.closestFreeCell(centre);
        if (endSeed >= 0) g = fineGrower.grow(endSeed, seg.step, seg.handRadiusM, seg.minAreaM2);
      }
      if (g.areaM2 >= seg.minAreaM2 && !g.inFrontOfSurface) {
        fineGrower.accept(static_cast<CellLabel>(label));
        s.fineRegion[r] = g;
        s.fineFound[r] = true;
        // Pieces passed over as too small that lie within this volume's ball, in front of it
        // or about as near: a hand broken up by missing data (fingers seen edge-on with a
        // structured-light camera), whose pieces belong to it.
        if (r == 0 && !twoRegions) {
          for (const Fragment& f : fragments) {
            if (!joins(f, g.nearestPoint, kFragmentDepthM)) continue;
            // Only its cells within the region's ball (the hand-radius rule), and only those
            // not in the region already (it may have grown into the piece).
            GrownRegion& taken = s.fineRegion[r];
            taken.areaM2 += fineGrower.labelCellsWithin(
                fragmentCells.data() + f.begin, f.end - f.begin, static_cast<CellLabel>(label),
                g.nearestPoint, seg.handRadiusM);
            includeBox(taken, f.region);  // a piece cut by the box widens it
          }
        }
      } else {
        // Recorded only while it fits the reserved buffers (no allocation per frame).
        bool piece =
            r == 0 && !twoRegions && !g.inFrontOfSurface && fragments.size() < fragments.capacity();
        if (piece) {
          Fragment f{g, fragmentCells.size(), 0};
          piece = fineGrower.appendLastRegion(fragmentCells);
          f.end = fragmentCells.size();
          if (piece) fragments.push_back(f);
        }
        fineGrower.reject();
        // Pieces that together make a volume are taken as one (mergePieces).
        if (piece && mergePieces(static_cast<CellLabel>(label), s.fineRegion[r]))
          s.fineFound[r] = true;
      }
    }
  }
}

bool CloudPipeline::Impl::widenBox(Search& s, int columns, int rows) const {
  PixelBox& box = s.box;
  const int extra = std::max(box.width(), box.height()) / 2;
  PixelBox wider = box;
  for (int r = 0; r < 2; ++r) {
    if (!s.fineFound[r]) continue;
    const GrownRegion& g = s.fineRegion[r];
    if (g.minI == 0 && box.x0 > 0) wider.x0 = std::max(0, box.x0 - extra);
    if (g.minJ == 0 && box.y0 > 0) wider.y0 = std::max(0, box.y0 - extra);
    if (g.maxI == columns - 1 && box.x1 < k.width) wider.x1 = std::min(k.width, box.x1 + extra);
    if (g.maxJ == rows - 1 && box.y1 < k.height) wider.y1 = std::min(k.height, box.y1 + extra);
  }
  if (wider.x0 == box.x0 && wider.y0 == box.y0 && wider.x1 == box.x1 && wider.y1 == box.y1)
    return false;
  box = wider;
  return true;
}

void CloudPipeline::Impl::segmentFine(const DepthFrame& frame, Search& s, CloudFrame& out) {
  for (int pass = 0;; ++pass) {
    out.filterBox = s.box;
    cloud::filterBox(frame, s.box, s.stride, config.filter, config.segmentation.step, k.fx, k.fy,
                     filterScratch, out.filteredDepthM);
    const DepthGrid fine = segmentationGrid(s, out);
    growFineRegions(s, fine);
    if (pass == kMaxBoxRetries || !s.fineFound[0]) break;
    if (!widenBox(s, fine.width, fine.height)) break;
  }
}

void CloudPipeline::Impl::scanRow(const Search& s, int v, Scan& scan, CloudFrame& out) {
  const SegmentationConfig& seg = config.segmentation;
  const PixelBox& box = s.box;
  const int stride = s.stride;
  const int bw = scan.columns;
  const int pv = box.y0 + v * stride;
  const std::size_t segmentRow =
      static_cast<std::size_t>(v >> scan.segmentShift) * scan.segmentColumns;
  const std::uint8_t* labelRow = fineGrower.labels().data() + segmentRow;
  const float* segmentDepthRow = scan.segmentGrid + segmentRow;
  const bool segmentSampleRow = (v & scan.segmentShift) == 0;
  const float* depthRow = out.filteredDepthM.data() + static_cast<std::size_t>(v) * bw;
  const int blockV0 = std::max(0, pv - scan.blockOffset);
  const int blockV1 = std::min(k.height, pv - scan.blockOffset + stride);
  const float ny = (static_cast<float>(pv) - k.cy) * scan.invFy;
  int rowMin = -1;
  int rowMax = -1;
  voxels.keysOfRow(boxColumnX.data(), ny, depthRow, bw, rowKeys.data());
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
  // Segmented samples [spanBegin, u) in a row: their blocks make one pixel span.
  int spanBegin = -1;
  const auto closeSpan = [&](int spanEnd) {
    const int pixel0 = std::max(0, box.x0 + spanBegin * stride - scan.blockOffset);
    const int pixel1 =
        std::min(k.width, box.x0 + (spanEnd - 1) * stride - scan.blockOffset + stride);
    for (int mv = blockV0; mv < blockV1; ++mv) {
      std::uint8_t* maskRow = out.mask.data() + static_cast<std::size_t>(mv) * k.width;
      std::fill(maskRow + pixel0, maskRow + pixel1, std::uint8_t{1});
    }
    scan.maskPixels += (blockV1 - blockV0) * (pixel1 - pixel0);
    spanBegin = -1;
  };
  for (int u = 0; u < bw; ++u) {
    const std::uint8_t label = labelRow[u >> scan.segmentShift];
    const float z = depthRow[u];
    bool segmented = label == cloud::kRegion1 || label == cloud::kRegion2;
    if (segmented && !(segmentSampleRow && (u & scan.segmentShift) == 0)) {
      const float zs = segmentDepthRow[u >> scan.segmentShift];
      const Vec3 p(boxColumnX[static_cast<std::size_t>(u)] * z, ny * z, z);
      segmented = z > 0.0f &&
                  std::fabs(z - zs) <= cloud::maxDepthStep(seg.step, zs, scan.segmentSpacing) &&
                  (p - s.fineRegion[label - 1].nearestPoint).squaredNorm() <= scan.handRadius2;
      for (const SupportPlane& plane : scan.planes)
        segmented = segmented && !cloud::onPlane(plane, p, scan.planeBandM);
    }
    if (!segmented) {
      if (spanBegin >= 0) closeSpan(u);
      continue;
    }
    if (spanBegin < 0) spanBegin = u;
    ++scan.segmentedSamples;
    const int pu = box.x0 + u * stride;
    const Vec3 p(boxColumnX[static_cast<std::size_t>(u)] * z, ny * z, z);
    const VoxelGrid::Key key = rowKeys[static_cast<std::size_t>(u)];
    scan.segmentedSum += p;
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
  if (rowMin < 0) return;
  hullPoints.emplace_back((static_cast<float>(rowMin) - k.cx) * scan.invFx, ny);
  if (rowMax != rowMin)
    hullPoints.emplace_back((static_cast<float>(rowMax) - k.cx) * scan.invFx, ny);
  PixelBox& segBox = scan.segmentBox;
  segBox.x0 = std::min(segBox.x0, std::max(0, rowMin - scan.blockOffset));
  segBox.x1 = std::max(segBox.x1, std::min(k.width, rowMax - scan.blockOffset + stride));
  segBox.y0 = std::min(segBox.y0, blockV0);
  segBox.y1 = blockV1;
}

CloudPipeline::Impl::Scan CloudPipeline::Impl::scanSegmented(const Search& s, CloudFrame& out) {
  const SegmentationConfig& seg = config.segmentation;
  const int stride = s.stride;
  const int bw = cloud::samplesAlong(s.box.width(), stride);
  const int bh = cloud::samplesAlong(s.box.height(), stride);
  out.filterStride = stride;
  out.filterColumns = bw;
  out.filterRows = bh;
  voxels.clear();
  hullPoints.clear();
  Scan scan;
  scan.columns = bw;
  scan.invFx = 1.0f / k.fx;
  scan.invFy = 1.0f / k.fy;
  // Each sample stands for the stride x stride pixel block around it (offset stride / 2).
  scan.blockOffset = stride / 2;
  scan.segmentBox = PixelBox{k.width, k.height, 0, 0};
  boxColumnX.resize(static_cast<std::size_t>(bw));
  for (int u = 0; u < bw; ++u) {
    boxColumnX[static_cast<std::size_t>(u)] =
        (static_cast<float>(s.box.x0 + u * stride) - k.cx) * scan.invFx;
  }
  rowKeys.resize(static_cast<std::size_t>(bw));
  columnVoxel.assign(static_cast<std::size_t>(bw), -1);
  // With segmentFactor 2 a working sample takes the label of the segmentation sample at the
  // top left of its 2 x 2 group when it lies on the same surface (the step rule between
  // segmentation neighbours): silhouette edges stay at the working resolution.
  scan.segmentShift = s.segmentFactor == 2 ? 1 : 0;
  scan.segmentColumns = cloud::samplesAlong(s.box.width(), stride * s.segmentFactor);
  scan.segmentGrid = s.segmentCopy ? segmentDepth.data() : out.filteredDepthM.data();
  scan.planes = std::span(out.segment.supportPlanes.data(),
                          static_cast<std::size_t>(out.segment.supportPlaneCount));
  scan.planeBandM = seg.supportPlanes.bandM;
  scan.handRadius2 = seg.handRadiusM * seg.handRadiusM;
  scan.segmentSpacing = static_cast<float>(stride * s.segmentFactor) / std::min(k.fx, k.fy);
  for (int v = 0; v < bh; ++v) scanRow(s, v, scan, out);
  out.segmentBox = scan.segmentBox;
  out.droppedPoints = voxels.droppedPoints();
  return scan;
}

void CloudPipeline::Impl::emitVoxels(CloudFrame& out) {
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
}

void CloudPipeline::Impl::summariseSegment(const Search& s, const Scan& scan,
                                           CloudFrame& out) const {
  Segment& segment = out.segment;
  segment.found = true;
  segment.regionCount = s.fineFound[1] ? 2 : 1;
  segment.nearestPoint = s.fineRegion[0].nearestPoint;
  segment.pixelCount = scan.maskPixels;
  segment.sampleCount = scan.segmentedSamples;
  segment.areaM2 = s.fineRegion[0].areaM2;
  if (s.fineFound[1]) segment.areaM2 += s.fineRegion[1].areaM2;
  segment.centroid = scan.segmentedSum / static_cast<float>(scan.segmentedSamples);
  segment.limbEndFound = s.haveHandEnd[0];
  segment.limbEnd = s.haveHandEnd[0] ? s.handEnd[0] : Vec3::Zero();
  const GrownRegion& hand = s.fineRegion[0];
  segment.cutPixelCount = hand.cutCount;
  if (hand.cutCount > 0) {
    const auto cuts = static_cast<float>(hand.cutCount);
    const auto cells = static_cast<float>(hand.cellCount);
    segment.armDirection = normalisedOrZero<3>(hand.cutPointSum / cuts - hand.pointSum / cells);
    segment.armDirectionImage =
        normalisedOrZero<2>(hand.cutPixelSum / cuts - hand.pixelSum / cells);
  }
}

void CloudPipeline::Impl::buildPlanes(const Scan& scan, CloudFrame& out) {
  BoundaryPlaneConfig planeConfig = config.planes;
  // The planes go through the samples; the mask blocks reach blockOffset pixels beyond.
  planeConfig.margin +=
      (config.planeMarginPixels + static_cast<float>(scan.blockOffset)) / std::min(k.fx, k.fy);
  const Vec2 armInPlane(out.segment.armDirectionImage.x() * scan.invFx,
                        out.segment.armDirectionImage.y() * scan.invFy);
  // The image's edges through its outermost pixel centres; a hull vertex within a sample
  // block of one lies on it.
  ViewBounds view;
  view.min = Vec2(-k.cx * scan.invFx, -k.cy * scan.invFy);
  view.max = Vec2((static_cast<float>(k.width - 1) - k.cx) * scan.invFx,
                  (static_cast<float>(k.height - 1) - k.cy) * scan.invFy);
  view.margin = static_cast<float>(out.filterStride + 1) / std::min(k.fx, k.fy);
  planeBuilder.build(hullPoints, planeConfig, armInPlane, out.planes, view);
}

Status CloudPipeline::Impl::run(const DepthFrame& frame, CloudFrame& out) {
  prepareOutput(frame, out);
  Search s;
  sampleCoarse(frame, s.coarse);
  leaveOutSupportPlanes(s.coarse, out);
  coarseGrower.reset(s.coarse, k);
  // A coarse volume can fail at full resolution (e.g. a speckle cluster whose coarse area was
  // overestimated): it is retired and the search goes on with the next candidate.
  for (int round = 0; round < kCandidateRounds && !s.fineFound[0]; ++round) {
    if (!findCoarseRegions(s)) return Ok{};  // no hand: valid, empty
    chooseBoxAndStride(s);
    if (s.regionCount == 2) markCoarseNeighbourhood(s);
    segmentFine(frame, s, out);
    if (!s.fineFound[0]) coarseGrower.retireAccepted();
  }
  if (!s.fineFound[0]) return Ok{};
  const Scan scan = scanSegmented(s, out);
  emitVoxels(out);
  summariseSegment(s, scan, out);
  buildPlanes(scan, out);
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
