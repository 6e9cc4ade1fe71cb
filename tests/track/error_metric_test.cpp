// The error metric against a brute-force reference: distances from fan-triangulated
// faces (point-triangle distance, independent of ConvexShape's queries), every body
// tried for every point, occlusion by direct pixel lookup.
#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <random>
#include <string>

#include "core/simd/simd.h"
#include "track/error_metric.h"

namespace dynahand::track {
namespace {

// The bulk queries' paths: each SIMD level the CPU has in turn (scalar first), then point by
// point (the one-point queries at the best level).
int bulkPathCount() {
  return static_cast<int>(simd::bestLevel()) + 2;
}
std::string chooseBulkPath(int path) {
  const bool bulk = path <= static_cast<int>(simd::bestLevel());
  const simd::Level level = bulk ? static_cast<simd::Level>(path) : simd::bestLevel();
  simd::forceLevel(level);
  PosedBodies::useBulkQueries(bulk);
  return bulk ? std::string("bulk, ") + simd::levelName(level) : "point by point";
}
void restoreBulkPath() {
  simd::forceLevel(simd::bestLevel());
  PosedBodies::useBulkQueries(true);
}

// Closest point on triangle abc to p (Ericson, Real-Time Collision Detection 5.1.5).
Vec3 closestOnTriangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const float d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Vec3 bp = p - b;
  const float d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const float vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + ab * (d1 / (d1 - d3));
  const Vec3 cp = p - c;
  const float d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const float vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + ac * (d2 / (d2 - d6));
  const float va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  const float denom = 1.0f / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

float bruteSurfaceDistance(const physics::ConvexShape& s, const Pose& pose, const Vec3& p) {
  float best = 1e9f;
  for (const auto& face : s.faces()) {
    const Vec3 a = pose.transform(s.vertices()[static_cast<std::size_t>(face.vertices[0])]);
    for (std::size_t k = 1; k + 1 < face.vertices.size(); ++k) {
      const Vec3 b = pose.transform(s.vertices()[static_cast<std::size_t>(face.vertices[k])]);
      const Vec3 c = pose.transform(s.vertices()[static_cast<std::size_t>(face.vertices[k + 1])]);
      best = std::min(best, (closestOnTriangle(p, a, b, c) - p).norm());
    }
  }
  return best;
}

struct Scene {
  std::vector<physics::ConvexShape> shapes;
  std::vector<const physics::ConvexShape*> shapePtrs;
  std::vector<Pose> poses;
  std::vector<Vec3> points;
  DepthFrame depth{64, 48, 0.001f};
  Intrinsics intrinsics{64, 48, 60.0f, 60.0f, 31.5f, 23.5f};

  // The metric's free-space test over this scene's depth image (valid while the scene is).
  FreeSpaceTest freeSpace() const {
    return [this](const Vec3& c) { return inFreeSpace(c, depth, intrinsics); };
  }
};

Scene randomScene(unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  Scene s;
  for (int b = 0; b < 6; ++b) {
    std::vector<Vec3> pts;
    const Vec3 half(0.01f + 0.01f * std::abs(u(rng)), 0.008f + 0.01f * std::abs(u(rng)),
                    0.02f + 0.02f * std::abs(u(rng)));
    for (int k = 0; k < 30; ++k) pts.push_back(Vec3(u(rng), u(rng), u(rng)).cwiseProduct(half));
    auto shape = physics::ConvexShape::fromPoints(pts);
    EXPECT_TRUE(shape.ok());
    s.shapes.push_back(*shape);
    s.poses.push_back(
        {Vec3(0.05f * u(rng), 0.04f * u(rng), 0.5f + 0.05f * u(rng)),
         Quat(Eigen::AngleAxisf(3.0f * u(rng), Vec3(u(rng), u(rng), u(rng)).normalized()))});
  }
  for (auto& shape : s.shapes) s.shapePtrs.push_back(&shape);
  for (int k = 0; k < 300; ++k)
    s.points.push_back(Vec3(0.08f * u(rng), 0.06f * u(rng), 0.5f + 0.08f * u(rng)));
  // A depth image: a wall at 0.52 m with a hole of no data and a near patch at 0.40 m.
  for (int v = 0; v < 48; ++v) {
    for (int x = 0; x < 64; ++x) {
      s.depth.at(x, v) = x < 10 ? 0 : (x < 40 ? 400 : 520);
    }
  }
  return s;
}

TEST(ErrorMetric, MatchesBruteForceOnRandomPoses) {
  for (unsigned seed = 1; seed <= 20; ++seed) {
    Scene s = randomScene(seed);
    PosedBodies bodies;
    bodies.set(s.shapePtrs, s.poses);
    ErrorBreakdown err;
    computeError(bodies, s.points, s.freeSpace(), err);

    std::vector<float> fit(s.shapes.size(), 0.0f);
    for (std::size_t k = 0; k < s.points.size(); ++k) {
      const Vec3& p = s.points[k];
      int bestBody = -1;
      float best = 1e9f;
      for (std::size_t i = 0; i < s.shapes.size(); ++i) {
        const float d = bruteSurfaceDistance(s.shapes[i], s.poses[i], p);
        if (d < best) best = d, bestBody = static_cast<int>(i);
      }
      EXPECT_NEAR(err.pointDistance[k], best, 1e-5f) << "seed " << seed << " point " << k;
      fit[static_cast<std::size_t>(bestBody)] =
          std::max(fit[static_cast<std::size_t>(bestBody)], best);
    }
    float total = 0;
    for (std::size_t i = 0; i < s.shapes.size(); ++i) {
      EXPECT_NEAR(err.fit[i], fit[i], 1e-5f) << "seed " << seed << " body " << i;
      const Vec3 c = s.poses[i].transform(s.shapes[i].centroid());
      const Vec2 uv = s.intrinsics.project(c);
      const int x = static_cast<int>(std::lround(uv.x())),
                y = static_cast<int>(std::lround(uv.y()));
      float occ = 0;
      if (x >= 0 && y >= 0 && x < 64 && y < 48) {
        const float d = s.depth.metres(x, y);
        if (d == 0.0f || d >= c.z()) occ = s.shapes[i].inscribedRadius();
      }
      EXPECT_FLOAT_EQ(err.occlusion[i], occ) << "seed " << seed << " body " << i;
      total += fit[i] + occ;
    }
    EXPECT_NEAR(err.total, total, 1e-4f);
  }
}

// The bounded metric: the same bits as computeError when the total stays under the bound,
// whatever the point order; otherwise it stops with a lower bound above the bound.
TEST(ErrorMetric, BoundedVersionIsExactUnderTheBoundAndALowerBoundAbove) {
  for (unsigned seed = 1; seed <= 10; ++seed) {
    Scene s = randomScene(seed);
    PosedBodies bodies;
    bodies.set(s.shapePtrs, s.poses);
    const FreeSpaceTest isFree = s.freeSpace();
    ErrorBreakdown full;
    computeError(bodies, s.points, isFree, full);
    std::vector<int> reversed(s.points.size());
    for (std::size_t k = 0; k < reversed.size(); ++k)
      reversed[k] = static_cast<int>(reversed.size() - 1 - k);

    ErrorBreakdown bounded;
    ASSERT_TRUE(computeErrorBounded(bodies, s.points, isFree, full.total, bounded, {}, reversed));
    EXPECT_EQ(bounded.total, full.total);
    EXPECT_EQ(bounded.fit, full.fit);
    EXPECT_EQ(bounded.occlusion, full.occlusion);
    EXPECT_EQ(bounded.pointCount, full.pointCount);
    EXPECT_EQ(bounded.pointDistance, full.pointDistance);

    const float bound = 0.5f * full.total;
    ErrorBreakdown stopped;
    EXPECT_FALSE(computeErrorBounded(bodies, s.points, isFree, bound, stopped, {}, reversed));
    EXPECT_GT(stopped.total, bound);
    EXPECT_LE(stopped.total, full.total);
    // It stopped early: points after the stop were never measured.
    EXPECT_GT(std::count(stopped.pointDistance.begin(), stopped.pointDistance.end(),
                         std::numeric_limits<float>::infinity()),
              0);
  }
}

// Settling (computeErrorBounded's settleBelowM) spares the queries of points that cannot
// raise any errFit: the errors and the give-up point are the same bits, and a settled
// point's distance is an upper bound no larger than settleBelowM.
TEST(ErrorMetric, SettlingGivesTheSameErrorsAndUpperBoundsBelowItsLimit) {
  constexpr float kSettleBelow = 0.05f;  // the random points lie up to a few cm off
  std::size_t settledTotal = 0;          // points in no pointCount
  for (unsigned seed = 1; seed <= 10; ++seed) {
    Scene s = randomScene(seed);
    PosedBodies bodies;
    bodies.set(s.shapePtrs, s.poses);
    const FreeSpaceTest isFree = s.freeSpace();
    ErrorBreakdown full, settled;
    computeError(bodies, s.points, isFree, full);
    ASSERT_TRUE(computeErrorBounded(bodies, s.points, isFree,
                                    std::numeric_limits<float>::infinity(), settled, {}, {},
                                    kSettleBelow));
    EXPECT_EQ(settled.total, full.total) << "seed " << seed;
    EXPECT_EQ(settled.fit, full.fit) << "seed " << seed;
    EXPECT_EQ(settled.occlusion, full.occlusion) << "seed " << seed;
    int counted = 0;
    for (const int c : settled.pointCount) counted += c;
    settledTotal += s.points.size() - static_cast<std::size_t>(counted);
    for (std::size_t k = 0; k < s.points.size(); ++k) {
      EXPECT_GE(settled.pointDistance[k], full.pointDistance[k]) << "seed " << seed << " " << k;
      if (settled.pointDistance[k] != full.pointDistance[k]) {
        EXPECT_LE(settled.pointDistance[k], kSettleBelow) << "seed " << seed << " " << k;
      }
    }
    // Giving up: at the same point, with the same lower bound.
    ErrorBreakdown stopped, stoppedSettled;
    EXPECT_FALSE(computeErrorBounded(bodies, s.points, isFree, 0.5f * full.total, stopped));
    EXPECT_FALSE(computeErrorBounded(bodies, s.points, isFree, 0.5f * full.total, stoppedSettled,
                                     {}, {}, kSettleBelow));
    EXPECT_EQ(stoppedSettled.total, stopped.total) << "seed " << seed;
  }
  EXPECT_GT(settledTotal, 300u);
}

// Settling gives the same bits on every SIMD level: the same points settle, with the same
// distances.
TEST(ErrorMetric, SettlingGivesTheSameBitsOnEveryLevel) {
  constexpr float kSettleBelow = 0.05f;
  for (unsigned seed = 1; seed <= 5; ++seed) {
    Scene s = randomScene(seed);
    PosedBodies bodies;
    bodies.set(s.shapePtrs, s.poses);
    const FreeSpaceTest isFree = s.freeSpace();
    ErrorBreakdown reference;
    for (int level = 0; level <= static_cast<int>(simd::bestLevel()); ++level) {
      const std::string name = chooseBulkPath(level);
      ErrorBreakdown settled;
      ASSERT_TRUE(computeErrorBounded(bodies, s.points, isFree,
                                      std::numeric_limits<float>::infinity(), settled, {}, {},
                                      kSettleBelow));
      if (level == 0) {
        reference = settled;
        continue;
      }
      EXPECT_EQ(settled.total, reference.total) << name;
      EXPECT_EQ(settled.pointCount, reference.pointCount) << name;
      EXPECT_EQ(settled.pointDistance, reference.pointDistance) << name;
    }
  }
  restoreBulkPath();
}

TEST(ErrorMetric, PerfectFitHasNoFitError) {
  // Points sampled on the visible surface of one box give errFit = 0 for it.
  std::vector<physics::ConvexShape> shapes{physics::ConvexShape::box(Vec3(0.02f, 0.02f, 0.02f))};
  const physics::ConvexShape* ptr = &shapes[0];
  const Pose pose{Vec3(0, 0, 0.5f), Quat::Identity()};
  PosedBodies bodies;
  bodies.set(std::span(&ptr, 1), std::span(&pose, 1));
  std::vector<Vec3> pts;
  for (int i = -4; i <= 4; ++i)
    for (int j = -4; j <= 4; ++j) pts.push_back(Vec3(0.004f * i, 0.004f * j, 0.48f));
  DepthFrame depth(64, 48, 0.001f);
  for (auto& d : depth.depth) d = 480;  // the box's front face occludes its centroid
  ErrorBreakdown err;
  computeError(
      bodies, pts,
      [&](const Vec3& c) {
        return inFreeSpace(c, depth, Intrinsics{64, 48, 60, 60, 31.5f, 23.5f});
      },
      err);
  EXPECT_NEAR(err.total, 0.0f, 1e-6f);
  EXPECT_EQ(err.pointCount[0], 81);
  // Move the box 1 cm back: every point is 1 cm off and the centroid still occluded.
  bodies.setPose(0, {Vec3(0, 0, 0.51f), Quat::Identity()});
  computeError(
      bodies, pts,
      [&](const Vec3& c) {
        return inFreeSpace(c, depth, Intrinsics{64, 48, 60, 60, 31.5f, 23.5f});
      },
      err);
  EXPECT_NEAR(err.fit[0], 0.01f, 1e-5f);
  EXPECT_FLOAT_EQ(err.occlusion[0], 0.0f);
  // Nothing seen at the centroid's pixel (no data): penalty = inscribed radius (2 cm).
  for (auto& d : depth.depth) d = 0;
  computeError(
      bodies, pts,
      [&](const Vec3& c) {
        return inFreeSpace(c, depth, Intrinsics{64, 48, 60, 60, 31.5f, 23.5f});
      },
      err);
  EXPECT_NEAR(err.occlusion[0], 0.02f, 1e-6f);
}

TEST(PosedBodies, MaskRestrictsMatching) {
  std::vector<physics::ConvexShape> shapes{physics::ConvexShape::box(Vec3(0.01f, 0.01f, 0.01f)),
                                           physics::ConvexShape::box(Vec3(0.01f, 0.01f, 0.01f))};
  std::vector<const physics::ConvexShape*> ptrs{&shapes[0], &shapes[1]};
  std::vector<Pose> poses{{Vec3(0, 0, 0.5f), Quat::Identity()},
                          {Vec3(0.1f, 0, 0.5f), Quat::Identity()}};
  PosedBodies bodies;
  bodies.set(ptrs, poses);
  const Vec3 p(0.0f, 0.0f, 0.48f);
  EXPECT_EQ(bodies.nearest(p).body, 0);
  EXPECT_NEAR(bodies.nearest(p).distance, 0.01f, 1e-6f);
  const SurfaceHit only1 = bodies.nearest(p, 0b10);
  EXPECT_EQ(only1.body, 1);
  EXPECT_GT(only1.distance, 0.08f);
  EXPECT_EQ(bodies.nearest(p, 0).body, -1);
}

}  // namespace
}  // namespace dynahand::track

namespace dynahand::track {
namespace {

TEST(PosedBodies, PlanarQueryIsExactInsideAndALowerBoundOutside) {
  Scene s = randomScene(5);
  PosedBodies bodies;
  bodies.set(s.shapePtrs, s.poses);
  int inside = 0;
  for (const Vec3& p : s.points) {
    for (int hint : {-1, 0, 3}) {
      const SurfaceHit exact = bodies.nearest(p);
      const SurfaceHit planar = bodies.nearestPlanar(p, kAllBodies, hint);
      ASSERT_GE(planar.body, 0);
      EXPECT_LE(planar.distance, exact.distance + 1e-6f);
      // The planar anchor lies on the chosen face's plane, body frame.
      const auto& face = bodies.shape(planar.body).faces()[static_cast<std::size_t>(planar.face)];
      EXPECT_NEAR(face.normal.dot(planar.localPoint), face.offset, 1e-5f);
      if (exact.signedDistance < 0.0f) {
        ++inside;
        EXPECT_NEAR(planar.distance, exact.distance, 1e-5f);
      }
    }
  }
  // The planar answer does not depend on the hint.
  for (const Vec3& p : s.points) {
    EXPECT_EQ(bodies.nearestPlanar(p, kAllBodies, -1).body,
              bodies.nearestPlanar(p, kAllBodies, 2).body);
  }
  EXPECT_GT(inside, 0);
}

// The bulk planar and exact queries (body by body, eight points at a time, on every SIMD level)
// answer every point exactly as the one-point queries do, whatever the hints.
TEST(PosedBodies, ManyPointsPlanarQueryMatchesOnePointAtATime) {
  for (unsigned seed = 1; seed <= 5; ++seed) {
    Scene s = randomScene(seed);
    PosedBodies bodies;
    bodies.set(s.shapePtrs, s.poses);
    for (int path = 0; path < bulkPathCount(); ++path) {
      const std::string name = chooseBulkPath(path);
      std::vector<int> hints(s.points.size());
      for (std::size_t i = 0; i < hints.size(); ++i)
        hints[i] = static_cast<int>(i % 7) - 1;  // none, right and wrong bodies
      const std::vector<int> given = hints;
      std::vector<SurfaceHit> hits(s.points.size()), exactHits(s.points.size());
      bodies.nearestPlanarMany(s.points, hints, hits);
      bodies.nearestMany(s.points, given, exactHits);
      for (std::size_t i = 0; i < s.points.size(); ++i) {
        const SurfaceHit one = bodies.nearestPlanar(s.points[i], kAllBodies, given[i]);
        const SurfaceHit exact = bodies.nearest(s.points[i], kAllBodies, given[i]);
        for (const auto& [a, b] : {std::pair{hits[i], one}, std::pair{exactHits[i], exact}}) {
          EXPECT_EQ(a.body, b.body) << name;
          EXPECT_EQ(a.face, b.face) << name;
          EXPECT_EQ(a.distance, b.distance) << name;
          EXPECT_EQ(a.signedDistance, b.signedDistance) << name;
          EXPECT_EQ(a.localPoint, b.localPoint) << name;
        }
        EXPECT_EQ(hints[i], one.body) << name;
      }
    }
  }
  restoreBulkPath();
}

// The bulk queries at their edges: no points, no bodies, out-of-range hints, two identical
// bodies (every distance a tie: the lower index wins) and a point that is not finite (no
// crash, no hit on a real distance).
TEST(PosedBodies, ManyPointsQueriesHandleEmptyInputTiesAndBadPoints) {
  Scene s = randomScene(3);
  for (int path = 0; path < bulkPathCount(); ++path) {
    SCOPED_TRACE(chooseBulkPath(path));
    PosedBodies none;
    none.set({}, {});
    std::vector<int> hints(s.points.size(), -1);
    std::vector<SurfaceHit> hits(s.points.size());
    none.nearestPlanarMany(s.points, hints, hits);
    for (const SurfaceHit& h : hits) EXPECT_EQ(h.body, -1);
    none.nearestMany(s.points, hints, hits);
    for (const SurfaceHit& h : hits) EXPECT_EQ(h.body, -1);

    // Body 1 is body 0 again: every point ties, and body 0 must win whatever the hint.
    std::vector<const physics::ConvexShape*> twins{s.shapePtrs[0], s.shapePtrs[0], s.shapePtrs[1]};
    std::vector<Pose> twinPoses{s.poses[0], s.poses[0], s.poses[1]};
    PosedBodies bodies;
    bodies.set(twins, twinPoses);
    std::vector<Vec3> points(s.points.begin(), s.points.begin() + 40);
    points.push_back(Vec3(std::numeric_limits<float>::quiet_NaN(), 0.0f, 0.5f));
    hints.assign(points.size(), 0);
    for (std::size_t i = 0; i < hints.size(); ++i) hints[i] = static_cast<int>(i % 5) - 1;
    const std::vector<int> given = hints;  // -1 .. 3: none, each body and one past the end
    hits.resize(points.size());
    std::vector<SurfaceHit> exactHits(points.size());
    bodies.nearestPlanarMany(std::span(points.data(), 0), std::span(hints.data(), 0),
                             std::span(hits.data(), 0));
    bodies.nearestPlanarMany(points, hints, hits);
    bodies.nearestMany(points, given, exactHits);
    for (std::size_t i = 0; i + 1 < points.size(); ++i) {
      EXPECT_NE(hits[i].body, 1) << "a tie goes to the lower index";
      EXPECT_NE(exactHits[i].body, 1);
      EXPECT_EQ(hits[i].distance, bodies.nearestPlanar(points[i], kAllBodies, given[i]).distance);
      EXPECT_EQ(exactHits[i].distance, bodies.nearest(points[i], kAllBodies, given[i]).distance);
    }
    EXPECT_FALSE(hits.back().distance < 0.06f) << "a NaN point attaches nowhere";
  }
  restoreBulkPath();
}

// Points equally far from two or more faces of a cube (its centre, its diagonals, its
// symmetry planes): every path of the bulk queries picks the lowest face, as the one-point
// queries do.
TEST(PosedBodies, ManyPointsQueriesBreakFaceTiesLikeOnePointQueries) {
  const physics::ConvexShape cube = physics::ConvexShape::box(Vec3(0.02f, 0.02f, 0.02f));
  const std::vector<const physics::ConvexShape*> shapes{&cube};
  const std::vector<Pose> poses{{Vec3(0.0f, 0.0f, 0.5f), Quat::Identity()}};
  PosedBodies bodies;
  bodies.set(shapes, poses);
  std::vector<Vec3> points;
  for (int i = -4; i <= 4; ++i)
    for (int j = -4; j <= 4; ++j) {
      const float a = static_cast<float>(i) / 256.0f, b = static_cast<float>(j) / 256.0f;
      points.emplace_back(a, a, 0.5f + b);        // x = y: the +-x and +-y faces tie
      points.emplace_back(a, b, 0.5f + a);        // x = z
      points.emplace_back(0.0f, 0.0f, 0.5f + a);  // on the axis: four faces tie
    }
  for (int path = 0; path < bulkPathCount(); ++path) {
    const std::string name = chooseBulkPath(path);
    std::vector<int> hints(points.size(), 0);
    std::vector<SurfaceHit> hits(points.size()), exactHits(points.size());
    bodies.nearestPlanarMany(points, hints, hits);
    bodies.nearestMany(points, std::vector<int>(points.size(), 0), exactHits);
    simd::forceLevel(simd::Level::Scalar);  // the reference: one-point queries, scalar level
    for (std::size_t i = 0; i < points.size(); ++i) {
      EXPECT_EQ(hits[i].face, bodies.nearestPlanar(points[i], kAllBodies, 0).face) << name;
      EXPECT_EQ(exactHits[i].face, bodies.nearest(points[i], kAllBodies, 0).face) << name;
    }
  }
  restoreBulkPath();
}

// The one-point queries give the scalar level's bits on every SIMD level.
TEST(PosedBodies, OnePointQueriesGiveTheSameBitsOnEveryLevel) {
  for (unsigned seed = 1; seed <= 5; ++seed) {
    Scene s = randomScene(seed);
    PosedBodies bodies;
    bodies.set(s.shapePtrs, s.poses);
    for (const Vec3& p : s.points) {
      for (int hint : {-1, 2}) {
        simd::forceLevel(simd::Level::Scalar);
        const SurfaceHit exact = bodies.nearest(p, kAllBodies, hint);
        const SurfaceHit planar = bodies.nearestPlanar(p, kAllBodies, hint);
        for (int level = 1; level <= static_cast<int>(simd::bestLevel()); ++level) {
          simd::forceLevel(static_cast<simd::Level>(level));
          const SurfaceHit exactWide = bodies.nearest(p, kAllBodies, hint);
          const SurfaceHit planarWide = bodies.nearestPlanar(p, kAllBodies, hint);
          for (const auto& [a, b] : {std::pair{exactWide, exact}, std::pair{planarWide, planar}}) {
            EXPECT_EQ(a.body, b.body) << level;
            EXPECT_EQ(a.face, b.face) << level;
            EXPECT_EQ(a.distance, b.distance) << level;
            EXPECT_EQ(a.signedDistance, b.signedDistance) << level;
            EXPECT_EQ(a.localPoint, b.localPoint) << level;
          }
        }
      }
    }
  }
  restoreBulkPath();
}

}  // namespace
}  // namespace dynahand::track
