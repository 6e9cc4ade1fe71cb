// The detector's crop (the definition is in dynahand/detector.h): nearest-pixel resampling of
// the segmented depth around a centre on the hand, depth-normalised.
#include <algorithm>
#include <cmath>

#include "dynahand/detector.h"

namespace dynahand::detect {

Vec3 CropFrame::toCamera(const Intrinsics& k, const Vec3& uvd) const {
  const float u = mirrored ? -uvd.x() : uvd.x();
  const float pu = centreU + u * halfPixels;
  const float pv = centreV + uvd.y() * halfPixels;
  const float z = centreZ + uvd.z() * (kCropSizeM * 0.5f);
  return k.deproject(pu, pv, z);
}

Vec3 CropFrame::toCrop(const Intrinsics& k, const Vec3& p) const {
  const float pu = k.fx * p.x() / p.z() + k.cx;
  const float pv = k.fy * p.y() / p.z() + k.cy;
  float u = (pu - centreU) / halfPixels;
  if (mirrored) u = -u;
  return {u, (pv - centreV) / halfPixels, (p.z() - centreZ) / (kCropSizeM * 0.5f)};
}

namespace {

// Whether pixel (u, v) at depth z lies nearer the own hand's cluster centre than the other's.
bool ownHand(const Intrinsics& k, int u, int v, float z, const CropHandSplit& split) {
  const Vec3 p = k.deproject(static_cast<float>(u), static_cast<float>(v), z);
  return (p - split.own).squaredNorm() <= (p - split.other).squaredNorm();
}

}  // namespace

Vec3 keypointBoxCentre(const std::array<Vec3, kKeypointCount>& points) {
  Vec3 lo = points[0], hi = points[0];
  for (const Vec3& p : points) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  return 0.5f * (lo + hi);
}

bool makeCrop(const CloudFrame& cloud, bool mirrored, HandCrop& out, const Vec3* centre,
              const CropHandSplit* split) {
  const Intrinsics& k = cloud.intrinsics;
  const Vec3 c = centre != nullptr ? *centre : cloud.segment.centroid;
  if ((centre == nullptr && !cloud.segment.found) || !(c.z() > 0.05f)) return false;
  CropFrame& f = out.frame;
  f.centreU = k.fx * c.x() / c.z() + k.cx;
  f.centreV = k.fy * c.y() / c.z() + k.cy;
  f.halfPixels = k.fx * kCropSizeM * 0.5f / c.z();
  f.centreZ = c.z();
  f.mirrored = mirrored;
  out.pixels.resize(static_cast<std::size_t>(kCropPixels * kCropPixels));
  const float inverseHalfDepth = 2.0f / kCropSizeM;
  const float step = 2.0f * f.halfPixels / static_cast<float>(kCropPixels);
  const PixelBox box = cloud.segmentBox;
  for (int row = 0; row < kCropPixels; ++row) {
    const float pv = f.centreV + (static_cast<float>(row) + 0.5f) * step - f.halfPixels;
    const int v = static_cast<int>(std::lround(pv));
    float* line = out.pixels.data() + static_cast<std::ptrdiff_t>(row) * kCropPixels;
    for (int col = 0; col < kCropPixels; ++col) {
      const int x = mirrored ? kCropPixels - 1 - col : col;
      const float pu = f.centreU + (static_cast<float>(x) + 0.5f) * step - f.halfPixels;
      const int u = static_cast<int>(std::lround(pu));
      float value = 1.0f;
      if (box.contains(u, v) &&
          cloud.mask[static_cast<std::size_t>(v) * static_cast<std::size_t>(k.width) +
                     static_cast<std::size_t>(u)] != 0) {
        const float z = cloud.depthAt(u, v);
        if (z > 0.0f && (split == nullptr || ownHand(k, u, v, z, *split)))
          value = std::clamp((z - f.centreZ) * inverseHalfDepth, -1.0f, 1.0f);
      }
      line[col] = value;
    }
  }
  return true;
}

bool limbEndHandCentre(const CloudFrame& cloud, std::span<const Vec3> points, float radiusM,
                       Vec3& centre) {
  if (!cloud.segment.limbEndFound) return false;
  const Vec3& end = cloud.segment.limbEnd;
  const float limit = radiusM * radiusM;
  Vec3 sum = Vec3::Zero();
  int count = 0;
  for (const Vec3& q : points) {
    if ((q - end).squaredNorm() > limit) continue;
    sum += q;
    ++count;
  }
  if (count == 0) return false;
  centre = sum / static_cast<float>(count);
  return true;
}

}  // namespace dynahand::detect
