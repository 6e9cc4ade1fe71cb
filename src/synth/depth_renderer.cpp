// Analytic ray casting of round cones (sphere-swept tapered capsules) and planes.
//
// Round cone math. Spheres (a, ra) and (b, rb), axis w = (b - a) / L, d = (ra - rb) / L,
// k = sqrt(1 - d^2). The cone tangent to both spheres touches sphere a at axial offset
// s = ra d and sphere b at s = L + rb d; between those, its radius at axial coordinate s
// (measured from a along w) is rho(s) = ra / k - (d / k) s. A ray point p = t dir with
// q = p - a, s = q.w satisfies |q|^2 - s^2 = rho(s)^2, a quadratic in t:
//   alpha t^2 - 2 beta t + gamma = 0,  alpha = D - e^2 / k^2,  beta = g - e f + h m e,
//   gamma = A - f^2 - h^2,
// with D = dir.dir, g = dir.a, e = dir.w, f = a.w, A = a.a, m = -d / k, h = ra / k - m f.
// The solid is the union of the two spheres and the truncated cone, so (camera outside)
// the first hit is the smallest positive crossing of either sphere or of the cone's side
// within s in [ra d, L + rb d]; the cone's end caps lie inside the spheres.
#include <algorithm>
#include <cassert>
#include <cmath>

#include "dynahand/synth_render.h"

namespace dynahand::synth {
namespace {

// Primitives closer than this to the camera plane are truncated (m).
constexpr float kNearPlane = 0.05f;

// Per-primitive constants of the ray test (see the top comment).
struct ConeTerms {
  Vec3 a, b, w;
  float raSq, rbSq, aa, bb;
  bool hasSide;      // false: one sphere contains the other (only spheres are tested)
  float invKSq;      // 1 / k^2
  float f, h, m;     // see the top comment
  float gammaSide;   // A - f^2 - h^2
  float sMin, sMax;  // axial range of the cone's side, m
  Vec3 centre;       // bounding sphere of the whole primitive
  float boundSq;
  float centreSq;
};

ConeTerms makeTerms(const RoundCone& c) {
  ConeTerms t{};
  t.a = c.a;
  t.b = c.b;
  t.raSq = c.ra * c.ra;
  t.rbSq = c.rb * c.rb;
  t.aa = c.a.squaredNorm();
  t.bb = c.b.squaredNorm();
  const Vec3 ab = c.b - c.a;
  const float length = ab.norm();
  const float d = length > 1e-7f ? (c.ra - c.rb) / length : 2.0f;
  t.hasSide = std::fabs(d) < 0.999f;
  if (t.hasSide) {
    t.w = ab / length;
    const float kSq = 1.0f - d * d;
    const float k = std::sqrt(kSq);
    t.invKSq = 1.0f / kSq;
    t.m = -d / k;
    t.f = c.a.dot(t.w);
    t.h = c.ra / k - t.m * t.f;
    t.gammaSide = t.aa - t.f * t.f - t.h * t.h;
    t.sMin = c.ra * d;
    t.sMax = length + c.rb * d;
  } else {
    t.w = Vec3::UnitZ();
  }
  t.centre = 0.5f * (c.a + c.b);
  const float bound = 0.5f * length + std::max(c.ra, c.rb);
  t.boundSq = bound * bound;
  t.centreSq = t.centre.squaredNorm();
  return t;
}

// Nearest positive sphere hit along t * dir, or +inf.
inline float sphereHit(float dd, float g, float cc, float rSq) {
  const float disc = g * g - dd * (cc - rSq);
  if (disc < 0.0f) return INFINITY;
  const float t = (g - std::sqrt(disc)) / dd;
  return t > 0.0f ? t : INFINITY;
}

inline float hitTerms(const ConeTerms& c, const Vec3& dir) {
  const float dd = dir.squaredNorm();
  const float ga = dir.dot(c.a);
  const float gb = dir.dot(c.b);
  float best = std::min(sphereHit(dd, ga, c.aa, c.raSq), sphereHit(dd, gb, c.bb, c.rbSq));
  if (!c.hasSide) return best;
  const float e = dir.dot(c.w);
  const float alpha = dd - e * e * c.invKSq;
  const float beta = ga - e * c.f + c.h * c.m * e;
  const float disc = beta * beta - alpha * c.gammaSide;
  if (disc < 0.0f || std::fabs(alpha) < 1e-12f) return best;
  const float root = std::sqrt(disc);
  const float roots[2] = {(beta - root) / alpha, (beta + root) / alpha};
  for (const float t : roots) {
    if (t <= 0.0f || t >= best) continue;
    const float s = t * e - c.f;
    if (s >= c.sMin && s <= c.sMax) best = t;
  }
  return best;
}

// Moves an end of the cone whose sphere crosses the near plane back along the axis so
// that the whole primitive lies beyond it. Returns false when nothing remains.
bool clipToNearPlane(RoundCone& c) {
  auto clearance = [](const Vec3& p, float r) { return p.z() - r - kNearPlane; };
  const float ca = clearance(c.a, c.ra);
  const float cb = clearance(c.b, c.rb);
  if (ca >= 0.0f && cb >= 0.0f) return true;
  if (ca < 0.0f && cb < 0.0f) return false;
  // clearance is linear along the segment: find where it is zero (plus a small margin).
  const float s = ca / (ca - cb);
  const float cut = ca < 0.0f ? std::min(1.0f, s + 1e-3f) : std::max(0.0f, s - 1e-3f);
  const Vec3 p = c.a + cut * (c.b - c.a);
  const float r = c.ra + cut * (c.rb - c.ra);
  if (ca < 0.0f) {
    c.a = p;
    c.ra = r;
  } else {
    c.b = p;
    c.rb = r;
  }
  return true;
}

// Conservative pixel range of a sphere: the box [x +- r] x [z +- r] contains it and x / z
// is extreme at that box's corners.
void extendBounds(const Vec3& c, float r, const Intrinsics& k, float& u0, float& u1, float& v0,
                  float& v1) {
  const float zn = c.z() - r, zf = c.z() + r;
  const float xl = c.x() - r, xr = c.x() + r, yt = c.y() - r, yb = c.y() + r;
  u0 = std::min(u0, k.fx * std::min(xl / zn, xl / zf) + k.cx);
  u1 = std::max(u1, k.fx * std::max(xr / zn, xr / zf) + k.cx);
  v0 = std::min(v0, k.fy * std::min(yt / zn, yt / zf) + k.cy);
  v1 = std::max(v1, k.fy * std::max(yb / zn, yb / zf) + k.cy);
}

}  // namespace

float intersectRoundCone(const RoundCone& cone, const Vec3& dir) {
  const float t = hitTerms(makeTerms(cone), dir);
  return std::isfinite(t) ? t : -1.0f;
}

DepthRenderer::DepthRenderer(const Intrinsics& intrinsics) : intrinsics_(intrinsics) {
  assert(intrinsics.width > 0 && intrinsics.height > 0 && intrinsics.fx > 0 && intrinsics.fy > 0);
  rayX_.resize(static_cast<std::size_t>(intrinsics.width));
  rayY_.resize(static_cast<std::size_t>(intrinsics.height));
  for (int u = 0; u < intrinsics.width; ++u)
    rayX_[static_cast<std::size_t>(u)] = (static_cast<float>(u) - intrinsics.cx) / intrinsics.fx;
  for (int v = 0; v < intrinsics.height; ++v)
    rayY_[static_cast<std::size_t>(v)] = (static_cast<float>(v) - intrinsics.cy) / intrinsics.fy;
  const std::size_t n = static_cast<std::size_t>(intrinsics.width) * intrinsics.height;
  depth_.assign(n, 0.0f);
  backgroundDepth_.assign(n, 0.0f);
  labels_.assign(n, PixelLabel::Empty);
  backgroundLabels_.assign(n, PixelLabel::Empty);
}

void DepthRenderer::setBackground(std::span<const Plane> planes,
                                  std::span<const RoundCone> solids) {
  std::fill(backgroundDepth_.begin(), backgroundDepth_.end(), 0.0f);
  std::fill(backgroundLabels_.begin(), backgroundLabels_.end(), PixelLabel::Empty);
  const int w = intrinsics_.width;
  for (const Plane& plane : planes) {
    for (int v = 0; v < intrinsics_.height; ++v) {
      for (int u = 0; u < w; ++u) {
        const Vec3 dir(rayX_[static_cast<std::size_t>(u)], rayY_[static_cast<std::size_t>(v)],
                       1.0f);
        const float denom = plane.normal.dot(dir);
        if (std::fabs(denom) < 1e-9f) continue;
        const float t = plane.offset / denom;  // depth, since dir.z == 1
        if (t <= kNearPlane) continue;
        const std::size_t i = static_cast<std::size_t>(v) * w + u;
        if (backgroundDepth_[i] == 0.0f || t < backgroundDepth_[i]) {
          backgroundDepth_[i] = t;
          backgroundLabels_[i] = PixelLabel::Background;
        }
      }
    }
  }
  for (const RoundCone& solid : solids)
    drawOne(solid, PixelLabel::Background, backgroundDepth_, backgroundLabels_);
  clear();
}

void DepthRenderer::clear() {
  std::copy(backgroundDepth_.begin(), backgroundDepth_.end(), depth_.begin());
  std::copy(backgroundLabels_.begin(), backgroundLabels_.end(), labels_.begin());
}

void DepthRenderer::draw(std::span<const RoundCone> primitives, PixelLabel label) {
  testedPixels_ = 0;
  for (const RoundCone& cone : primitives) drawOne(cone, label, depth_, labels_);
}

void DepthRenderer::draw(const OrientedBox& box, PixelLabel label) {
  testedPixels_ = 0;
  const Intrinsics& k = intrinsics_;
  // The projected bounding rectangle of the eight corners.
  float u0 = INFINITY, u1 = -INFINITY, v0 = INFINITY, v1 = -INFINITY;
  for (int corner = 0; corner < 8; ++corner) {
    Vec3 p = box.centre;
    for (int axis = 0; axis < 3; ++axis) {
      const float sign = (corner >> axis) & 1 ? 1.0f : -1.0f;
      p += sign * box.halfExtents[axis] * box.axes.col(axis);
    }
    if (p.z() <= kNearPlane) return;
    const float u = k.fx * p.x() / p.z() + k.cx;
    const float v = k.fy * p.y() / p.z() + k.cy;
    u0 = std::min(u0, u);
    u1 = std::max(u1, u);
    v0 = std::min(v0, v);
    v1 = std::max(v1, v);
  }
  const int uBegin = std::max(0, static_cast<int>(std::floor(u0)));
  const int uEnd = std::min(k.width - 1, static_cast<int>(std::ceil(u1)));
  const int vBegin = std::max(0, static_cast<int>(std::floor(v0)));
  const int vEnd = std::min(k.height - 1, static_cast<int>(std::ceil(v1)));
  // The ray in the box's frame: origin o = -R^T c, direction R^T dir; slabs |x_i| <= h_i.
  const Vec3 origin = -(box.axes.transpose() * box.centre);
  const int w = k.width;
  for (int v = vBegin; v <= vEnd; ++v) {
    for (int u = uBegin; u <= uEnd; ++u) {
      const Vec3 dir(rayX_[static_cast<std::size_t>(u)], rayY_[static_cast<std::size_t>(v)], 1.0f);
      const Vec3 local = box.axes.transpose() * dir;
      ++testedPixels_;
      float enter = 0.0f, leave = INFINITY;
      bool miss = false;
      for (int axis = 0; axis < 3 && !miss; ++axis) {
        const float h = box.halfExtents[axis];
        if (std::fabs(local[axis]) < 1e-12f) {
          miss = std::fabs(origin[axis]) > h;
          continue;
        }
        float t0 = (-h - origin[axis]) / local[axis];
        float t1 = (h - origin[axis]) / local[axis];
        if (t0 > t1) std::swap(t0, t1);
        enter = std::max(enter, t0);
        leave = std::min(leave, t1);
        miss = enter > leave;
      }
      if (miss || enter <= kNearPlane) continue;
      const std::size_t i = static_cast<std::size_t>(v) * w + static_cast<std::size_t>(u);
      if (depth_[i] == 0.0f || enter < depth_[i]) {
        depth_[i] = enter;  // depth, since dir.z == 1
        labels_[i] = label;
      }
    }
  }
}

void DepthRenderer::drawOne(const RoundCone& original, PixelLabel label, std::vector<float>& depth,
                            std::vector<PixelLabel>& labels) {
  RoundCone cone = original;
  if (!clipToNearPlane(cone)) return;
  const Intrinsics& k = intrinsics_;
  float u0 = INFINITY, u1 = -INFINITY, v0 = INFINITY, v1 = -INFINITY;
  extendBounds(cone.a, cone.ra, k, u0, u1, v0, v1);
  extendBounds(cone.b, cone.rb, k, u0, u1, v0, v1);
  const int uBegin = std::max(0, static_cast<int>(std::floor(u0)));
  const int uEnd = std::min(k.width - 1, static_cast<int>(std::ceil(u1)));
  const int vBegin = std::max(0, static_cast<int>(std::floor(v0)));
  const int vEnd = std::min(k.height - 1, static_cast<int>(std::ceil(v1)));
  if (uBegin > uEnd || vBegin > vEnd) return;
  const ConeTerms terms = makeTerms(cone);
  const int w = k.width;
  for (int v = vBegin; v <= vEnd; ++v) {
    const float ry = rayY_[static_cast<std::size_t>(v)];
    const std::size_t row = static_cast<std::size_t>(v) * w;
    for (int u = uBegin; u <= uEnd; ++u) {
      const Vec3 dir(rayX_[static_cast<std::size_t>(u)], ry, 1.0f);
      // Cheap reject against the bounding sphere (and against a nearer surface).
      const float dd = dir.squaredNorm();
      const float gc = dir.dot(terms.centre);
      const float discBound = gc * gc - dd * (terms.centreSq - terms.boundSq);
      if (discBound < 0.0f) continue;
      const std::size_t i = row + static_cast<std::size_t>(u);
      const float current = depth[i];
      if (current > 0.0f && (gc - std::sqrt(discBound)) / dd >= current) continue;
      ++testedPixels_;
      const float t = hitTerms(terms, dir);
      if (t < INFINITY && (current == 0.0f || t < current)) {
        depth[i] = t;
        labels[i] = label;
      }
    }
  }
}

}  // namespace dynahand::synth
