// FaceCells: a point's cell lists every face that can hold its largest face-plane distance,
// so the tracker's scans over those faces find the same face and bits as over all of them.
#include "physics/face_cells.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include "dynahand/convex_shape.h"

namespace dynahand::physics {
namespace {

// A rounded shape like the hand model's bodies: rings of `segments` points (half radius at
// the ends), `rings` of them over `length`, flattened by `flatten` in y.
ConvexShape roundedBody(float radius, float length, float flatten, int rings, int segments) {
  std::vector<Vec3> points;
  for (int r = 0; r < rings; ++r) {
    const float t = static_cast<float>(r) / static_cast<float>(rings - 1);
    const float scale = std::sqrt(std::max(0.25f, 1.0f - (2.0f * t - 1.0f) * (2.0f * t - 1.0f)));
    for (int s = 0; s < segments; ++s) {
      const float a = 2.0f * 3.14159265f *
                      (static_cast<float>(s) + 0.5f * static_cast<float>(r % 2)) /
                      static_cast<float>(segments);
      points.emplace_back(radius * scale * std::cos(a), flatten * radius * scale * std::sin(a),
                          length * t);
    }
  }
  auto shape = ConvexShape::fromPoints(points);
  EXPECT_TRUE(shape.ok());
  return *shape;
}

std::vector<ConvexShape> testShapes() {
  std::vector<ConvexShape> shapes;
  shapes.push_back(roundedBody(0.009f, 0.045f, 1.0f, 6, 8));   // a finger bone
  shapes.push_back(roundedBody(0.045f, 0.09f, 0.35f, 8, 16));  // a palm
  shapes.push_back(ConvexShape::box(Vec3(0.01f, 0.02f, 0.03f)));
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-0.02f, 0.02f);
  std::vector<Vec3> cloud;
  for (int k = 0; k < 60; ++k) cloud.emplace_back(u(rng), u(rng), 2.0f * u(rng));
  shapes.push_back(*ConvexShape::fromPoints(cloud));
  return shapes;
}

// The scans' arithmetic, ((nx qx + ny qy) + nz qz) - offset, over the faces in `mask` (all
// when null): the largest and its first face.
std::pair<float, int> largestPlaneDistance(const ConvexShape& shape, const Vec3& q,
                                           const std::uint64_t* mask) {
  float best = -std::numeric_limits<float>::infinity();
  int face = -1;
  for (std::size_t f = 0; f < shape.faces().size(); ++f) {
    if (mask != nullptr && !(mask[f / 64] >> (f % 64) & 1u)) continue;
    const Face& plane = shape.faces()[f];
    const float d =
        ((plane.normal.x() * q.x() + plane.normal.y() * q.y()) + plane.normal.z() * q.z()) -
        plane.offset;
    if (d > best) {
      best = d;
      face = static_cast<int>(f);
    }
  }
  return {best, face};
}

TEST(FaceCells, CandidatesHoldTheLargestPlaneDistanceBitForBit) {
  std::mt19937 rng(11);
  for (const ConvexShape& shape : testShapes()) {
    const FaceCells& cells = shape.faceCells();
    const FaceCells::Grid& g = cells.grid();
    ASSERT_GT(cells.cellCount(), 0u);
    const Vec3 lo(g.loX, g.loY, g.loZ);
    const Vec3 size = Vec3(g.cellsX, g.cellsY, g.cellsZ) * FaceCells::kCellSize;
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    std::uniform_int_distribution<int> cell(0, 1000);
    long candidates = 0, near = 0;
    for (int k = 0; k < 20000; ++k) {
      Vec3 q = lo + Vec3(u(rng), u(rng), u(rng)).cwiseProduct(size);
      if (k % 4 == 1) {
        // On a cell's corner: the lookup's rounding may put it in either neighbour.
        q = lo + Vec3(static_cast<float>(cell(rng) % static_cast<int>(g.cellsX)),
                      static_cast<float>(cell(rng) % static_cast<int>(g.cellsY)),
                      static_cast<float>(cell(rng) % static_cast<int>(g.cellsZ))) *
                     FaceCells::kCellSize;
      } else if (k % 4 == 2) {
        // Near the surface, where the tracker's points are: a vertex, nudged.
        const auto& v = shape.vertices();
        q = v[static_cast<std::size_t>(cell(rng)) % v.size()] +
            Vec3(u(rng) - 0.5f, u(rng) - 0.5f, u(rng) - 0.5f) * 0.01f;
      }
      const std::uint64_t* mask = cells.candidates(q.x(), q.y(), q.z());
      if (mask == nullptr) continue;
      const auto all = largestPlaneDistance(shape, q, nullptr);
      const auto some = largestPlaneDistance(shape, q, mask);
      ASSERT_EQ(all.first, some.first) << "at " << q.transpose();
      ASSERT_EQ(all.second, some.second) << "at " << q.transpose();
      if (std::abs(all.first) < 0.005f) {
        ++near;
        for (int w = 0; w < cells.words(); ++w) candidates += __builtin_popcountll(mask[w]);
      }
    }
    ASSERT_GT(near, 100);
    // Near the surface a cell lists a few faces, not all of them.
    if (shape.faces().size() > 20) {
      EXPECT_LT(static_cast<double>(candidates) / static_cast<double>(near),
                0.4 * static_cast<double>(shape.faces().size()))
          << shape.faces().size() << " faces";
    }
  }
}

TEST(FaceCells, OutsideTheGridOrNotFiniteMeansEveryFace) {
  const ConvexShape shape = ConvexShape::box(Vec3(0.01f, 0.01f, 0.01f));
  const FaceCells& cells = shape.faceCells();
  EXPECT_NE(cells.candidates(0.0f, 0.0f, 0.0f), nullptr);
  const float edge = 0.01f + FaceCells::kMargin + 2.0f * FaceCells::kCellSize;
  EXPECT_EQ(cells.candidates(edge, 0.0f, 0.0f), nullptr);
  EXPECT_EQ(cells.candidates(0.0f, -edge, 0.0f), nullptr);
  EXPECT_EQ(cells.candidates(0.0f, 0.0f, 1.0f), nullptr);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(cells.candidates(nan, 0.0f, 0.0f), nullptr);
  EXPECT_EQ(cells.candidates(0.0f, std::numeric_limits<float>::infinity(), 0.0f), nullptr);
}

TEST(FaceCells, CopiesOfAShapeShareOneGrid) {
  const ConvexShape shape = ConvexShape::box(Vec3(0.01f, 0.02f, 0.03f));
  const ConvexShape copy = shape;  // before the grid exists
  const FaceCells* built = &copy.faceCells();
  EXPECT_EQ(&shape.faceCells(), built);
  const ConvexShape later = shape;
  EXPECT_EQ(&later.faceCells(), built);
}

}  // namespace
}  // namespace dynahand::physics
