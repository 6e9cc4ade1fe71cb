// The paper's naive five-finger detector ("Feature Detection"): scanlines across the
// hand's segmentation mask, from the fingertips toward the wrist, follow contiguous
// segments; it fires when five finger-wide segments have each run far enough on their
// own and then come together (the palm; the thumb, lower on the hand, may start after the
// four fingers have met). The top of each segment is a fingertip. Scanlines run across
// the hand axis (away from where the arm leaves the region, turned up to 40 degrees either
// way when that fails), so a hand rotated in the image plane is found too.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "dynahand/cloud.h"

namespace dynahand::track {

struct FingerDetectorSettings {
  float minFingerWidthM = 0.005f;   // narrower runs are noise (m)
  float maxFingerWidthM = 0.035f;   // wider runs are not a single finger (m)
  float minFingerLengthM = 0.015f;  // a segment must run this long before it counts (m)
  float maxScanLengthM = 0.16f;     // scan from the top this far toward the wrist (m)
};

struct FingerDetection {
  bool fired = false;
  // Fingertips ordered thumb, index, middle, ring, pinky (camera frame, m) when fired.
  std::array<Vec3, 5> tips{};
  std::array<Vec2, 5> tipPixels{};
  Vec2 axisImage = Vec2(0, -1);      // unit, wrist -> fingertips in the image
  Vec2 thumbSideImage = Vec2(1, 0);  // unit, across the hand toward the thumb
};

// A run of on-mask samples along one scanline: columns [begin, end).
struct ScanlineRun {
  int begin, end;
  int segment = -1;  // FingerDetector's: the segment it continues
};
// The runs of one scanline's samples (sample col on the mask: bit col % 64 of on[col / 64];
// `columns` samples, the bits beyond them zero), into `runs`: a one-sample gap does not
// split a run, and a run still open at the last sample is left out (it may go on past the
// mask's extent).
void scanlineRuns(const std::uint64_t* on, int columns, std::vector<ScanlineRun>& runs);

class FingerDetector {
 public:
  explicit FingerDetector(const FingerDetectorSettings& settings = {}) : settings_(settings) {}
  // Looks for an open hand in the cloud's segmentation mask.
  const FingerDetection& detect(const CloudFrame& cloud);

 private:
  using Run = ScanlineRun;
  struct Segment {
    int topRow;
    float topColumn;
    int length;               // rows
    bool decided = false;     // fingerLike is final (minLength rows reached, or merged first)
    bool fingerLike = false;  // ran minLength rows apart from the others, finger-wide
  };
  // One scan with scanlines across `axis` (wrist -> fingertips, image) through the mask
  // centroid c; fills result_ and returns true when it fires.
  bool scanAlong(const CloudFrame& cloud, const Vec2& c, const Vec2& axis);
  // scanAlong's stages: this row's runs_ continue the segments of previousRuns_ (a segment
  // is decided finger-like or not once minLength rows long, or when it merges); and, once five
  // finger-like segments were seen, the fingertips at their tops into result_ (false when a
  // tip has no depth near it).
  void continueSegments(int row, int minLength, float minWidth, float maxWidth);
  struct TipFrame {
    Vec2 centre;   // the mask centroid c, pixels
    Vec2 axis;     // wrist -> fingertips, image, unit
    float sMax;    // the scan's first row along axis from c, pixels
    float tMin;    // the scanlines' first sample across axis from c, pixels
    float pxPerM;  // pixels per metre at the hand's depth
  };
  bool placeTips(const CloudFrame& cloud, const TipFrame& frame,
                 const std::array<int, 5>& fiveSegments);
  FingerDetectorSettings settings_;
  FingerDetection result_;
  std::vector<Run> runs_, previousRuns_;
  std::vector<Segment> segments_;
  // Per row of the segment box, the first and last mask column (-1: none), found once per
  // frame: a projection of the pixels on a direction is monotonic along a row, so its extremes
  // over the mask are at those two pixels, for every scan direction.
  std::vector<int> rowFirst_, rowLast_;
  std::vector<std::uint64_t> rowSamples_;  // one scanline's samples, bit per column: on mask
};

}  // namespace dynahand::track
