#include "track/finger_detector.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "core/simd/lanes.h"

namespace dynahand::track {

namespace {
constexpr float kExactRounding = 4194304.0f;  // 2^22: below it roundToPixel is exact inline

// std::lround for pixel coordinates (|x| < 2^22), inline: truncation and the fraction are
// exact there, so halves round away from zero exactly as lround does.
int roundToPixel(float x) {
  if (!(std::abs(x) < kExactRounding)) return static_cast<int>(std::lround(x));
  int i = static_cast<int>(x);
  const float fraction = x - static_cast<float>(i);
  if (fraction >= 0.5f) ++i;
  if (fraction <= -0.5f) --i;
  return i;
}

// The samples of one scanline: sample col (t = tMin + col across, from rowBase = c + axis s)
// is on when its pixel (c + axis s + across t, rounded) is in the box and on the mask. Bit
// col % 64 of on[col / 64]; the words must hold `columns` bits, all clear. The box lies inside the
// image; sampleRow (finger_sampling.inl) reads pixel 0 for the lanes outside it (and ignores
// it), so the mask must not be empty (detect() asks for 50 mask pixels).
struct ScanlineSampler {
  const std::uint8_t* mask;
  int width;
  PixelBox box;

  bool sample(const Vec2& rowBase, const Vec2& across, float t) const {
    const Vec2 p = rowBase + across * t;
    const int u = roundToPixel(p.x()), v = roundToPixel(p.y());
    if (!box.contains(u, v)) return false;
    return mask[static_cast<std::size_t>(v * width + u)] != 0;
  }

  // Samples [from, to) one by one.
  void row(const Vec2& rowBase, const Vec2& across, float tMin, int from, int to,
           std::uint64_t* on) const {
    for (int col = from; col < to; ++col)
      if (sample(rowBase, across, tMin + static_cast<float>(col)))
        on[col / 64] |= std::uint64_t{1} << (col % 64);
  }
};

#define DYNAHAND_SIMD_KERNELS "track/finger_sampling.inl"
#include "core/simd/for_each_level.inl"

}  // namespace

// Word by word: single-sample gaps (an off sample with on samples either side) are filled
// first, then each run is a block of ones.
void scanlineRuns(const std::uint64_t* on, int columns, std::vector<ScanlineRun>& runs) {
  runs.clear();
  const int words = (columns + 63) / 64;
  auto word = [&](int w) { return w >= 0 && w < words ? on[w] : std::uint64_t{0}; };
  auto filledWord = [&](int w) {  // on, plus the gaps with on samples either side
    const std::uint64_t b = word(w);
    const std::uint64_t before = (b << 1) | (word(w - 1) >> 63);  // bit j: sample j - 1
    const std::uint64_t after = (b >> 1) | (word(w + 1) << 63);   // bit j: sample j + 1
    return b | (before & after);
  };
  int begin = -1;
  std::uint64_t previous = 0;  // filled word w - 1
  std::uint64_t current = words > 0 ? filledWord(0) : 0;
  for (int w = 0; w < words; ++w) {
    const std::uint64_t next = w + 1 < words ? filledWord(w + 1) : 0;
    const std::uint64_t starts = current & ~((current << 1) | (previous >> 63));
    const std::uint64_t ends = current & ~((current >> 1) | (next << 63));  // last on sample
    std::uint64_t edges = starts | ends;
    while (edges != 0) {
      const int bit = __builtin_ctzll(edges);
      edges &= edges - 1;
      const int col = 64 * w + bit;
      if ((starts >> bit) & 1u) begin = col;
      if ((ends >> bit) & 1u) {
        if (col + 1 < columns) runs.push_back({begin, col + 1});
        begin = -1;
      }
    }
    previous = current;
    current = next;
  }
}

const FingerDetection& FingerDetector::detect(const CloudFrame& cloud) {
  result_.fired = false;
  if (!cloud.segment.found || cloud.segmentBox.empty()) return result_;
  const Intrinsics& k = cloud.intrinsics;
  const int width = k.width;

  // Mask centroid and extent.
  double su = 0, sv = 0;
  int count = 0;
  const PixelBox& box = cloud.segmentBox;
  rowFirst_.assign(static_cast<std::size_t>(box.y1 - box.y0), -1);
  rowLast_.assign(static_cast<std::size_t>(box.y1 - box.y0), -1);
  for (int v = box.y0; v < box.y1; ++v) {
    const auto row = static_cast<std::size_t>(v - box.y0);
    for (int u = box.x0; u < box.x1; ++u) {
      if (cloud.mask[static_cast<std::size_t>(v * width + u)]) {
        su += u;
        sv += v;
        ++count;
        if (rowFirst_[row] < 0) rowFirst_[row] = u;
        rowLast_[row] = u;
      }
    }
  }
  if (count < 50) return result_;
  const Vec2 c(static_cast<float>(su / count), static_cast<float>(sv / count));
  Vec2 axis(0.0f, -1.0f);  // fingers up when there is no arm direction
  if (cloud.segment.armDirectionImage.norm() > 0.5f)
    axis = -cloud.segment.armDirectionImage.normalized();
  // The arm's direction is only roughly the hand's (wrist deviation, a short or noisy arm):
  // scanlines are tried across it and turned up to 40 degrees either way, nearest first.
  for (const float turnDeg : {0.0f, 10.0f, -10.0f, 20.0f, -20.0f, 30.0f, -30.0f, 40.0f, -40.0f}) {
    const float a = turnDeg * 3.14159265f / 180.0f;
    const Vec2 turned(std::cos(a) * axis.x() - std::sin(a) * axis.y(),
                      std::sin(a) * axis.x() + std::cos(a) * axis.y());
    if (scanAlong(cloud, c, turned)) break;
  }
  return result_;
}

bool FingerDetector::scanAlong(const CloudFrame& cloud, const Vec2& c, const Vec2& axis) {
  const Intrinsics& k = cloud.intrinsics;
  const int width = k.width;
  const PixelBox& box = cloud.segmentBox;
  const Vec2 across(-axis.y(), axis.x());

  // The mask's extent along and across the axis: along a row each projection is monotonic in
  // u (float rounding keeps it so), so the row's first and last mask pixels bound it.
  float sMax = -1e9f, tMin = 1e9f, tMax = -1e9f;
  for (int v = box.y0; v < box.y1; ++v) {
    const auto row = static_cast<std::size_t>(v - box.y0);
    if (rowFirst_[row] < 0) continue;
    for (const int u : {rowFirst_[row], rowLast_[row]}) {
      const Vec2 d = Vec2(static_cast<float>(u), static_cast<float>(v)) - c;
      sMax = std::max(sMax, d.dot(axis));
      const float t = d.dot(across);
      tMin = std::min(tMin, t);
      tMax = std::max(tMax, t);
    }
  }
  // Pixels per metre at the hand's depth.
  const float z = std::max(0.1f, cloud.segment.centroid.z());
  const float pxPerM = k.fx / z;
  const float minWidth = settings_.minFingerWidthM * pxPerM;
  const float maxWidth = settings_.maxFingerWidthM * pxPerM;
  const int minLength = std::max(2, static_cast<int>(settings_.minFingerLengthM * pxPerM));
  const int rows = std::max(1, static_cast<int>(settings_.maxScanLengthM * pxPerM));
  const int columns = static_cast<int>(tMax - tMin) + 1;

  // A sample t across the scanline through rowBase = c + axis s is on when its pixel
  // (c + axis s + across t, the same sums as one expression) is on the mask.
  const ScanlineSampler sampler{cloud.mask.data(), width, box};
  rowSamples_.resize(static_cast<std::size_t>(columns + 63) / 64);
  std::uint64_t* const on = rowSamples_.data();

  segments_.clear();
  previousRuns_.clear();
  for (int row = 0; row < rows; ++row) {
    const float s = sMax - static_cast<float>(row);
    const Vec2 rowBase = c + axis * s;
    std::fill(rowSamples_.begin(), rowSamples_.end(), std::uint64_t{0});
    DYNAHAND_SIMD_DISPATCH(sampleRow, sampler, rowBase, across, tMin, columns, on);
    scanlineRuns(on, columns, runs_);
    continueSegments(row, minLength, minWidth, maxWidth);
    // Fire once five fingers were seen apart and the scan has reached the palm: at most two
    // runs (the palm, and possibly the thumb still apart; the thumb, lower on the hand, may
    // start after the four fingers have met).
    std::array<int, 5> fiveSegments{};
    int fingers = 0;
    for (std::size_t i = 0; i < segments_.size(); ++i) {
      if (!segments_[i].fingerLike) continue;
      if (fingers < 5) fiveSegments[static_cast<std::size_t>(fingers)] = static_cast<int>(i);
      ++fingers;
    }
    if (fingers > 5) return false;  // more finger-like things than fingers: not this way
    const bool undecided = std::any_of(runs_.begin(), runs_.end(), [&](const Run& r) {
      return !segments_[static_cast<std::size_t>(r.segment)].decided;
    });
    if (fingers == 5 && runs_.size() <= 2 && !undecided) {
      result_.fired = placeTips(cloud, TipFrame{c, axis, sMax, tMin, pxPerM}, fiveSegments);
      return result_.fired;
    }
    std::swap(runs_, previousRuns_);
  }
  return false;
}

void FingerDetector::continueSegments(int row, int minLength, float minWidth, float maxWidth) {
  // A run overlapping previous runs joins the first one's segment; overlapping several means
  // they came together.
  for (Run& run : runs_) {
    int overlaps = 0;
    for (const Run& prev : previousRuns_) {
      if (prev.end > run.begin && prev.begin < run.end) {
        if (run.segment < 0) run.segment = prev.segment;
        ++overlaps;
      }
    }
    if (run.segment < 0) {
      run.segment = static_cast<int>(segments_.size());
      segments_.push_back({row, 0.5f * static_cast<float>(run.begin + run.end - 1), 0});
    }
    Segment& seg = segments_[static_cast<std::size_t>(run.segment)];
    if (overlaps > 1) seg.decided = true;  // merged: no longer one finger on its own
    ++seg.length;
    if (!seg.decided && seg.length == minLength) {
      seg.decided = true;
      const float w = static_cast<float>(run.end - run.begin);
      seg.fingerLike = w >= minWidth && w <= maxWidth;
    }
  }
}

bool FingerDetector::placeTips(const CloudFrame& cloud, const TipFrame& f,
                               const std::array<int, 5>& fiveSegments) {
  const Intrinsics& k = cloud.intrinsics;
  const int width = k.width;
  const Vec2& c = f.centre;
  const Vec2& axis = f.axis;
  const Vec2 across(-axis.y(), axis.x());
  const float sMax = f.sMax, tMin = f.tMin, pxPerM = f.pxPerM;
  // Fingertips: the top of each segment, ordered across the hand.
  std::array<std::pair<float, int>, 5> order;
  for (int i = 0; i < 5; ++i) {
    const Segment& seg =
        segments_[static_cast<std::size_t>(fiveSegments[static_cast<std::size_t>(i)])];
    order[static_cast<std::size_t>(i)] = {seg.topColumn, fiveSegments[static_cast<std::size_t>(i)]};
  }
  std::sort(order.begin(), order.end());
  // The thumb is the end finger whose tip is lower (nearer the wrist).
  const int firstTop = segments_[static_cast<std::size_t>(order[0].second)].topRow;
  const int lastTop = segments_[static_cast<std::size_t>(order[4].second)].topRow;
  const bool thumbFirst = firstTop > lastTop;
  result_.axisImage = axis;
  result_.thumbSideImage = thumbFirst ? Vec2(-across) : across;
  for (int i = 0; i < 5; ++i) {
    const int j = thumbFirst ? i : 4 - i;
    const Segment& seg =
        segments_[static_cast<std::size_t>(order[static_cast<std::size_t>(j)].second)];
    // Step a little into the finger so the depth sample is on it, not its edge.
    const float sTip = sMax - static_cast<float>(seg.topRow) - 0.004f * pxPerM;
    const Vec2 p = c + axis * sTip + across * (tMin + seg.topColumn);
    const int u = std::clamp(static_cast<int>(std::lround(p.x())), 0, width - 1);
    const int v = std::clamp(static_cast<int>(std::lround(p.y())), 0, k.height - 1);
    float depth = cloud.depthAt(u, v);
    for (int r = 1; depth <= 0.0f && r <= 3; ++r) {  // nearest valid sample nearby
      for (int dv = -r; dv <= r && depth <= 0.0f; ++dv) {
        for (int du = -r; du <= r && depth <= 0.0f; ++du) {
          const int uu = std::clamp(u + du, 0, width - 1), vv = std::clamp(v + dv, 0, k.height - 1);
          if (cloud.mask[static_cast<std::size_t>(vv * width + uu)]) depth = cloud.depthAt(uu, vv);
        }
      }
    }
    if (depth <= 0.0f) return false;
    result_.tipPixels[static_cast<std::size_t>(i)] = p;
    result_.tips[static_cast<std::size_t>(i)] = k.deproject(p.x(), p.y(), depth);
  }
  return true;
}

}  // namespace dynahand::track
