// The analytic renderer against independent references: a closed-form sphere hit, a
// sphere-traced hit on the round cone's exact definition, and a brute-force
// full-image ray cast (checks the bounding-box culling never cuts a surface).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include <cmath>

#include "dynahand/synth_render.h"

namespace dynahand::synth {
namespace {

Intrinsics testCamera() {
  Intrinsics k;
  k.width = 320;
  k.height = 240;
  k.fx = k.fy = 224.0f;
  k.cx = 159.5f;
  k.cy = 119.5f;
  return k;
}

// Signed "inside" measure of the convex hull of two balls, which is the union over s in
// [0, 1] of the balls (a + s (b - a), ra + s (rb - ra)); convex in s, so a ternary search
// finds the minimum. Double precision, independent of the renderer's cone algebra.
double hullMeasure(const RoundCone& c, const Eigen::Vector3d& p) {
  const Eigen::Vector3d a = c.a.cast<double>(), b = c.b.cast<double>();
  const double ra = c.ra, rb = c.rb;
  auto f = [&](double s) { return (p - (a + s * (b - a))).norm() - (ra + s * (rb - ra)); };
  double lo = 0.0, hi = 1.0;
  for (int i = 0; i < 100; ++i) {
    const double m1 = lo + (hi - lo) / 3.0, m2 = hi - (hi - lo) / 3.0;
    if (f(m1) < f(m2))
      hi = m2;
    else
      lo = m1;
  }
  return f(0.5 * (lo + hi));
}

// First t along t * dir (dir.z = 1, so t is depth) on the hull. Outside, hullMeasure is
// the exact distance to the hull (the distance to a union of balls is the smallest
// distance to one of them), so sphere tracing converges onto the first hit.
double tracedDepth(const RoundCone& c, const Eigen::Vector3d& dir) {
  const double step = 1.0 / dir.norm();
  double t = 0.05;
  for (int i = 0; i < 500 && t < 2.0; ++i) {
    const double distance = hullMeasure(c, t * dir);
    if (distance < 1e-9) return t;
    t += distance * step;
  }
  return 0.0;
}

TEST(DepthRenderer, SphereDepthMatchesClosedForm) {
  const Intrinsics k = testCamera();
  DepthRenderer renderer(k);
  const RoundCone sphere{{0.02f, -0.01f, 0.5f}, {0.02f, -0.01f, 0.5f}, 0.03f, 0.03f};
  renderer.clear();
  renderer.draw(std::span(&sphere, 1), PixelLabel::Hand0);
  const int u = 172, v = 112;
  // Ray p = t d with d = ((u - cx)/fx, (v - cy)/fy, 1): |t d - c|^2 = r^2.
  const Eigen::Vector3d d((u - k.cx) / k.fx, (v - k.cy) / k.fy, 1.0f);
  const Eigen::Vector3d c(0.02, -0.01, 0.5);
  const double b = d.dot(c), disc = b * b - d.squaredNorm() * (c.squaredNorm() - 0.03 * 0.03);
  ASSERT_GT(disc, 0.0);
  const double expected = (b - std::sqrt(disc)) / d.squaredNorm();
  const float rendered = renderer.depth()[static_cast<std::size_t>(v) * k.width + u];
  EXPECT_NEAR(rendered, expected, 2e-6);
  EXPECT_EQ(renderer.labels()[static_cast<std::size_t>(v) * k.width + u], PixelLabel::Hand0);
  // The silhouette edge: the sphere's projected centre row, far left and right of it, is empty.
  EXPECT_EQ(renderer.depth()[120 * k.width + 10], 0.0f);
}

TEST(DepthRenderer, TaperedConeDepthMatchesSphereTracedHullHit) {
  const Intrinsics k = testCamera();
  const RoundCone cone{{-0.05f, 0.03f, 0.45f}, {0.04f, -0.02f, 0.52f}, 0.018f, 0.009f};
  DepthRenderer renderer(k);
  renderer.clear();
  renderer.draw(std::span(&cone, 1), PixelLabel::Hand0);
  int checked = 0;
  // Pixels over the cone's whole projection and around it.
  for (int u = 110; u < 200; u += 3) {
    for (int v = 95; v < 155; v += 2) {
      const Eigen::Vector3d dir((u - k.cx) / k.fx, (v - k.cy) / k.fy, 1.0f);
      const double expected = tracedDepth(cone, dir);
      const float rendered = renderer.depth()[static_cast<std::size_t>(v) * k.width + u];
      if (expected == 0.0) {
        EXPECT_EQ(rendered, 0.0f) << u << "," << v;
      } else {
        EXPECT_NEAR(rendered, expected, 2e-5) << u << "," << v;
        ++checked;
      }
    }
  }
  EXPECT_GT(checked, 100);
}

TEST(DepthRenderer, BoundingBoxCullingMatchesBruteForce) {
  const Intrinsics k = testCamera();
  DepthRenderer renderer(k);
  // Long, tilted, partly off-image primitives, including one reaching toward the camera.
  const RoundCone cones[] = {{{-0.3f, 0.1f, 0.6f}, {0.1f, -0.05f, 0.35f}, 0.02f, 0.012f},
                             {{0.05f, 0.05f, 0.4f}, {0.05f, 0.4f, 0.2f}, 0.015f, 0.03f},
                             {{0.0f, 0.0f, 0.3f}, {0.0f, 0.0f, 0.3f}, 0.01f, 0.01f}};
  renderer.clear();
  renderer.draw(cones, PixelLabel::Hand0);
  int hits = 0;
  for (int v = 0; v < k.height; ++v) {
    for (int u = 0; u < k.width; ++u) {
      const Vec3 dir((static_cast<float>(u) - k.cx) / k.fx, (static_cast<float>(v) - k.cy) / k.fy,
                     1.0f);
      float best = 0.0f;
      for (const RoundCone& c : cones) {
        const float t = intersectRoundCone(c, dir);
        if (t > 0.0f && (best == 0.0f || t < best)) best = t;
      }
      ASSERT_EQ(renderer.depth()[static_cast<std::size_t>(v) * k.width + u], best) << u << "," << v;
      hits += best > 0.0f;
    }
  }
  EXPECT_GT(hits, 1000);
}

TEST(DepthRenderer, ContainedSphereRendersAsTheLargerSphere) {
  const RoundCone nested{{0.0f, 0.0f, 0.5f}, {0.005f, 0.0f, 0.5f}, 0.03f, 0.01f};
  const RoundCone sphere{{0.0f, 0.0f, 0.5f}, {0.0f, 0.0f, 0.5f}, 0.03f, 0.03f};
  for (const float x : {-0.1f, -0.05f, 0.0f, 0.02f, 0.06f}) {
    const Vec3 dir(x, 0.01f, 1.0f);
    EXPECT_FLOAT_EQ(intersectRoundCone(nested, dir), intersectRoundCone(sphere, dir));
  }
}

TEST(DepthRenderer, BackgroundPlaneAndNearestSurfaceWins) {
  const Intrinsics k = testCamera();
  DepthRenderer renderer(k);
  const Plane wall{Vec3::UnitZ(), 0.8f};
  renderer.setBackground(std::span(&wall, 1), {});
  EXPECT_FLOAT_EQ(renderer.depth()[0], 0.8f);
  EXPECT_EQ(renderer.labels()[0], PixelLabel::Background);
  const RoundCone sphere{{0.0f, 0.0f, 0.5f}, {0.0f, 0.0f, 0.5f}, 0.05f, 0.05f};
  renderer.draw(std::span(&sphere, 1), PixelLabel::Hand1);
  const std::size_t centre = static_cast<std::size_t>(120) * k.width + 160;
  EXPECT_NEAR(renderer.depth()[centre], 0.45f, 1e-4f);
  EXPECT_EQ(renderer.labels()[centre], PixelLabel::Hand1);
  renderer.clear();  // back to the wall
  EXPECT_FLOAT_EQ(renderer.depth()[centre], 0.8f);
}

// A box facing the camera shows its front face at its depth; turned 45 degrees about the
// vertical axis, its nearest edge; the nearer of box and sphere wins per pixel.
TEST(DepthRenderer, BoxShowsItsNearestFace) {
  const Intrinsics k = testCamera();
  DepthRenderer renderer(k);
  OrientedBox box;
  box.centre = Vec3(0.0f, 0.0f, 0.5f);
  box.halfExtents = Vec3(0.05f, 0.03f, 0.02f);
  renderer.draw(box, PixelLabel::HeldObject);
  const std::size_t centre = static_cast<std::size_t>(120) * k.width + 160;
  EXPECT_NEAR(renderer.depth()[centre], 0.48f, 1e-5f);
  EXPECT_EQ(renderer.labels()[centre], PixelLabel::HeldObject);
  // Its image: 0.10 x 0.06 m at 0.48 m, in pixels of focal length k.fx, k.fy.
  int drawn = 0;
  for (const PixelLabel l : renderer.labels()) drawn += l == PixelLabel::HeldObject;
  const float expected = (k.fx * 0.10f / 0.48f) * (k.fy * 0.06f / 0.48f);
  EXPECT_NEAR(static_cast<float>(drawn), expected, 0.1f * expected);

  renderer.clear();
  const float c = std::cos(std::numbers::pi_v<float> / 4.0f);
  box.axes << c, 0.0f, c, 0.0f, 1.0f, 0.0f, -c, 0.0f, c;
  box.halfExtents = Vec3(0.03f, 0.03f, 0.03f);
  renderer.draw(box, PixelLabel::HeldObject);
  // (the pixel centre lies half a pixel off the axis: 1 mm farther along the 45-degree face)
  EXPECT_NEAR(renderer.depth()[centre], 0.5f - 0.03f * std::sqrt(2.0f), 1.5e-3f);
  const RoundCone sphere{{0.0f, 0.0f, 0.4f}, {0.0f, 0.0f, 0.4f}, 0.01f, 0.01f};
  renderer.draw(std::span(&sphere, 1), PixelLabel::Hand0);
  EXPECT_EQ(renderer.labels()[centre], PixelLabel::Hand0);
  EXPECT_NEAR(renderer.depth()[centre], 0.39f, 1e-4f);
}

TEST(DepthRenderer, PrimitiveBehindTheCameraIsNotDrawnAndCrossingOneIsClipped) {
  const Intrinsics k = testCamera();
  DepthRenderer renderer(k);
  const RoundCone behind{{0.0f, 0.0f, -0.5f}, {0.1f, 0.0f, -0.3f}, 0.05f, 0.05f};
  const RoundCone crossing{{0.0f, 0.1f, 0.5f}, {0.0f, 0.1f, -0.2f}, 0.03f, 0.03f};
  renderer.clear();
  renderer.draw(std::span(&behind, 1), PixelLabel::Hand0);
  for (const float z : renderer.depth()) ASSERT_EQ(z, 0.0f);
  renderer.draw(std::span(&crossing, 1), PixelLabel::Hand0);
  float nearest = 10.0f;
  for (const float z : renderer.depth())
    if (z > 0.0f) nearest = std::min(nearest, z);
  EXPECT_GT(nearest, 0.05f);  // nothing nearer than the near plane
  EXPECT_LT(nearest, 0.2f);
}

}  // namespace
}  // namespace dynahand::synth
