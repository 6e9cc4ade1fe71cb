#include "dynahand/voxel_grid.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

namespace dynahand {
namespace {

// Points placed inside known voxels of size 0.01 m, including negative coordinates.
struct Constructed {
  std::vector<Vec3> points;
  std::vector<Eigen::Vector3d> expectedCentroid;  // in first-hit order
  std::vector<int> expectedCount;
};

Constructed constructedCloud() {
  Constructed c;
  const float size = 0.01f;
  const Eigen::Vector3i voxels[3] = {{3, -2, 50}, {-7, 0, 41}, {3, -2, 51}};
  // Offsets inside a voxel, as fractions of its edge.
  const Eigen::Vector3f offsets[4] = {
      {0.1f, 0.2f, 0.3f}, {0.9f, 0.5f, 0.25f}, {0.5f, 0.75f, 0.6f}, {0.3f, 0.1f, 0.95f}};
  const int perVoxel[3] = {4, 1, 3};
  for (int v = 0; v < 3; ++v) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (int i = 0; i < perVoxel[v]; ++i) {
      const Vec3 p = (voxels[v].cast<float>() + offsets[i]) * size;
      sum += p.cast<double>();
    }
    c.expectedCentroid.push_back(sum / perVoxel[v]);
    c.expectedCount.push_back(perVoxel[v]);
  }
  // Interleave so that first-hit order is voxel 0, 1, 2.
  for (int i = 0; i < 4; ++i) {
    for (int v = 0; v < 3; ++v) {
      if (i < perVoxel[v]) {
        c.points.push_back((voxels[v].cast<float>() + offsets[i]) * size);
      }
    }
  }
  return c;
}

TEST(VoxelGrid, CentroidsOfConstructedCloudAreExact) {
  const Constructed c = constructedCloud();
  // Float precision near 0.5 m is 6e-8 m: "exact" means within two of those.
  VoxelGrid grid(0.01f, 64);
  grid.clear();
  for (std::size_t i = 0; i < c.points.size(); ++i) {
    EXPECT_TRUE(grid.add(c.points[i], static_cast<std::int32_t>(i)));
  }
  ASSERT_EQ(grid.voxelCount(), 3);
  EXPECT_EQ(grid.droppedPoints(), 0);
  for (int v = 0; v < 3; ++v) {
    EXPECT_EQ(grid.count(v), c.expectedCount[static_cast<std::size_t>(v)]);
    const Vec3 centroid = grid.centroid(v);
    for (int a = 0; a < 3; ++a) {
      EXPECT_NEAR(centroid[a], c.expectedCentroid[static_cast<std::size_t>(v)][a], 1.2e-7)
          << "voxel " << v << " axis " << a;
    }
  }
  EXPECT_EQ(grid.firstTag(0), 0);
  EXPECT_EQ(grid.firstTag(1), 1);
  EXPECT_EQ(grid.firstTag(2), 2);
}

TEST(VoxelGrid, OnePointPerOccupiedVoxelOnARegularLattice) {
  // A 10 x 10 x 2 lattice with 3 points per voxel: 200 voxels, each centroid at the mean.
  VoxelGrid grid(0.005f, 1024);
  grid.clear();
  for (int z = 0; z < 2; ++z) {
    for (int y = 0; y < 10; ++y) {
      for (int x = 0; x < 10; ++x) {
        const Vec3 corner =
            Vec3(static_cast<float>(x), static_cast<float>(y), static_cast<float>(100 + z)) *
            0.005f;
        for (int i = 0; i < 3; ++i) {
          grid.add(corner + Vec3(0.001f, 0.001f + 0.001f * static_cast<float>(i), 0.002f));
        }
      }
    }
  }
  ASSERT_EQ(grid.voxelCount(), 200);
  for (int i = 0; i < grid.voxelCount(); ++i) {
    EXPECT_EQ(grid.count(i), 3);
    const int x = i % 10;
    const int y = (i / 10) % 10;
    const int z = i / 100;
    const Vec3 expected =
        Vec3(static_cast<float>(x), static_cast<float>(y), static_cast<float>(100 + z)) * 0.005f +
        Vec3(0.001f, 0.002f, 0.002f);
    EXPECT_LT((grid.centroid(i) - expected).norm(), 1e-6f) << "voxel " << i;
  }
}

TEST(VoxelGrid, ClearForgetsPreviousFrame) {
  VoxelGrid grid(0.01f, 8);
  grid.clear();
  grid.add(Vec3(0.001f, 0.001f, 0.501f));
  grid.add(Vec3(0.101f, 0.001f, 0.501f));
  ASSERT_EQ(grid.voxelCount(), 2);
  for (int frame = 0; frame < 3; ++frame) {
    grid.clear();
    EXPECT_EQ(grid.voxelCount(), 0);
    grid.add(Vec3(0.003f, 0.004f, 0.505f));
    ASSERT_EQ(grid.voxelCount(), 1);
    EXPECT_EQ(grid.count(0), 1);  // not merged with the previous frame's point
    EXPECT_LT((grid.centroid(0) - Vec3(0.003f, 0.004f, 0.505f)).norm(), 1e-7f);
  }
}

TEST(VoxelGrid, FullTableDropsAndCountsPoints) {
  VoxelGrid grid(0.01f, 2);
  grid.clear();
  EXPECT_TRUE(grid.add(Vec3(0.005f, 0.0f, 0.5f)));
  EXPECT_TRUE(grid.add(Vec3(0.015f, 0.0f, 0.5f)));
  EXPECT_FALSE(grid.add(Vec3(0.025f, 0.0f, 0.5f)));  // a third voxel
  EXPECT_TRUE(grid.add(Vec3(0.006f, 0.0f, 0.5f)));   // joins an existing voxel
  EXPECT_EQ(grid.voxelCount(), 2);
  EXPECT_EQ(grid.droppedPoints(), 1);
  EXPECT_EQ(grid.count(0), 2);
}

TEST(VoxelGrid, NonFiniteAndFarPointsAreDropped) {
  VoxelGrid grid(0.001f, 8);
  grid.clear();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  EXPECT_FALSE(grid.add(Vec3(nan, 0.0f, 0.5f)));
  EXPECT_FALSE(grid.add(Vec3(0.0f, inf, 0.5f)));
  EXPECT_FALSE(grid.add(Vec3(0.0f, 0.0f, 5000.0f)));  // beyond 2^20 voxels of 1 mm
  EXPECT_EQ(grid.voxelCount(), 0);
  EXPECT_EQ(grid.droppedPoints(), 3);
}

TEST(VoxelGrid, CollidingHashesStayDistinct) {
  // Many voxels in a small table force probing; every voxel must keep its own points.
  VoxelGrid grid(0.002f, 600);
  grid.clear();
  for (int i = 0; i < 600; ++i) {
    const Vec3 p(0.002f * static_cast<float>(i % 30) + 0.0005f,
                 0.002f * static_cast<float>(i / 30) + 0.0005f, 0.4005f);
    ASSERT_TRUE(grid.add(p));
    ASSERT_TRUE(grid.add(p + Vec3(0.001f, 0.001f, 0.001f)));
  }
  ASSERT_EQ(grid.voxelCount(), 600);
  for (int i = 0; i < 600; ++i) {
    EXPECT_EQ(grid.count(i), 2);
    const Vec3 expected(0.002f * static_cast<float>(i % 30) + 0.001f,
                        0.002f * static_cast<float>(i / 30) + 0.001f, 0.401f);
    EXPECT_LT((grid.centroid(i) - expected).norm(), 1e-6f);
  }
}

}  // namespace
}  // namespace dynahand
