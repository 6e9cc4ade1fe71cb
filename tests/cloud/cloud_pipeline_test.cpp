#include "dynahand/cloud.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "cloud/scenes.h"

namespace dynahand {
namespace {

using cloud::scenes::Sphere;

// A flat disc of spheres facing the camera (a blob of about radius + sphereRadius).
std::vector<Sphere> disc(const Vec3& centre, float radius) {
  std::vector<Sphere> s;
  for (float y = -radius; y <= radius + 1e-6f; y += 0.01f) {
    for (float x = -radius; x <= radius + 1e-6f; x += 0.01f) {
      if (x * x + y * y <= radius * radius) s.push_back({centre + Vec3(x, y, 0.0f), 0.015f});
    }
  }
  return s;
}

bool maskAt(const CloudFrame& out, const Vec3& p) {
  const Vec2 px = out.intrinsics.project(p);
  const int u = static_cast<int>(std::lround(px.x()));
  const int v = static_cast<int>(std::lround(px.y()));
  return out.mask[static_cast<std::size_t>(v) * out.intrinsics.width + u] != 0;
}

TEST(CloudPipeline, PlaneAtHalfMetreDeprojectsToHalfMetreEverywhere) {
  const Intrinsics k = cloud::scenes::camera(320, 240);
  DepthFrame frame(320, 240, 0.001f);
  std::fill(frame.depth.begin(), frame.depth.end(), std::uint16_t{500});
  CloudConfig config;
  config.segmentation.supportPlanes.enabled = false;  // the plane stands for the hand here
  CloudPipeline pipeline(k, config);
  CloudFrame out;
  ASSERT_TRUE(pipeline.process(frame, out).ok());
  ASSERT_TRUE(out.segment.found);
  ASSERT_GT(out.pointCount(), 100u);
  for (const Vec3& p : out.points) EXPECT_NEAR(p.z(), 0.5f, 1e-6f);
  int masked = 0;
  for (int v = 0; v < k.height; ++v) {
    for (int u = 0; u < k.width; ++u) {
      if (!out.mask[static_cast<std::size_t>(v) * k.width + u]) continue;
      ++masked;
      EXPECT_NEAR(out.depthAt(u, v), 0.5f, 1e-6f);
    }
  }
  EXPECT_EQ(masked, out.segment.pixelCount);
  // The region is the part of the plane within the hand radius of its nearest point.
  const float radius = pipeline.config().segmentation.handRadiusM;
  for (const Vec3& p : out.points) {
    EXPECT_LE((p - out.segment.nearestPoint).norm(), radius + 1e-5f);
  }
  int weights = 0;
  for (int w : out.pointWeights) weights += w;
  EXPECT_EQ(weights, out.segment.sampleCount);
}

TEST(CloudPipeline, SegmentationPicksTheNearerOfTwoBlobs) {
  const Intrinsics k = cloud::scenes::camera(320, 240);
  for (int swap = 0; swap < 2; ++swap) {
    const Vec3 a(0.1f, 0.0f, swap ? 0.6f : 0.5f);
    const Vec3 b(-0.12f, 0.02f, swap ? 0.5f : 0.6f);
    std::vector<Sphere> spheres = disc(a, 0.05f);
    const std::vector<Sphere> other = disc(b, 0.05f);
    spheres.insert(spheres.end(), other.begin(), other.end());
    const DepthFrame frame = cloud::scenes::render(k, spheres, 1.0f);
    CloudPipeline pipeline(k);
    CloudFrame out;
    ASSERT_TRUE(pipeline.process(frame, out).ok());
    ASSERT_TRUE(out.segment.found);
    const Vec3& nearer = swap ? b : a;
    const Vec3& farther = swap ? a : b;
    EXPECT_TRUE(maskAt(out, nearer - Vec3(0, 0, 0.015f)));
    EXPECT_FALSE(maskAt(out, farther - Vec3(0, 0, 0.015f)));
    for (const Vec3& p : out.points) {
      EXPECT_LT((p - nearer).norm(), 0.08f);  // only the nearer blob, not the wall
    }
    EXPECT_EQ(out.segment.cutPixelCount, 0);  // nothing connected beyond the radius
    EXPECT_EQ(out.segment.armDirection, Vec3::Zero());
  }
}

TEST(CloudPipeline, SpecksSmallerThanTheMinimumAreaAreSkipped) {
  const Intrinsics k = cloud::scenes::camera(320, 240);
  std::vector<Sphere> spheres = disc(Vec3(0.05f, 0.0f, 0.5f), 0.05f);
  const Vec3 speck(-0.05f, -0.05f, 0.3f);
  spheres.push_back({speck, 0.008f});  // 2e-4 m^2, nearer than the blob
  const DepthFrame frame = cloud::scenes::render(k, spheres, 1.0f);
  CloudPipeline pipeline(k);
  CloudFrame out;
  ASSERT_TRUE(pipeline.process(frame, out).ok());
  ASSERT_TRUE(out.segment.found);
  EXPECT_GT(out.segment.nearestPoint.z(), 0.45f);
  EXPECT_FALSE(maskAt(out, speck));
  EXPECT_GE(out.segment.areaM2, pipeline.config().segmentation.minAreaM2);
}

// A hand broken up by missing data (fingers seen edge-on by a structured-light camera): small
// pieces in front of the volume taken, within its ball, belong to it; a speck does not.
TEST(CloudPipeline, PiecesInFrontOfTheVolumeTakenJoinIt) {
  const Intrinsics k = cloud::scenes::camera(320, 240);
  std::vector<Sphere> spheres = disc(Vec3(0.0f, 0.03f, 0.55f), 0.05f);  // the palm
  const Vec3 pieceA(-0.03f, -0.055f, 0.52f), pieceB(0.03f, -0.055f, 0.51f);
  spheres.push_back({pieceA, 0.012f});  // about 4.5 cm^2 each: under minAreaM2 alone
  spheres.push_back({pieceB, 0.012f});
  const Vec3 speck(0.07f, -0.03f, 0.5f);
  spheres.push_back({speck, 0.003f});  // 0.3 cm^2: noise
  const DepthFrame frame = cloud::scenes::render(k, spheres, 1.0f);
  CloudPipeline pipeline(k);
  CloudFrame out;
  ASSERT_TRUE(pipeline.process(frame, out).ok());
  ASSERT_TRUE(out.segment.found);
  EXPECT_GT(out.segment.nearestPoint.z(), 0.52f);  // the palm was the volume taken
  EXPECT_TRUE(maskAt(out, Vec3(0.0f, 0.03f, 0.54f)));
  EXPECT_TRUE(maskAt(out, pieceA));
  EXPECT_TRUE(maskAt(out, pieceB));
  EXPECT_FALSE(maskAt(out, speck));
  int nearPieces = 0;
  for (const Vec3& p : out.points) nearPieces += (p - pieceA).norm() < 0.015f;
  EXPECT_GT(nearPieces, 0) << "the pieces' samples are in the cloud";
}

// Pieces each under minAreaM2 that together make one (a hand seen edge-on, broken up) are
// taken before a larger surface farther behind (the forearm), which would otherwise win.
TEST(CloudPipeline, AHandInPiecesIsTakenBeforeALargerSurfaceBehindIt) {
  const Intrinsics k = cloud::scenes::camera(320, 240);
  std::vector<Sphere> spheres;
  cloud::scenes::addCapsule(spheres, Vec3(0.0f, 0.02f, 0.68f), Vec3(0.0f, 0.2f, 0.7f), 0.05f,
                            0.01f);  // the forearm, across the image's lower half
  const std::vector<Vec3> pieces = {Vec3(-0.05f, -0.02f, 0.50f), Vec3(0.0f, -0.03f, 0.51f),
                                    Vec3(0.05f, -0.02f, 0.52f)};
  for (const Vec3& c : pieces) spheres.push_back({c, 0.02f});  // about 12 cm^2 each
  const DepthFrame frame = cloud::scenes::render(k, spheres, 0.0f);
  CloudPipeline pipeline(k);
  const float minArea = pipeline.config().segmentation.minAreaM2;
  CloudFrame out;
  ASSERT_TRUE(pipeline.process(frame, out).ok());
  ASSERT_TRUE(out.segment.found);
  EXPECT_LT(out.segment.nearestPoint.z(), 0.5f);
  for (const Vec3& c : pieces) EXPECT_TRUE(maskAt(out, c - Vec3(0.0f, 0.0f, 0.02f)));
  EXPECT_FALSE(maskAt(out, Vec3(0.0f, 0.12f, 0.66f)));
  EXPECT_GE(out.segment.areaM2, minArea);
  // Each piece alone is under the minimum: only together are they a volume.
  CloudFrame one;
  const DepthFrame single = cloud::scenes::render(k, {{pieces[1], 0.02f}}, 0.0f);
  ASSERT_TRUE(pipeline.process(single, one).ok());
  EXPECT_FALSE(one.segment.found);
}

// Pieces taken together keep the hand-radius rule: no sample beyond the radius of the segment's
// nearest point is in the cloud or the mask, at either grow step (two pieces 17 cm apart: the
// farther one's far side lies beyond the ball).
TEST(CloudPipeline, PiecesTakenTogetherStayWithinTheHandRadius) {
  const Intrinsics k = cloud::scenes::camera(320, 240);
  std::vector<Sphere> spheres;
  cloud::scenes::addCapsule(spheres, Vec3(0.0f, 0.02f, 0.68f), Vec3(0.0f, 0.2f, 0.7f), 0.05f,
                            0.01f);
  spheres.push_back({Vec3(0.0f, -0.02f, 0.50f), 0.025f});
  spheres.push_back({Vec3(0.0f, 0.15f, 0.505f), 0.025f});
  const DepthFrame frame = cloud::scenes::render(k, spheres, 0.0f);
  for (const int growStep : {1, 2}) {
    SCOPED_TRACE(growStep);
    CloudConfig config;
    config.segmentation.growStep = growStep;
    CloudPipeline pipeline(k, config);
    CloudFrame out;
    ASSERT_TRUE(pipeline.process(frame, out).ok());
    ASSERT_TRUE(out.segment.found);
    EXPECT_LT(out.segment.nearestPoint.z(), 0.5f);  // the pieces, not the forearm
    const float radius = config.segmentation.handRadiusM;
    const float voxelDiagonal = config.voxelSizeM * std::sqrt(3.0f);
    for (const Vec3& p : out.points)
      EXPECT_LE((p - out.segment.nearestPoint).norm(), radius + voxelDiagonal);
    int beyond = 0;
    for (int v = 0; v < k.height; ++v) {
      for (int u = 0; u < k.width; ++u) {
        const float z = out.depthAt(u, v);
        if (z <= 0.0f || z > 0.6f) continue;
        const Vec3 p = k.deproject(static_cast<float>(u), static_cast<float>(v), z);
        if ((p - out.segment.nearestPoint).norm() <= radius + 0.005f) continue;
        beyond += out.mask[static_cast<std::size_t>(v) * k.width + u] != 0;
      }
    }
    EXPECT_EQ(beyond, 0) << "mask pixels beyond the hand radius";
  }
}

TEST(CloudPipeline, RangeGateIgnoresObjectsTooClose) {
  const Intrinsics k = cloud::scenes::camera(320, 240);
  std::vector<Sphere> spheres = disc(Vec3(0.0f, 0.0f, 0.6f), 0.06f);
  const std::vector<Sphere> tooClose = disc(Vec3(0.0f, 0.0f, 0.1f), 0.02f);
  spheres.insert(spheres.end(), tooClose.begin(), tooClose.end());
  const DepthFrame frame = cloud::scenes::render(k, spheres, 1.0f);
  // The object too close hides the disc: what is left is the wall, which stands for the hand.
  CloudConfig config;  // minDepthM 0.15
  config.segmentation.supportPlanes.enabled = false;
  CloudPipeline pipeline(k, config);
  CloudFrame out;
  ASSERT_TRUE(pipeline.process(frame, out).ok());
  ASSERT_TRUE(out.segment.found);
  for (const Vec3& p : out.points) EXPECT_GT(p.z(), 0.5f);
}

TEST(CloudPipeline, AWallIsASupportPlaneAndLeftOut) {
  const Intrinsics k = cloud::scenes::camera(320, 240);
  // A hand-sized disc 4 cm in front of a wall: without support planes the wall's samples near
  // the disc would be one surface with it.
  const DepthFrame frame = cloud::scenes::render(k, disc(Vec3(0.0f, 0.0f, 0.5f), 0.06f), 0.54f);
  CloudPipeline pipeline(k);
  CloudFrame out;
  ASSERT_TRUE(pipeline.process(frame, out).ok());
  ASSERT_TRUE(out.segment.found);
  ASSERT_EQ(out.segment.supportPlaneCount, 1);
  const SupportPlane& wall = out.segment.supportPlanes[0];
  EXPECT_NEAR(wall.normal.z(), -1.0f, 1e-3f);  // facing the camera
  EXPECT_NEAR(wall.offset, -0.54f, 2e-3f);
  EXPECT_GT(wall.areaM2, pipeline.config().segmentation.supportPlanes.minAreaM2);
  for (const Vec3& p : out.points) EXPECT_LT(p.z(), 0.54f - 0.01f);
}

TEST(CloudPipeline, AHandSizedSurfaceIsNoSupportPlane) {
  const Intrinsics k = cloud::scenes::camera(320, 240);
  const DepthFrame frame = cloud::scenes::render(k, disc(Vec3(0.0f, 0.0f, 0.5f), 0.06f), 0.0f);
  CloudPipeline pipeline(k);
  CloudFrame out;
  ASSERT_TRUE(pipeline.process(frame, out).ok());
  ASSERT_TRUE(out.segment.found);
  EXPECT_EQ(out.segment.supportPlaneCount, 0);
  EXPECT_GT(out.pointCount(), 100u);
}

TEST(CloudPipeline, ForearmIsCutAtTheHandRadiusAndItsSideHasNoPlane) {
  const Intrinsics k = cloud::scenes::camera(320, 240);
  const std::vector<Sphere> hand = cloud::scenes::handWithForearm(Vec3(0.0f, -0.03f, 0.5f), 0.35f);
  const DepthFrame frame = cloud::scenes::render(k, hand, 1.2f);
  CloudPipeline pipeline(k);
  CloudFrame out;
  ASSERT_TRUE(pipeline.process(frame, out).ok());
  const Segment& s = out.segment;
  ASSERT_TRUE(s.found);
  const float radius = pipeline.config().segmentation.handRadiusM;
  const float voxelDiagonal = pipeline.config().voxelSizeM * std::sqrt(3.0f);
  for (const Vec3& p : out.points) {
    EXPECT_LE((p - s.nearestPoint).norm(), radius + voxelDiagonal);
  }
  EXPECT_GT(s.cutPixelCount, 0);
  EXPECT_GT(s.armDirection.dot(Vec3(0.0f, 0.8f, 0.6f)), 0.8f);  // toward the elbow
  EXPECT_GT(s.armDirectionImage.y(), 0.8f);                     // downward in the image
  // The planes keep every side but the arm's.
  const BoundaryPlaneConfig& pc = pipeline.config().planes;
  EXPECT_LT(out.planes.size(), static_cast<std::size_t>(pc.planeCount));
  for (const BoundaryPlane& plane : out.planes) {
    EXPECT_LT(plane.imageDirection.dot(Vec2(0.0f, 1.0f)), std::cos(pc.omitHalfAngle) + 0.01f);
  }
}

// Every voxel point and every masked pixel (deprojected at its depth) lies inside all planes.
void checkPlanesContainSegment(const Intrinsics& k, const CloudConfig& config,
                               const CloudFrame& out) {
  ASSERT_EQ(out.planes.size(), static_cast<std::size_t>(config.planes.planeCount));
  for (const BoundaryPlane& plane : out.planes) {
    for (const Vec3& p : out.points) EXPECT_LE(plane.signedDistance(p), 1e-6f);
    for (int v = 0; v < k.height; ++v) {
      for (int u = 0; u < k.width; ++u) {
        if (!out.mask[static_cast<std::size_t>(v) * k.width + u]) continue;
        const Vec3 p = k.deproject(static_cast<float>(u), static_cast<float>(v), out.depthAt(u, v));
        ASSERT_LE(plane.signedDistance(p), 1e-6f) << "pixel " << u << "," << v;
      }
    }
  }
}

TEST(CloudPipeline, BoundaryPlanesContainEverySegmentedPixelAndPoint) {
  // Stride 1 at 320x240, and strides 2 and 3 at 640x480 (mask blocks around samples).
  for (const int stride : {1, 2, 3}) {
    SCOPED_TRACE(stride);
    const Intrinsics k = cloud::scenes::camera(stride == 1 ? 320 : 640, stride == 1 ? 240 : 480);
    const DepthFrame frame =
        cloud::scenes::render(k, cloud::scenes::handWithForearm(Vec3(0.04f, 0.0f, 0.45f)), 0.9f);
    CloudConfig config;
    config.planes.omitHalfAngle = 0.0f;  // all sides
    config.sampleStride = stride;
    CloudPipeline pipeline(k, config);
    CloudFrame out;
    ASSERT_TRUE(pipeline.process(frame, out).ok());
    ASSERT_TRUE(out.segment.found);
    EXPECT_EQ(out.filterStride, stride);
    checkPlanesContainSegment(k, config, out);
  }
}

TEST(CloudPipeline, AutomaticStrideKeepsHalfAVoxelBetweenSamples) {
  // Hand at 0.45 m; 60-degree camera. 320 px: 1.6 mm between pixels -> stride 1;
  // 640 px: 0.8 mm -> stride 3 (2.4 mm <= 2.5 mm).
  for (const int width : {320, 640}) {
    const Intrinsics k = cloud::scenes::camera(width, width * 3 / 4);
    const DepthFrame frame =
        cloud::scenes::render(k, cloud::scenes::handWithForearm(Vec3(0.0f, 0.0f, 0.45f)), 0.9f);
    CloudPipeline pipeline(k);
    CloudFrame out;
    ASSERT_TRUE(pipeline.process(frame, out).ok());
    ASSERT_TRUE(out.segment.found);
    const float spacing =
        out.segment.nearestPoint.z() * static_cast<float>(out.filterStride) / k.fx;
    // The stride is chosen at the coarse nearest depth, within a few mm of the final one.
    const float halfVoxel = 0.5f * pipeline.config().voxelSizeM;
    EXPECT_LE(spacing, 1.02f * halfVoxel);
    EXPECT_GT(
        spacing / static_cast<float>(out.filterStride) * static_cast<float>(out.filterStride + 1),
        0.98f * halfVoxel);  // the largest such stride
    EXPECT_EQ(out.filterStride, width == 320 ? 1 : 3);
    int weights = 0;
    for (int w : out.pointWeights) weights += w;
    EXPECT_EQ(weights, out.segment.sampleCount);
  }
}

TEST(CloudPipeline, GrowStep2SegmentsTheSameHandAsEverySample) {
  // 320 px, hand at 0.45 m: working stride 1; growStep 2 grows on every other sample (3.2 mm
  // apart, within a 5 mm voxel) and lets the samples between join. Same hand, within a few
  // percent of the samples, every point in the ball.
  const Intrinsics k = cloud::scenes::camera(320, 240);
  const DepthFrame frame =
      cloud::scenes::render(k, cloud::scenes::handWithForearm(Vec3(0.0f, 0.0f, 0.45f)), 0.9f);
  CloudConfig sparse;
  sparse.segmentation.growStep = 2;
  CloudPipeline every(k);
  CloudPipeline half(k, sparse);
  CloudFrame a;
  CloudFrame b;
  ASSERT_TRUE(every.process(frame, a).ok());
  ASSERT_TRUE(half.process(frame, b).ok());
  ASSERT_TRUE(a.segment.found && b.segment.found);
  EXPECT_EQ(b.filterStride, 1);
  EXPECT_NEAR(static_cast<float>(b.segment.sampleCount), static_cast<float>(a.segment.sampleCount),
              0.03f * a.segment.sampleCount);
  EXPECT_NEAR(static_cast<float>(b.pointCount()), static_cast<float>(a.pointCount()),
              0.03f * static_cast<float>(a.pointCount()));
  int weights = 0;
  for (int w : b.pointWeights) weights += w;
  EXPECT_EQ(weights, b.segment.sampleCount);
  const float radius = sparse.segmentation.handRadiusM;
  for (const Vec3& p : b.points) EXPECT_LE((p - b.segment.nearestPoint).norm(), radius + 1e-5f);
}

TEST(CloudPipeline, FreeSpaceQueryAgreesWithBruteForce) {
  const Intrinsics k = cloud::scenes::camera(160, 120);
  // No wall: the background has no data (free), the hand occludes.
  const DepthFrame frame =
      cloud::scenes::render(k, cloud::scenes::handWithForearm(Vec3(0.0f, -0.02f, 0.5f)), 0.0f);
  CloudConfig config;
  config.filter.median = false;
  config.filter.removeFlyingPixels = false;
  CloudPipeline pipeline(k, config);
  CloudFrame out;
  ASSERT_TRUE(pipeline.process(frame, out).ok());
  ASSERT_TRUE(out.segment.found);

  std::uint32_t state = 99u;
  const auto next = [&state] {
    state = state * 1664525u + 1013904223u;
    return static_cast<float>(state >> 8) / 16777216.0f;
  };
  int checked = 0;
  int freeCount = 0;
  for (int n = 0; n < 300; ++n) {
    const Vec3 p((next() - 0.5f) * 0.5f, (next() - 0.5f) * 0.4f, 0.3f + 0.5f * next());
    // Brute force: the pixel whose ray is closest in angle to p, its raw depth.
    const Vec3 dir = p.normalized();
    int bestU = -1;
    int bestV = -1;
    float bestCos = -2.0f;
    for (int v = 0; v < k.height; ++v) {
      for (int u = 0; u < k.width; ++u) {
        const float c = k.ray(static_cast<float>(u), static_cast<float>(v)).dot(dir);
        if (c > bestCos) {
          bestCos = c;
          bestU = u;
          bestV = v;
        }
      }
    }
    // Skip points right on a pixel border, where rounding may pick either side.
    const Vec2 px = k.project(p);
    const float fu = px.x() - std::floor(px.x());
    const float fv = px.y() - std::floor(px.y());
    if (std::fabs(fu - 0.5f) < 0.02f || std::fabs(fv - 0.5f) < 0.02f) continue;
    if (!k.contains(px.x(), px.y())) {
      EXPECT_FALSE(out.isFree(p));
      continue;
    }
    const float observed = frame.metres(bestU, bestV);
    const bool expectedFree = observed == 0.0f || observed > p.z();
    EXPECT_EQ(out.isFree(p), expectedFree) << "point " << p.transpose();
    ++checked;
    freeCount += expectedFree;
  }
  EXPECT_GT(checked, 200);
  EXPECT_GT(freeCount, 10);
  EXPECT_LT(freeCount, checked);
  EXPECT_FALSE(out.isFree(Vec3(0.0f, 0.0f, -0.5f)));  // behind the camera: unknown
}

TEST(CloudPipeline, AllZeroFrameIsValidAndHasNoHand) {
  const Intrinsics k = cloud::scenes::camera(320, 240);
  const DepthFrame frame(320, 240, 0.001f);
  CloudPipeline pipeline(k);
  CloudFrame out;
  const Status status = pipeline.process(frame, out);
  ASSERT_TRUE(status.ok());
  EXPECT_FALSE(out.segment.found);
  EXPECT_EQ(out.pointCount(), 0u);
  EXPECT_TRUE(out.planes.empty());
  EXPECT_TRUE(out.isFree(Vec3(0.0f, 0.0f, 0.5f)));  // no data: free
}

TEST(CloudPipeline, FrameSizeDifferentFromIntrinsicsIsAnError) {
  CloudPipeline pipeline(cloud::scenes::camera(320, 240));
  CloudFrame out;
  const Status status = pipeline.process(DepthFrame(640, 480, 0.001f), out);
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.message().find("640 x 480"), std::string::npos) << status.message();
  EXPECT_NE(status.message().find("320 x 240"), std::string::npos) << status.message();
  EXPECT_EQ(out.pointCount(), 0u);
}

TEST(CloudPipeline, DepthBufferOfWrongLengthIsAnError) {
  CloudPipeline pipeline(cloud::scenes::camera(320, 240));
  DepthFrame frame(320, 240, 0.001f);
  frame.depth.resize(1000);
  CloudFrame out;
  const Status status = pipeline.process(frame, out);
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.message().find("1000"), std::string::npos) << status.message();
}

TEST(CloudPipeline, NonPositiveDepthScaleIsAnError) {
  CloudPipeline pipeline(cloud::scenes::camera(320, 240));
  CloudFrame out;
  for (float scale : {0.0f, -0.001f, std::nanf("")}) {
    DepthFrame frame(320, 240, scale);
    const Status status = pipeline.process(frame, out);
    ASSERT_FALSE(status.ok()) << scale;
    EXPECT_NE(status.message().find("depth scale"), std::string::npos) << status.message();
  }
}

TEST(CloudPipeline, MaskFollowsTheHandBetweenFramesAndBuffersAreReused) {
  const Intrinsics k = cloud::scenes::camera(320, 240);
  const Vec3 left(-0.1f, 0.0f, 0.5f);
  const Vec3 right(0.1f, 0.0f, 0.5f);
  const DepthFrame a = cloud::scenes::render(k, disc(left, 0.05f), 1.0f);
  const DepthFrame b = cloud::scenes::render(k, disc(right, 0.05f), 1.0f);
  CloudPipeline pipeline(k);
  CloudFrame out;
  ASSERT_TRUE(pipeline.process(a, out).ok());
  EXPECT_TRUE(maskAt(out, left));
  const Vec3* pointsData = out.points.data();
  const float* filteredData = out.filteredDepthM.data();
  ASSERT_TRUE(pipeline.process(b, out).ok());
  EXPECT_FALSE(maskAt(out, left));
  EXPECT_TRUE(maskAt(out, right));
  ASSERT_TRUE(pipeline.process(a, out).ok());
  EXPECT_EQ(out.points.data(), pointsData);  // no reallocation after the first frame
  EXPECT_EQ(out.filteredDepthM.data(), filteredData);
}

TEST(CloudPipeline, ResultsAreDeterministic) {
  const Intrinsics k = cloud::scenes::camera(320, 240);
  const DepthFrame frame =
      cloud::scenes::render(k, cloud::scenes::handWithForearm(Vec3(0.0f, 0.0f, 0.45f)), 0.9f);
  CloudPipeline p1(k);
  CloudPipeline p2(k);
  CloudFrame o1;
  CloudFrame o2;
  ASSERT_TRUE(p1.process(frame, o1).ok());
  ASSERT_TRUE(p2.process(frame, o2).ok());
  ASSERT_TRUE(p2.process(frame, o2).ok());  // a reused frame gives the same answer
  ASSERT_EQ(o1.pointCount(), o2.pointCount());
  Fnv1a h1;
  Fnv1a h2;
  for (std::size_t i = 0; i < o1.pointCount(); ++i) {
    h1.add(o1.points[i]);
    h2.add(o2.points[i]);
    EXPECT_EQ(o1.pointWeights[i], o2.pointWeights[i]);
    EXPECT_EQ(o1.pointPixels[i], o2.pointPixels[i]);
  }
  EXPECT_EQ(h1.value(), h2.value());
}

TEST(CloudPipeline, SecondRegionTakesTheOtherHand) {
  const Intrinsics k = cloud::scenes::camera(320, 240);
  std::vector<Sphere> spheres = disc(Vec3(-0.15f, 0.0f, 0.5f), 0.05f);
  const std::vector<Sphere> other = disc(Vec3(0.15f, 0.0f, 0.55f), 0.05f);
  spheres.insert(spheres.end(), other.begin(), other.end());
  const DepthFrame frame = cloud::scenes::render(k, spheres, 1.0f);
  CloudFrame out;
  CloudPipeline one(k);
  ASSERT_TRUE(one.process(frame, out).ok());
  EXPECT_EQ(out.segment.regionCount, 1);
  CloudConfig config;
  config.segmentation.secondRegionDepthBandM = 0.1f;
  CloudPipeline two(k, config);
  ASSERT_TRUE(two.process(frame, out).ok());
  EXPECT_EQ(out.segment.regionCount, 2);
  EXPECT_TRUE(maskAt(out, Vec3(-0.15f, 0.0f, 0.5f)));
  EXPECT_TRUE(maskAt(out, Vec3(0.15f, 0.0f, 0.55f)));
}

// --- filters: a two-level step edge with one column of mixed (flying) pixels ---
DepthFrame stepEdgeFrame() {
  DepthFrame frame(160, 120, 0.001f);
  for (int v = 0; v < 120; ++v) {
    for (int u = 0; u < 160; ++u) frame.at(u, v) = u < 80 ? 500 : 1000;
    frame.at(80, v) = 750;  // halfway between: a flying pixel on every row
  }
  frame.at(40, 60) = 0;  // a one-pixel hole in the near surface
  return frame;
}

TEST(CloudFilter, FlyingPixelsAtDepthEdgesAreRemoved) {
  const Intrinsics k = cloud::scenes::camera(160, 120);
  CloudConfig config;
  config.filter.median = false;
  config.segmentation.handRadiusM = 1.0f;             // filter box covers the edge
  config.segmentation.supportPlanes.enabled = false;  // the two planes stand for a hand
  CloudPipeline pipeline(k, config);
  CloudFrame out;
  ASSERT_TRUE(pipeline.process(stepEdgeFrame(), out).ok());
  ASSERT_TRUE(out.filterBox.contains(81, 60));
  EXPECT_EQ(out.depthAt(80, 60), 0.0f);           // flying: removed
  EXPECT_NEAR(out.depthAt(79, 60), 0.5f, 1e-6f);  // true edge of the near surface kept
  EXPECT_NEAR(out.depthAt(81, 60), 1.0f, 1e-6f);  // and of the far surface
  EXPECT_EQ(out.depthAt(40, 60), 0.0f);           // hole stays a hole without median
  for (int v = 0; v < 120; ++v) EXPECT_EQ(out.mask[static_cast<std::size_t>(v) * 160 + 80], 0);
}

TEST(CloudFilter, MedianFillsOnePixelHoles) {
  const Intrinsics k = cloud::scenes::camera(160, 120);
  CloudConfig config;  // median on by default
  config.segmentation.handRadiusM = 1.0f;
  config.segmentation.supportPlanes.enabled = false;  // the two planes stand for a hand
  CloudPipeline pipeline(k, config);
  CloudFrame out;
  ASSERT_TRUE(pipeline.process(stepEdgeFrame(), out).ok());
  ASSERT_TRUE(out.filterBox.contains(40, 60));
  EXPECT_NEAR(out.depthAt(40, 60), 0.5f, 1e-6f);
}

TEST(CloudFilter, BilateralKeepsPlanesAndInventsNoDepth) {
  const Intrinsics k = cloud::scenes::camera(160, 120);
  CloudConfig config;
  config.filter.median = false;
  config.filter.bilateral = true;
  config.segmentation.handRadiusM = 1.0f;
  config.segmentation.supportPlanes.enabled = false;  // the two planes stand for a hand
  CloudPipeline pipeline(k, config);
  CloudFrame out;
  ASSERT_TRUE(pipeline.process(stepEdgeFrame(), out).ok());
  EXPECT_NEAR(out.depthAt(30, 30), 0.5f, 1e-4f);  // flat stays flat
  EXPECT_NEAR(out.depthAt(78, 30), 0.5f, 1e-3f);  // the edge is preserved (range sigma 1 cm)
  EXPECT_EQ(out.depthAt(40, 60), 0.0f);           // no depth where there was none
}

}  // namespace
}  // namespace dynahand
