#include "track/finger_detector.h"

#include <algorithm>
#include <cmath>

namespace dynahand::track {

const FingerDetection& FingerDetector::detect(const CloudFrame& cloud) {
  result_.fired = false;
  if (!cloud.segment.found || cloud.segmentBox.empty()) return result_;
  const Intrinsics& k = cloud.intrinsics;
  const int width = k.width;

  // Mask centroid and extent.
  double su = 0, sv = 0;
  int count = 0;
  const PixelBox& box = cloud.segmentBox;
  for (int v = box.y0; v < box.y1; ++v) {
    for (int u = box.x0; u < box.x1; ++u) {
      if (cloud.mask[static_cast<std::size_t>(v * width + u)]) {
        su += u;
        sv += v;
        ++count;
      }
    }
  }
  if (count < 50) return result_;
  const Vec2 c(static_cast<float>(su / count), static_cast<float>(sv / count));
  Vec2 axis(0.0f, -1.0f);  // fingers up when there is no arm direction
  if (cloud.segment.armDirectionImage.norm() > 0.5f)
    axis = -cloud.segment.armDirectionImage.normalized();
  const Vec2 across(-axis.y(), axis.x());

  float sMax = -1e9f, tMin = 1e9f, tMax = -1e9f;
  for (int v = box.y0; v < box.y1; ++v) {
    for (int u = box.x0; u < box.x1; ++u) {
      if (!cloud.mask[static_cast<std::size_t>(v * width + u)]) continue;
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

  auto masked = [&](float s, float t) {
    const Vec2 p = c + axis * s + across * t;
    const int u = static_cast<int>(std::lround(p.x())), v = static_cast<int>(std::lround(p.y()));
    if (!box.contains(u, v)) return false;
    return cloud.mask[static_cast<std::size_t>(v * width + u)] != 0;
  };

  segments_.clear();
  previousRuns_.clear();
  int fiveRow = -1;
  std::array<int, 5> fiveSegments{};
  for (int row = 0; row < rows; ++row) {
    const float s = sMax - static_cast<float>(row);
    runs_.clear();
    int begin = -1, gap = 0;
    for (int col = 0; col <= columns; ++col) {
      const bool on = col < columns && masked(s, tMin + static_cast<float>(col));
      if (on) {
        if (begin < 0) begin = col;
        gap = 0;
      } else if (begin >= 0 && ++gap > 1) {  // a 1-sample gap does not split a run
        runs_.push_back({begin, col - gap + 1, -1});
        begin = -1;
        gap = 0;
      }
    }
    // Continue segments: a run overlapping previous runs joins the first one's segment;
    // overlapping several means they came together.
    for (Run& run : runs_) {
      for (const Run& prev : previousRuns_) {
        if (prev.end > run.begin && prev.begin < run.end) {
          if (run.segment < 0) {
            run.segment = prev.segment;
          }
        }
      }
      if (run.segment < 0) {
        run.segment = static_cast<int>(segments_.size());
        segments_.push_back({row, 0.5f * static_cast<float>(run.begin + run.end - 1), 0});
      }
      ++segments_[static_cast<std::size_t>(run.segment)].length;
    }
    if (fiveRow < 0 && runs_.size() == 5) {
      bool fingerLike = true;
      for (int i = 0; i < 5; ++i) {
        const Run& r = runs_[static_cast<std::size_t>(i)];
        const float w = static_cast<float>(r.end - r.begin);
        fingerLike = fingerLike && w >= minWidth && w <= maxWidth;
        for (int j = 0; j < i; ++j)
          fingerLike = fingerLike && runs_[static_cast<std::size_t>(j)].segment != r.segment;
      }
      if (fingerLike) {
        fiveRow = row;
        for (int i = 0; i < 5; ++i)
          fiveSegments[static_cast<std::size_t>(i)] = runs_[static_cast<std::size_t>(i)].segment;
      }
    }
    // Fire once the five fingers have come together into at most two runs (palm, and
    // possibly the thumb still apart) and each finger was long enough.
    if (fiveRow >= 0 && runs_.size() <= 2 && row > fiveRow) {
      bool longEnough = true;
      for (int segIndex : fiveSegments) {
        longEnough =
            longEnough && segments_[static_cast<std::size_t>(segIndex)].length >= minLength;
      }
      if (!longEnough) return result_;
      // Fingertips: the top of each segment, ordered across the hand.
      std::array<std::pair<float, int>, 5> order;
      for (int i = 0; i < 5; ++i) {
        const Segment& seg =
            segments_[static_cast<std::size_t>(fiveSegments[static_cast<std::size_t>(i)])];
        order[static_cast<std::size_t>(i)] = {seg.topColumn,
                                              fiveSegments[static_cast<std::size_t>(i)]};
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
              const int uu = std::clamp(u + du, 0, width - 1),
                        vv = std::clamp(v + dv, 0, k.height - 1);
              if (cloud.mask[static_cast<std::size_t>(vv * width + uu)])
                depth = cloud.depthAt(uu, vv);
            }
          }
        }
        if (depth <= 0.0f) return result_;
        result_.tipPixels[static_cast<std::size_t>(i)] = p;
        result_.tips[static_cast<std::size_t>(i)] = k.deproject(p.x(), p.y(), depth);
      }
      result_.fired = true;
      return result_;
    }
    std::swap(runs_, previousRuns_);
  }
  return result_;
}

}  // namespace dynahand::track
