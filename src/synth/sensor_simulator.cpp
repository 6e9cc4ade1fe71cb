// Degrades exact rendered depth the way each kind of camera does (see synth_sensor.h).
// Order: range gate on the true depth, geometric effects (flying pixels, projector
// shadows, thin-feature loss, edge fattening, left band), per-pixel noise and
// quantisation, speckle, random dropout, holes, then storage in depth units.
#include <algorithm>
#include <cassert>
#include <cmath>

#include "dynahand/synth_sensor.h"
#include "random.h"

namespace dynahand::synth {
namespace {

using detail::bits;
using detail::normal;
using detail::uniform;
using detail::uniformLow;

// Random streams, one per decision, so effects do not share random numbers.
enum Stream : std::uint64_t {
  kNoise = 1,
  kDropout,
  kFlyDecide,
  kFlyMix,
  kThin,
  kSpeckleDecide,
  kSpeckleSize,
  kHoleX,
  kHoleY
};

constexpr float kFar = 1e4f;  // stands for "no surface" inside the morphology filters, m

// Running max (isMax) or min over a window of +-radius along rows or columns.
void windowFilter(const std::vector<float>& src, std::vector<float>& dst, int w, int h, int radius,
                  bool alongRows, bool isMax) {
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      float best = src[static_cast<std::size_t>(v) * w + u];
      for (int o = -radius; o <= radius; ++o) {
        const int uu = alongRows ? u + o : u, vv = alongRows ? v : v + o;
        if (uu < 0 || vv < 0 || uu >= w || vv >= h) continue;
        const float x = src[static_cast<std::size_t>(vv) * w + uu];
        best = isMax ? std::max(best, x) : std::min(best, x);
      }
      dst[static_cast<std::size_t>(v) * w + u] = best;
    }
  }
}

}  // namespace

SensorSimulator::SensorSimulator(SensorProfile profile, std::uint64_t seed)
    : profile_(std::move(profile)), seed_(seed) {
  const std::size_t n =
      static_cast<std::size_t>(profile_.intrinsics.width) * profile_.intrinsics.height;
  work_.assign(n, 0.0f);
  scratch_.assign(n, 0.0f);
  scratch2_.assign(n, 0.0f);
}

void SensorSimulator::apply(std::span<const float> trueDepth, std::span<const PixelLabel> labels,
                            int frameIndex, double timestamp, DepthFrame& out) {
  const SensorProfile& p = profile_;
  const int w = p.intrinsics.width, h = p.intrinsics.height;
  const std::size_t n = static_cast<std::size_t>(w) * h;
  assert(trueDepth.size() == n && labels.size() == n);
  (void)labels;
  if (out.width != w || out.height != h || out.depth.size() != n)
    out = DepthFrame(w, h, p.depthScale);
  out.depthScale = p.depthScale;
  out.timestamp = timestamp;
  const std::uint64_t key = detail::frameKey(seed_, frameIndex);

  for (std::size_t i = 0; i < n; ++i) {
    const float z = trueDepth[i];
    work_[i] = (z >= p.minRange && z <= p.maxRange) ? z : 0.0f;
  }

  switch (p.kind) {
    case SensorKind::Ideal:
      break;
    case SensorKind::TimeOfFlight:
      flyingPixels(trueDepth, key);
      break;
    case SensorKind::StructuredLight:
      if (p.projectorShadows) shadows();
      if (p.thinRadiusPx > 0) thinFeatures(key);
      break;
    case SensorKind::ActiveStereo:
      if (p.edgeFatteningPx > 0) fattenEdges();
      break;
  }

  const bool triangulating = p.baseline > 0.0f && p.disparityStep > 0.0f;
  const float focalBaseline = p.intrinsics.fx * p.baseline;  // px m
  // Disparity noise equivalent to sigma(z) = noiseAtHalfMetre (z / 0.5)^2.
  const float disparitySigma = triangulating ? p.noiseAtHalfMetre * focalBaseline / 0.25f : 0.0f;
  const float inverseStep = triangulating ? 1.0f / p.disparityStep : 0.0f;
  const float noiseScale = p.noiseAtHalfMetre * 4.0f;  // sigma(z) = noiseScale z^2
  const bool random =
      p.noiseAtHalfMetre > 0.0f || p.dropoutFraction > 0.0f || p.speckleFraction > 0.0f;
  for (std::size_t i = 0; i < n; ++i) {
    float z = work_[i];
    if (z <= 0.0f || !random) continue;
    // One 64-bit draw per pixel: the top 12 bits pick the normal sample, the low 24 bits
    // decide dropout (independent bits of the same mixed value).
    const std::uint64_t r = bits(key, i, kNoise);
    if (p.kind == SensorKind::TimeOfFlight) {
      z += noiseScale * z * z * normal(r);
    } else if (triangulating) {
      float d = focalBaseline / z + disparitySigma * normal(r);
      d = std::round(d * inverseStep) * p.disparityStep;
      z = d > 0.0f ? focalBaseline / d : 0.0f;
      if (p.leftInvalidBand && static_cast<float>(i % static_cast<std::size_t>(w)) < d) z = 0.0f;
    }
    if (p.speckleFraction > 0.0f && uniform(bits(key, i, kSpeckleDecide)) < p.speckleFraction) {
      const std::uint64_t rs = bits(key, i, kSpeckleSize);
      const float size = 0.02f + 0.06f * uniform(rs);
      z += (rs & 1u) ? size : -size;
    }
    if (uniformLow(r) < p.dropoutFraction) z = 0.0f;
    work_[i] = z;
  }
  if (p.holeFraction > 0.0f) holes(key);

  const float inverseScale = 1.0f / p.depthScale;
  for (std::size_t i = 0; i < n; ++i) {
    const float units = work_[i] * inverseScale + 0.5f;
    out.depth[i] = (units >= 1.0f && units < 65536.0f) ? static_cast<std::uint16_t>(units) : 0;
  }
}

// Time of flight: a pixel straddling a depth jump integrates light from both surfaces
// and reads a depth between them (or trails off behind the silhouette into nothing).
void SensorSimulator::flyingPixels(std::span<const float> depth, std::uint64_t key) {
  const SensorProfile& p = profile_;
  const int w = p.intrinsics.width, h = p.intrinsics.height;
  constexpr float kTrail = 0.15f;  // m, how far behind a silhouette over empty space
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * w + u;
      const float z = work_[i];
      if (z <= 0.0f) continue;
      float target = z, jump = 0.0f;
      const int du[4] = {-1, 1, 0, 0}, dv[4] = {0, 0, -1, 1};
      for (int k = 0; k < 4; ++k) {
        const int uu = u + du[k], vv = v + dv[k];
        if (uu < 0 || vv < 0 || uu >= w || vv >= h) continue;
        const float zn = depth[static_cast<std::size_t>(vv) * w + uu];
        const float other = zn > 0.0f ? zn : z + kTrail;
        if (std::fabs(other - z) > jump) {
          jump = std::fabs(other - z);
          target = other;
        }
      }
      if (jump <= p.edgeJump || uniform(bits(key, i, kFlyDecide)) >= p.flyingPixelProbability)
        continue;
      const float z2 = z + uniform(bits(key, i, kFlyMix)) * (target - z);
      work_[i] = (z2 >= p.minRange && z2 <= p.maxRange) ? z2 : 0.0f;
    }
  }
}

// Structured light: the projector (baseline to the right of the camera) cannot light
// background just left of a near object. Scanning each row from the projector's side, a
// pixel is shadowed when a pixel further right maps to a smaller projector column.
void SensorSimulator::shadows() {
  const SensorProfile& p = profile_;
  const int w = p.intrinsics.width, h = p.intrinsics.height;
  const float focalBaseline = p.intrinsics.fx * p.baseline;
  for (int v = 0; v < h; ++v) {
    float runMin = INFINITY;
    for (int u = w - 1; u >= 0; --u) {
      const std::size_t i = static_cast<std::size_t>(v) * w + u;
      const float z = work_[i];
      if (z <= 0.0f) continue;
      const float projectorColumn = static_cast<float>(u) - focalBaseline / z;
      if (projectorColumn > runMin)
        work_[i] = 0.0f;
      else
        runMin = projectorColumn;
    }
  }
}

// Structured light: the correlation window cannot resolve near features narrower than
// the window (fingertips, fingers seen edge-on). A grey-level closing of depth (max then
// min filter) removes near protrusions narrower than the window; what it removed drops.
void SensorSimulator::thinFeatures(std::uint64_t key) {
  const SensorProfile& p = profile_;
  const int w = p.intrinsics.width, h = p.intrinsics.height;
  const std::size_t n = work_.size();
  for (std::size_t i = 0; i < n; ++i) scratch_[i] = work_[i] > 0.0f ? work_[i] : kFar;
  windowFilter(scratch_, scratch2_, w, h, p.thinRadiusPx, true, true);
  windowFilter(scratch2_, scratch_, w, h, p.thinRadiusPx, false, true);
  windowFilter(scratch_, scratch2_, w, h, p.thinRadiusPx, true, false);
  windowFilter(scratch2_, scratch_, w, h, p.thinRadiusPx, false, false);
  for (std::size_t i = 0; i < n; ++i) {
    if (work_[i] > 0.0f && scratch_[i] - work_[i] > p.edgeJump &&
        uniform(bits(key, i, kThin)) < p.thinDropProbability)
      work_[i] = 0.0f;
  }
}

// Active stereo: block matching assigns the nearer surface's disparity to pixels within
// the block of a depth edge, so foreground grows onto background along rows.
void SensorSimulator::fattenEdges() {
  const SensorProfile& p = profile_;
  const int w = p.intrinsics.width, h = p.intrinsics.height;
  std::copy(work_.begin(), work_.end(), scratch_.begin());
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * w + u;
      float nearest = scratch_[i] > 0.0f ? scratch_[i] : kFar;
      for (int o = -p.edgeFatteningPx; o <= p.edgeFatteningPx; ++o) {
        const int uu = u + o;
        if (uu < 0 || uu >= w) continue;
        const float zn = scratch_[static_cast<std::size_t>(v) * w + uu];
        if (zn > 0.0f && zn < nearest - p.edgeJump) nearest = zn;
      }
      if (nearest < kFar) work_[i] = nearest;
    }
  }
}

// Active stereo: untextured or unmatched patches read as holes. Disc centres are uniform
// over the image grown by the radius, so every pixel is covered with the same
// probability 1 - (1 - pi r^2 / area)^count, and count is chosen to give holeFraction.
void SensorSimulator::holes(std::uint64_t key) {
  const SensorProfile& p = profile_;
  const int w = p.intrinsics.width, h = p.intrinsics.height;
  const float r = p.holeRadiusPx;
  const float areaW = static_cast<float>(w) + 2.0f * r, areaH = static_cast<float>(h) + 2.0f * r;
  const double perDisc =
      M_PI * static_cast<double>(r * r) / (static_cast<double>(areaW) * static_cast<double>(areaH));
  const int count = static_cast<int>(
      std::lround(std::log(1.0 - static_cast<double>(p.holeFraction)) / std::log(1.0 - perDisc)));
  for (int k = 0; k < count; ++k) {
    const float cu = -0.5f - r + areaW * uniform(bits(key, static_cast<std::uint64_t>(k), kHoleX));
    const float cv = -0.5f - r + areaH * uniform(bits(key, static_cast<std::uint64_t>(k), kHoleY));
    const int u0 = std::max(0, static_cast<int>(std::ceil(cu - r)));
    const int u1 = std::min(w - 1, static_cast<int>(std::floor(cu + r)));
    const int v0 = std::max(0, static_cast<int>(std::ceil(cv - r)));
    const int v1 = std::min(h - 1, static_cast<int>(std::floor(cv + r)));
    for (int v = v0; v <= v1; ++v)
      for (int u = u0; u <= u1; ++u) {
        const float du = static_cast<float>(u) - cu, dv = static_cast<float>(v) - cv;
        if (du * du + dv * dv <= r * r) work_[static_cast<std::size_t>(v) * w + u] = 0.0f;
      }
  }
}

}  // namespace dynahand::synth
