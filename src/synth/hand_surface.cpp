// The synthetic hand's render surface built from its skeleton, and hand proportions (per-bone
// length and per-finger thickness factors of the rendered hand; see synth_render.h).
#include <cassert>
#include <cmath>

#include "dynahand/synth_render.h"
#include "random.h"

namespace dynahand::synth {
namespace {

// First keypoint of each finger chain (thumb CMC, index MCP, ...).
constexpr int kFingerBase[5] = {1, 5, 9, 13, 17};

Vec3 safeNormalized(const Vec3& v, const Vec3& fallback) {
  const float n = v.norm();
  return n > 1e-9f ? Vec3(v / n) : fallback;
}

}  // namespace

void buildHandSurface(const HandSkeleton& hand, const SurfaceRadii& radii,
                      std::vector<RoundCone>& out) {
  const HandKeypoints& kp = hand.keypoints;
  const float s = hand.scale;
  const std::size_t firstPrimitive = out.size();
  const Vec3 wrist = kp[0];

  // Palm frame: lateral runs pinky -> index MCP; the palmar normal follows the hand side.
  const Vec3 lateral = safeNormalized(kp[5] - kp[17], Vec3::UnitX());
  const Vec3 distal = safeNormalized(kp[9] - wrist, Vec3::UnitY());
  Vec3 palmar = safeNormalized(lateral.cross(distal), Vec3::UnitZ());
  if (hand.leftHand) palmar = -palmar;

  // Finger chains: base -> joint -> joint -> tip; the last sphere is pulled back so the
  // surface ends at the tip keypoint.
  for (int f = 0; f < 5; ++f) {
    const int base = kFingerBase[f];
    const auto& r = radii.finger[static_cast<std::size_t>(f)];
    for (int j = 0; j < 3; ++j) {
      const Vec3& a = kp[static_cast<std::size_t>(base + j)];
      Vec3 b = kp[static_cast<std::size_t>(base + j + 1)];
      const float ra = r[static_cast<std::size_t>(j)] * s;
      const float rb = r[static_cast<std::size_t>(j + 1)] * s;
      if (j == 2) b -= safeNormalized(b - a, distal) * (0.5f * rb);
      out.push_back({a, b, ra, rb});
    }
    // Fingertip pad: a sphere bulging palmar of the distal bone's middle.
    const Vec3& dip = kp[static_cast<std::size_t>(base + 2)];
    const Vec3& tip = kp[static_cast<std::size_t>(base + 3)];
    const Vec3 boneDir = safeNormalized(tip - dip, distal);
    const Vec3 padDir = safeNormalized(palmar - palmar.dot(boneDir) * boneDir, palmar);
    const float padRadius = r[3] * s;
    out.push_back(
        {0.5f * (dip + tip) + padDir * (radii.padOffset * s), Vec3::Zero(), padRadius, padRadius});
    out.back().b = out.back().a;
  }

  // Palm slab: cones from a row of base points near the wrist to each MCP, plus cones
  // half-way between neighbours so the slab's surface has only shallow grooves.
  const float palmR = radii.palmHalfThickness * s;
  Vec3 basePoint[4];
  for (int f = 1; f < 5; ++f) {
    const Vec3 toMcp = kp[static_cast<std::size_t>(kFingerBase[f])] - wrist;
    basePoint[f - 1] = wrist + 0.7f * toMcp.dot(lateral) * lateral + 0.12f * toMcp;
  }
  for (int f = 1; f < 5; ++f)
    out.push_back({basePoint[f - 1], kp[static_cast<std::size_t>(kFingerBase[f])], palmR, palmR});
  for (int f = 1; f < 4; ++f) {
    const Vec3 mcpMid = 0.5f * (kp[static_cast<std::size_t>(kFingerBase[f])] +
                                kp[static_cast<std::size_t>(kFingerBase[f + 1])]);
    out.push_back({0.5f * (basePoint[f - 1] + basePoint[f]), mcpMid, palmR, palmR});
  }
  out.push_back({basePoint[0], basePoint[3], palmR, palmR});

  // Thenar eminence: fills between the thumb metacarpal and the index metacarpal.
  const float thenarR = radii.finger[0][0] * s;
  out.push_back({basePoint[0], kp[1], palmR, thenarR});
  out.push_back({basePoint[0], 0.5f * (kp[2] + kp[5]), palmR, 0.85f * thenarR});

  // Forearm: two parallel cones make its cross-section wider than thick.
  const Vec3 forearmDir = safeNormalized(hand.elbow - wrist, -distal);
  const Vec3 side = safeNormalized(lateral - lateral.dot(forearmDir) * forearmDir, lateral);
  const float spread = 0.35f * radii.wrist * s;
  const float wristR = 0.75f * radii.wrist * s, elbowR = 0.75f * radii.elbow * s;
  out.push_back({wrist + side * spread, hand.elbow + side * (1.4f * spread), wristR, elbowR});
  out.push_back({wrist - side * spread, hand.elbow - side * (1.4f * spread), wristR, elbowR});
  if (hand.shoulder) {
    // Upper arm: one cone as wide as the forearm's two at the elbow, thicker at the shoulder.
    const float upperR = elbowR + 1.4f * spread;
    out.push_back({hand.elbow, *hand.shoulder, upperR, 1.2f * upperR});
  }

  assert(out.size() - firstPrimitive <= static_cast<std::size_t>(kMaxHandPrimitives));
  (void)firstPrimitive;
}

HandProportions randomProportions(std::uint64_t seed, float spread) {
  HandProportions p;
  if (spread == 0.0f) return p;
  const std::uint64_t key = detail::mix64(seed ^ 0x70726F706F72ull);  // "propor"
  std::uint64_t index = 0;
  const auto next = [&] {
    const float u = detail::uniform(detail::bits(key, index++, 7));
    return 1.0f + spread * (2.0f * u - 1.0f);
  };
  for (auto& finger : p.boneLength)
    for (float& f : finger) f = next();
  for (float& f : p.fingerThickness) f = next();
  p.palmThickness = next();
  return p;
}

void applyProportions(const HandProportions& p, HandKeypoints& keypoints) {
  if (p.identity()) return;
  const HandKeypoints original = keypoints;
  for (int f = 0; f < 5; ++f) {
    const auto& lengths = p.boneLength[static_cast<std::size_t>(f)];
    std::size_t parent = 0;  // the wrist
    for (int b = 0; b < 4; ++b) {
      const auto child = static_cast<std::size_t>(kFingerBase[f] + b);
      keypoints[child] = keypoints[parent] + lengths[static_cast<std::size_t>(b)] *
                                                 (original[child] - original[parent]);
      parent = child;
    }
  }
}

SurfaceRadii scaledRadii(const SurfaceRadii& radii, const HandProportions& p) {
  SurfaceRadii out = radii;
  for (std::size_t f = 0; f < 5; ++f)
    for (float& r : out.finger[f]) r *= p.fingerThickness[f];
  out.palmHalfThickness *= p.palmThickness;
  return out;
}

}  // namespace dynahand::synth
