// Synthetic depth scenes shared by the cloud tests and benchmarks (as Box2D's shared/
// scenes): unions of spheres in front of a wall, rendered by exact ray casting.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "dynahand/depth_frame.h"

namespace dynahand::cloud::scenes {

struct Sphere {
  Vec3 centre;   // m
  float radius;  // m
};

// A pinhole camera like a 60-degree-wide depth camera at the given resolution.
inline Intrinsics camera(int width, int height) {
  Intrinsics k;
  k.width = width;
  k.height = height;
  k.fx = k.fy = 0.8660254f * static_cast<float>(width);  // 60 deg horizontal field of view
  k.cx = 0.5f * static_cast<float>(width - 1);
  k.cy = 0.5f * static_cast<float>(height - 1);
  return k;
}

// Appends spheres of `radius` every `spacing` along the segment a-b (a capsule).
inline void addCapsule(std::vector<Sphere>& out, const Vec3& a, const Vec3& b, float radius,
                       float spacing) {
  const int n = std::max(1, static_cast<int>(std::ceil((b - a).norm() / spacing)));
  for (int i = 0; i <= n; ++i) {
    out.push_back({a + (b - a) * (static_cast<float>(i) / static_cast<float>(n)), radius});
  }
}

// Depth frame (depthScale 0.001 m) of the spheres in front of a wall at wallDepthM
// (0 = no wall: no data behind the spheres).
inline DepthFrame render(const Intrinsics& k, const std::vector<Sphere>& spheres,
                         float wallDepthM) {
  DepthFrame frame(k.width, k.height, 0.001f);
  std::vector<float> z(static_cast<std::size_t>(k.width) * k.height, wallDepthM);
  for (const Sphere& s : spheres) {
    // Conservative pixel box of the sphere's projection.
    const float zNear = std::max(s.centre.z() - s.radius, 0.01f);
    const float ru = k.fx * s.radius / zNear + 2.0f;
    const float rv = k.fy * s.radius / zNear + 2.0f;
    const Vec2 c = k.project(s.centre);
    const int u0 = std::max(0, static_cast<int>(std::floor(c.x() - ru)));
    const int u1 = std::min(k.width - 1, static_cast<int>(std::ceil(c.x() + ru)));
    const int v0 = std::max(0, static_cast<int>(std::floor(c.y() - rv)));
    const int v1 = std::min(k.height - 1, static_cast<int>(std::ceil(c.y() + rv)));
    for (int v = v0; v <= v1; ++v) {
      for (int u = u0; u <= u1; ++u) {
        // Ray p = t * d with d = (x/z, y/z, 1): depth along z is t.
        const Vec3 d = k.deproject(static_cast<float>(u), static_cast<float>(v), 1.0f);
        const float a = d.squaredNorm();
        const float b = d.dot(s.centre);
        const float disc = b * b - a * (s.centre.squaredNorm() - s.radius * s.radius);
        if (disc < 0.0f) continue;
        const float t = (b - std::sqrt(disc)) / a;
        float& zz = z[static_cast<std::size_t>(v) * k.width + u];
        if (t > 0.0f && (zz == 0.0f || t < zz)) zz = t;
      }
    }
  }
  for (std::size_t i = 0; i < z.size(); ++i) {
    frame.depth[i] = static_cast<std::uint16_t>(std::lround(std::min(z[i], 65.0f) * 1000.0f));
  }
  return frame;
}

// A hand-like blob: a palm slab of spheres, five fingers, and a forearm that continues
// `forearmLengthM` from the wrist along +y (down) and away from the camera.
inline std::vector<Sphere> handWithForearm(const Vec3& palmCentre, float forearmLengthM = 0.25f) {
  std::vector<Sphere> s;
  for (int iy = -2; iy <= 2; ++iy) {
    for (int ix = -2; ix <= 2; ++ix) {
      s.push_back(
          {palmCentre + Vec3(0.009f * static_cast<float>(ix), 0.01f * static_cast<float>(iy), 0.0f),
           0.022f});
    }
  }
  const float fingerX[5] = {-0.032f, -0.012f, 0.008f, 0.028f, 0.05f};
  const float fingerLength[5] = {0.07f, 0.085f, 0.09f, 0.08f, 0.06f};
  for (int f = 0; f < 5; ++f) {
    const Vec3 base = palmCentre + Vec3(fingerX[f], f == 4 ? 0.0f : -0.04f, -0.005f);
    const Vec3 tip =
        base + (f == 4 ? Vec3(0.04f, -0.03f, -0.01f) : Vec3(0.0f, -fingerLength[f], -0.01f));
    addCapsule(s, base, tip, 0.009f, 0.004f);
  }
  const Vec3 wrist = palmCentre + Vec3(0.0f, 0.05f, 0.01f);
  const Vec3 elbow = wrist + Vec3(0.0f, 0.8f, 0.6f) * forearmLengthM;
  addCapsule(s, wrist, elbow, 0.03f, 0.01f);
  return s;
}

}  // namespace dynahand::cloud::scenes
