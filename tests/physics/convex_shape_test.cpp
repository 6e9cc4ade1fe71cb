#include "dynahand/convex_shape.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

namespace dynahand::physics {
namespace {

std::vector<Vec3> boxCorners(const Vec3& h, const Vec3& centre = Vec3::Zero()) {
  std::vector<Vec3> c;
  for (int i = 0; i < 8; ++i) {
    c.push_back(centre +
                Vec3((i & 1) ? h.x() : -h.x(), (i & 2) ? h.y() : -h.y(), (i & 4) ? h.z() : -h.z()));
  }
  return c;
}

// count random points on a sphere of the given radius about the origin (a random hull's
// vertices); draws from rng through u, which the caller keeps using.
std::vector<Vec3> randomSpherePoints(std::mt19937& rng, std::uniform_real_distribution<float>& u,
                                     int count, float radius) {
  std::vector<Vec3> points;
  for (int i = 0; i < count; ++i)
    points.push_back(Vec3(u(rng), u(rng), u(rng)).normalized() * radius);
  return points;
}

// Exact signed distance of an axis-aligned box of half extents h centred at the origin.
float boxSignedDistance(const Vec3& p, const Vec3& h) {
  const Vec3 q = p.cwiseAbs() - h;
  const float outside = q.cwiseMax(0.0f).norm();
  const float inside = std::min(q.maxCoeff(), 0.0f);
  return outside + inside;
}

// vertexHeights (four vertices per SSE instruction) gives each vertex's Vec3::dot bit for bit,
// also for the vertices past the last full four.
TEST(ConvexShape, VertexHeightsAreTheDotProducts) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<Vec3> points;
    const int count = 5 + trial;  // hulls of different vertex counts
    for (int i = 0; i < count; ++i) points.emplace_back(u(rng), u(rng), u(rng));
    const auto shape = ConvexShape::fromPoints(points);
    ASSERT_TRUE(shape.ok());
    const Vec3 direction = Vec3(u(rng), u(rng), u(rng)).normalized();
    std::vector<float> heights(shape->vertices().size());
    shape->vertexHeights(direction, heights.data());
    for (std::size_t i = 0; i < heights.size(); ++i) {
      const float dot = direction.dot(shape->vertices()[i]);
      EXPECT_EQ(std::memcmp(&heights[i], &dot, sizeof(float)), 0) << "vertex " << i;
    }
  }
}

TEST(ConvexShape, UnitCubeMassProperties) {
  auto shape = ConvexShape::fromPoints(boxCorners(Vec3(0.5f, 0.5f, 0.5f)));
  ASSERT_TRUE(shape.ok()) << shape.message();
  EXPECT_EQ(shape->vertices().size(), 8u);
  EXPECT_EQ(shape->faces().size(), 6u);  // coplanar triangles merged into squares
  for (const Face& f : shape->faces()) EXPECT_EQ(f.vertices.size(), 4u);
  EXPECT_NEAR(shape->volume(), 1.0f, 1e-6f);
  EXPECT_LT(shape->centroid().norm(), 1e-6f);
  const Mat3 inertia = shape->inertiaAboutCentroid(6.0f);  // m (a^2 + a^2) / 12 = 1
  EXPECT_LT((inertia - Mat3::Identity()).norm(), 1e-5f);
  EXPECT_NEAR(shape->inscribedRadius(), 0.5f, 1e-6f);
  EXPECT_NEAR(shape->boundingRadius(), std::sqrt(0.75f), 1e-6f);
}

TEST(ConvexShape, OffsetBoxMassPropertiesMatchClosedForm) {
  const Vec3 h(0.01f, 0.02f, 0.04f);  // finger-bone sized, m
  const Vec3 centre(0.1f, -0.05f, 0.3f);
  auto shape = ConvexShape::fromPoints(boxCorners(h, centre));
  ASSERT_TRUE(shape.ok()) << shape.message();
  EXPECT_NEAR(shape->volume(), 8.0f * h.prod(), 1e-9f);
  EXPECT_LT((shape->centroid() - centre).norm(), 1e-6f);
  const float m = 2.0f;
  const Vec3 s = 2.0f * h;
  const Mat3 expected =
      Vec3(m / 12.0f * (s.y() * s.y() + s.z() * s.z()), m / 12.0f * (s.x() * s.x() + s.z() * s.z()),
           m / 12.0f * (s.x() * s.x() + s.y() * s.y()))
          .asDiagonal();
  EXPECT_LT((shape->inertiaAboutCentroid(m) - expected).norm(), 1e-3f * expected.norm());
  EXPECT_NEAR(shape->inscribedRadius(), 0.01f, 1e-6f);  // half the smallest side
  EXPECT_NEAR(shape->boundingRadius(), h.norm(), 1e-6f);
}

TEST(ConvexShape, RotatedBoxInertiaRotatesWithIt) {
  const Vec3 h(0.1f, 0.2f, 0.3f);
  const Mat3 r = Eigen::AngleAxisf(0.6f, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  std::vector<Vec3> pts = boxCorners(h);
  for (Vec3& p : pts) p = r * p;
  auto shape = ConvexShape::fromPoints(pts);
  ASSERT_TRUE(shape.ok()) << shape.message();
  const Vec3 s = 2.0f * h;
  const Mat3 local =
      Vec3((s.y() * s.y() + s.z() * s.z()) / 12.0f, (s.x() * s.x() + s.z() * s.z()) / 12.0f,
           (s.x() * s.x() + s.y() * s.y()) / 12.0f)
          .asDiagonal();
  const Mat3 expected = r * local * r.transpose();
  EXPECT_LT((shape->inertiaAboutCentroid(1.0f) - expected).norm(), 1e-4f);
  EXPECT_EQ(shape->faces().size(), 6u);
}

TEST(ConvexShape, TetrahedronVolumeAndCentroid) {
  const std::vector<Vec3> pts = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)};
  auto shape = ConvexShape::fromPoints(pts);
  ASSERT_TRUE(shape.ok()) << shape.message();
  EXPECT_NEAR(shape->volume(), 1.0f / 6.0f, 1e-6f);
  EXPECT_LT((shape->centroid() - Vec3(0.25f, 0.25f, 0.25f)).norm(), 1e-6f);
  EXPECT_EQ(shape->faces().size(), 4u);
}

TEST(ConvexShape, InteriorPointsAreDropped) {
  std::vector<Vec3> pts = boxCorners(Vec3(1, 1, 1));
  pts.emplace_back(0.1f, 0.2f, 0.3f);
  pts.emplace_back(0.0f, 0.0f, 0.0f);
  auto shape = ConvexShape::fromPoints(pts);
  ASSERT_TRUE(shape.ok()) << shape.message();
  EXPECT_EQ(shape->vertices().size(), 8u);
}

TEST(ConvexShape, FacesAreOutwardCcwSupportingPlanes) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::vector<Vec3> pts;
  for (int i = 0; i < 60; ++i) pts.emplace_back(u(rng), 0.5f * u(rng), 0.3f * u(rng));
  auto shape = ConvexShape::fromPoints(pts);
  ASSERT_TRUE(shape.ok()) << shape.message();
  for (const Face& f : shape->faces()) {
    EXPECT_NEAR(f.normal.norm(), 1.0f, 1e-5f);
    // Every hull vertex is on the inner side; the face's own vertices are on the plane.
    for (const Vec3& v : shape->vertices()) EXPECT_LE(f.normal.dot(v) - f.offset, 1e-6f);
    for (int vi : f.vertices) EXPECT_NEAR(f.normal.dot(shape->vertices()[vi]), f.offset, 1e-5f);
    // CCW seen from outside: the polygon's area vector points along the normal.
    Vec3 area = Vec3::Zero();
    const Vec3& a = shape->vertices()[f.vertices[0]];
    for (std::size_t i = 1; i + 1 < f.vertices.size(); ++i) {
      area +=
          (shape->vertices()[f.vertices[i]] - a).cross(shape->vertices()[f.vertices[i + 1]] - a);
    }
    EXPECT_GT(area.dot(f.normal), 0.0f);
  }
}

TEST(ConvexShape, SignedDistanceMatchesBoxClosedFormEverywhere) {
  const Vec3 h(0.3f, 0.2f, 0.1f);
  const ConvexShape shape = ConvexShape::box(h);
  // Inside, on faces, beyond edges and beyond vertices.
  const std::vector<Vec3> probes = {Vec3(0, 0, 0),           Vec3(0.1f, 0.05f, 0.02f),
                                    Vec3(0.5f, 0.0f, 0.0f),  Vec3(0.0f, -0.4f, 0.0f),
                                    Vec3(0.5f, 0.4f, 0.0f),  Vec3(-0.5f, 0.0f, -0.3f),
                                    Vec3(0.4f, 0.3f, 0.2f),  Vec3(-0.4f, -0.3f, -0.2f),
                                    Vec3(0.29f, 0.0f, 0.0f), Vec3(0.3f, 0.2f, 0.1f)};
  for (const Vec3& p : probes) {
    const float expected = boxSignedDistance(p, h);
    EXPECT_NEAR(shape.signedDistance(p), expected, 1e-6f) << p.transpose();
    const Vec3 q = shape.closestPoint(p);
    EXPECT_NEAR((q - p).norm(), std::abs(expected), 1e-6f) << p.transpose();
    EXPECT_NEAR(boxSignedDistance(q, h), 0.0f, 1e-6f) << "closest point not on surface";
  }
  // Beyond a vertex the closest point is that vertex; beyond an edge it is on the edge.
  EXPECT_LT((shape.closestPoint(Vec3(1, 1, 1)) - h).norm(), 1e-6f);
  EXPECT_LT((shape.closestPoint(Vec3(1, 1, 0.05f)) - Vec3(0.3f, 0.2f, 0.05f)).norm(), 1e-6f);
  // The closest face of a point beyond +x is the +x face.
  const Face& fx = shape.faces()[static_cast<std::size_t>(shape.closestFace(Vec3(0.6f, 0.01f, 0)))];
  EXPECT_LT((fx.normal - Vec3::UnitX()).norm(), 1e-6f);
}

// Brute force over a dense sampling of every face: the sampled minimum can only exceed the
// exact distance, and by no more than the sampling spacing.
TEST(ConvexShape, SignedDistanceMatchesBruteForceOnRandomHull) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  auto shape = ConvexShape::fromPoints(randomSpherePoints(rng, u, 30, 0.05f));
  ASSERT_TRUE(shape.ok()) << shape.message();
  std::vector<Vec3> samples;
  const int n = 40;
  for (const Face& f : shape->faces()) {
    const Vec3& a = shape->vertices()[f.vertices[0]];
    for (std::size_t i = 1; i + 1 < f.vertices.size(); ++i) {
      const Vec3& b = shape->vertices()[f.vertices[i]];
      const Vec3& c = shape->vertices()[f.vertices[i + 1]];
      for (int s = 0; s <= n; ++s) {
        for (int t = 0; s + t <= n; ++t) {
          const float fs = static_cast<float>(s) / n, ft = static_cast<float>(t) / n;
          samples.push_back(a + fs * (b - a) + ft * (c - a));
        }
      }
    }
  }
  const float spacing = 0.1f / n * 1.5f;  // diameter / n, with margin
  for (int i = 0; i < 200; ++i) {
    const Vec3 p(0.08f * u(rng), 0.08f * u(rng), 0.08f * u(rng));
    float brute = std::numeric_limits<float>::infinity();
    for (const Vec3& s : samples) brute = std::min(brute, (s - p).norm());
    const float sd = shape->signedDistance(p);
    EXPECT_LE(std::abs(sd), brute + 1e-6f);
    EXPECT_GE(std::abs(sd), brute - spacing);
    // Sign agrees with the half-space test.
    bool inside = true;
    for (const Face& f : shape->faces()) inside = inside && f.normal.dot(p) <= f.offset;
    EXPECT_EQ(sd <= 0.0f, inside);
    EXPECT_NEAR((shape->closestPoint(p) - p).norm(), std::abs(sd), 1e-6f);
  }
}

// Outside points whose foot misses the farthest face: the closest point is checked against a
// reference that clamps p to every face polygon in turn (projection, else nearest edge point)
// and keeps the nearest; the face reported must hold the point.
TEST(ConvexShape, ClosestPointMatchesClampingToEveryFace) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  auto shape = ConvexShape::fromPoints(randomSpherePoints(rng, u, 40, 0.03f));
  ASSERT_TRUE(shape.ok()) << shape.message();
  const auto& vertices = shape->vertices();
  auto onSegment = [](const Vec3& p, const Vec3& a, const Vec3& b) {
    const float t = std::clamp((p - a).dot(b - a) / (b - a).squaredNorm(), 0.0f, 1.0f);
    return Vec3(a + t * (b - a));
  };
  auto clampToFace = [&](const Face& f, const Vec3& p) {
    const Vec3 projected = p - (f.normal.dot(p) - f.offset) * f.normal;
    bool inside = true;
    Vec3 best = projected;
    float bestD2 = std::numeric_limits<float>::infinity();
    for (std::size_t i = 0; i < f.vertices.size(); ++i) {
      const Vec3& a = vertices[static_cast<std::size_t>(f.vertices[i])];
      const Vec3& b = vertices[static_cast<std::size_t>(f.vertices[(i + 1) % f.vertices.size()])];
      inside = inside && (b - a).cross(projected - a).dot(f.normal) >= 0.0f;
      const Vec3 q = onSegment(p, a, b);
      if ((q - p).squaredNorm() < bestD2) {
        bestD2 = (q - p).squaredNorm();
        best = q;
      }
    }
    return inside ? projected : best;
  };
  int edgeCases = 0;
  for (int i = 0; i < 2000; ++i) {
    const Vec3 p(0.06f * u(rng), 0.06f * u(rng), 0.06f * u(rng));
    Vec3 reference = p;
    float referenceDist = std::numeric_limits<float>::infinity();
    for (const Face& f : shape->faces()) {
      const Vec3 q = clampToFace(f, p);
      if ((q - p).norm() < referenceDist) {
        referenceDist = (q - p).norm();
        reference = q;
      }
    }
    Vec3 closest;
    int face = -1;
    const float sd = shape->query(p, &closest, &face);
    if (sd <= 0.0f) continue;
    ASSERT_GE(face, 0);
    const Face& f = shape->faces()[static_cast<std::size_t>(face)];
    edgeCases += std::abs(f.normal.dot(p) - f.offset - sd) > 1e-6f;
    EXPECT_NEAR(sd, referenceDist, 1e-6f);
    EXPECT_LT((closest - reference).norm(), 1e-5f);
    EXPECT_NEAR(f.normal.dot(closest), f.offset, 1e-6f) << "the face holds the point";
    EXPECT_LT((clampToFace(f, closest) - closest).norm(), 1e-6f);
  }
  EXPECT_GT(edgeCases, 100);  // the edge branch ran
}

TEST(ConvexShape, QueryFromPlaneMatchesQueryInsideAndOutside) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  auto shape = ConvexShape::fromPoints(randomSpherePoints(rng, u, 40, 0.03f));
  ASSERT_TRUE(shape.ok()) << shape.message();
  int inside = 0;
  for (int i = 0; i < 500; ++i) {
    const Vec3 p(0.06f * u(rng), 0.06f * u(rng), 0.06f * u(rng));
    int maxFace = 0;
    float maxDist = -std::numeric_limits<float>::infinity();
    for (std::size_t f = 0; f < shape->faces().size(); ++f) {
      const float d = shape->faces()[f].normal.dot(p) - shape->faces()[f].offset;
      if (d > maxDist) {
        maxDist = d;
        maxFace = static_cast<int>(f);
      }
    }
    inside += maxDist <= 0.0f;
    Vec3 expectedPoint, point;
    int expectedFace = -1, face = -1;
    const float expected = shape->query(p, &expectedPoint, &expectedFace);
    EXPECT_EQ(shape->queryFromPlane(p, maxDist, maxFace, &point, &face), expected);
    EXPECT_EQ(face, expectedFace);
    EXPECT_EQ(point, expectedPoint);
  }
  EXPECT_GT(inside, 10);  // both branches ran
  EXPECT_LT(inside, 480);
}

TEST(ConvexShape, SupportIsExtremeVertex) {
  const ConvexShape shape = ConvexShape::box(Vec3(1, 2, 3));
  EXPECT_LT((shape.support(Vec3(1, 1, 1)) - Vec3(1, 2, 3)).norm(), 1e-6f);
  EXPECT_LT((shape.support(Vec3(-1, 0.1f, -1)) - Vec3(-1, 2, -3)).norm(), 1e-6f);
}

// support (four vertices per SSE instruction) returns the first vertex of the largest dot
// product, as one by one: random hulls of 5 to 64 vertices and random directions, and
// directions where vertices tie.
TEST(ConvexShape, SupportIsTheFirstVertexOfTheLargestDot) {
  auto firstLargest = [](const ConvexShape& shape, const Vec3& direction) {
    std::size_t best = 0;
    float bestDot = -std::numeric_limits<float>::infinity();
    for (std::size_t i = 0; i < shape.vertices().size(); ++i) {
      const float d = shape.vertices()[i].dot(direction);
      if (d > bestDot) bestDot = d, best = i;
    }
    return shape.vertices()[best];
  };
  auto same = [](const Vec3& a, const Vec3& b) { return std::memcmp(&a, &b, sizeof(Vec3)) == 0; };
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (int trial = 0; trial < 60; ++trial) {
    std::vector<Vec3> points;
    const int count = 5 + trial;
    for (int i = 0; i < count; ++i) points.emplace_back(u(rng), u(rng), u(rng));
    const auto shape = ConvexShape::fromPoints(points);
    ASSERT_TRUE(shape.ok());
    for (int d = 0; d < 20; ++d) {
      const Vec3 direction(u(rng), u(rng), u(rng));
      EXPECT_TRUE(same(shape->support(direction), firstLargest(*shape, direction)))
          << "trial " << trial << " direction " << d;
    }
  }
  // Exact ties: a cube (8 vertices) and a cuboctahedron (12) along the 26 directions of
  // {-1, 0, 1}^3, where two, three or four vertices share the largest dot product.
  std::vector<Vec3> cube, cuboctahedron;
  for (int x = -1; x <= 1; x += 2)
    for (int y = -1; y <= 1; y += 2) {
      for (int z = -1; z <= 1; z += 2) cube.emplace_back(x, y, z);
      cuboctahedron.emplace_back(x, y, 0);
      cuboctahedron.emplace_back(x, 0, y);
      cuboctahedron.emplace_back(0, x, y);
    }
  for (const auto* points : {&cube, &cuboctahedron}) {
    const auto shape = ConvexShape::fromPoints(*points);
    ASSERT_TRUE(shape.ok());
    ASSERT_GE(shape->vertices().size(), 8u);  // the four-wide path
    for (int x = -1; x <= 1; ++x)
      for (int y = -1; y <= 1; ++y)
        for (int z = -1; z <= 1; ++z) {
          const Vec3 direction(x, y, z);
          EXPECT_TRUE(same(shape->support(direction), firstLargest(*shape, direction)))
              << shape->vertices().size() << " vertices, direction " << direction.transpose();
        }
  }
}

TEST(ConvexShape, RaycastHitsMissesAndStartsInside) {
  const ConvexShape shape = ConvexShape::box(Vec3(0.1f, 0.1f, 0.1f));
  auto hit = shape.raycast(Vec3(0, 0, -1), Vec3(0, 0, 1), 10.0f);
  ASSERT_TRUE(hit.has_value());
  EXPECT_NEAR(*hit, 0.9f, 1e-6f);
  auto slanted = shape.raycast(Vec3(-1, 0.05f, 0), Vec3(1, 0, 0), 10.0f);
  ASSERT_TRUE(slanted.has_value());
  EXPECT_NEAR(*slanted, 0.9f, 1e-6f);
  EXPECT_FALSE(shape.raycast(Vec3(0, 0.2f, -1), Vec3(0, 0, 1), 10.0f).has_value());
  EXPECT_FALSE(shape.raycast(Vec3(0, 0, -1), Vec3(0, 0, 1), 0.5f).has_value());    // too short
  EXPECT_FALSE(shape.raycast(Vec3(0, 0, -1), Vec3(0, 0, -1), 10.0f).has_value());  // away
  auto inside = shape.raycast(Vec3(0, 0, 0), Vec3(1, 0, 0), 10.0f);
  ASSERT_TRUE(inside.has_value());
  EXPECT_EQ(*inside, 0.0f);
}

TEST(ConvexShape, RejectsFewerThanFourPoints) {
  const std::vector<Vec3> pts = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  auto shape = ConvexShape::fromPoints(pts);
  ASSERT_FALSE(shape.ok());
  EXPECT_NE(shape.message().find("at least 4"), std::string::npos) << shape.message();
}

TEST(ConvexShape, RejectsCoplanarPoints) {
  const std::vector<Vec3> pts = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(1, 1, 0),
                                 Vec3(0.5f, 0.5f, 0)};
  auto shape = ConvexShape::fromPoints(pts);
  ASSERT_FALSE(shape.ok());
  EXPECT_NE(shape.message().find("convex shape"), std::string::npos) << shape.message();
}

TEST(ConvexShape, RejectsCollinearPoints) {
  const std::vector<Vec3> pts = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(2, 0, 0), Vec3(3, 0, 0)};
  EXPECT_FALSE(ConvexShape::fromPoints(pts).ok());
}

TEST(ConvexShape, RejectsNaN) {
  const std::vector<Vec3> pts = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0),
                                 Vec3(0, 0, std::numeric_limits<float>::quiet_NaN())};
  auto shape = ConvexShape::fromPoints(pts);
  ASSERT_FALSE(shape.ok());
  EXPECT_NE(shape.message().find("non-finite"), std::string::npos) << shape.message();
}

TEST(ConvexShape, RejectsInfinity) {
  const std::vector<Vec3> pts = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0),
                                 Vec3(std::numeric_limits<float>::infinity(), 0, 1)};
  EXPECT_FALSE(ConvexShape::fromPoints(pts).ok());
}

}  // namespace
}  // namespace dynahand::physics
