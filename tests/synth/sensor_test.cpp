// Sensor profiles against their documented parameters: noise std near 0.5 m, dropout
// fraction and minimum range (each within 10%), the kind-specific artefacts, and
// reproducibility (same seed, same bytes).
#include <gtest/gtest.h>

#include <cmath>

#include "dynahand/synth_sensor.h"

namespace dynahand::synth {
namespace {

const SensorProfile& profileNamed(const char* name) {
  static std::vector<SensorProfile> profiles = sensorProfiles();
  for (const SensorProfile& p : profiles)
    if (p.name == name) return p;
  ADD_FAILURE() << "no profile " << name;
  return profiles.front();
}

// A wall whose depth at the image centre is `centreDepth`, slightly tilted so that
// quantisation errors are spread over their whole step.
Plane tiltedWall(float centreDepth) {
  Plane wall;
  wall.normal = Vec3(0.02f, 0.013f, 1.0f).normalized();
  wall.offset = centreDepth * wall.normal.z();
  return wall;
}

struct WallStats {
  double noiseStd = 0.0;         // of reported minus true depth, outliers excluded, m
  double expectedStd = 0.0;      // RMS of the profile's expectedNoiseStd over those pixels, m
  double dropout = 0.0;          // fraction of pixels reading 0 (left band excluded)
  double outlierFraction = 0.0;  // fraction of valid pixels beyond 6 expected std
};

WallStats measureWall(const SensorProfile& profile, float centreDepth, int frames,
                      std::uint64_t seed = 7) {
  DepthRenderer renderer(profile.intrinsics);
  const Plane wall = tiltedWall(centreDepth);
  renderer.setBackground(std::span(&wall, 1), {});
  SensorSimulator sensor(profile, seed);
  DepthFrame frame;
  double sumSq = 0.0, expectedSq = 0.0;
  long inliers = 0, zeros = 0, considered = 0, outliers = 0, valid = 0;
  const int w = profile.intrinsics.width;
  for (int f = 0; f < frames; ++f) {
    sensor.apply(renderer.depth(), renderer.labels(), f, f / 30.0, frame);
    for (std::size_t i = 0; i < frame.depth.size(); ++i) {
      const float truth = renderer.depth()[i];
      const int u = static_cast<int>(i % static_cast<std::size_t>(w));
      // The stereo left band (u < disparity) is a separate, deterministic effect.
      if (profile.leftInvalidBand && u < profile.intrinsics.fx * profile.baseline / truth + 2.0f)
        continue;
      ++considered;
      if (frame.depth[i] == 0) {
        ++zeros;
        continue;
      }
      ++valid;
      const double residual =
          frame.depth[i] * static_cast<double>(profile.depthScale) - static_cast<double>(truth);
      const double sigma = static_cast<double>(profile.expectedNoiseStd(truth));
      if (std::fabs(residual) > 6.0 * sigma) {
        ++outliers;
        continue;
      }
      sumSq += residual * residual;
      expectedSq += sigma * sigma;
      ++inliers;
    }
  }
  WallStats stats;
  stats.noiseStd = std::sqrt(sumSq / static_cast<double>(inliers));
  stats.expectedStd = std::sqrt(expectedSq / static_cast<double>(inliers));
  stats.dropout = static_cast<double>(zeros) / static_cast<double>(considered);
  stats.outlierFraction = static_cast<double>(outliers) / static_cast<double>(valid);
  return stats;
}

// The wall at 0.5 m; structured light's minimum range is 0.5 m, so its wall sits just beyond.
float noiseWallDepth(const SensorProfile& p) {
  return std::max(0.5f, p.minRange + 0.012f);
}

TEST(SensorProfiles, EveryProfileHasADeviceAndValidCamera) {
  ASSERT_EQ(sensorProfiles().size(), 4u);
  for (const SensorProfile& p : sensorProfiles()) {
    EXPECT_FALSE(p.device.empty()) << p.name;
    EXPECT_GT(p.intrinsics.width, 0);
    EXPECT_GT(p.maxRange, p.minRange);
    EXPECT_TRUE(findSensorProfile(p.name).ok());
  }
  EXPECT_EQ(profileNamed("tof").intrinsics.width, 320);
  EXPECT_EQ(profileNamed("structured-light").intrinsics.width, 640);
  EXPECT_FLOAT_EQ(profileNamed("tof").minRange, 0.20f);
}

TEST(SensorProfiles, UnknownNameIsAnErrorListingTheNames) {
  const Result<SensorProfile> p = findSensorProfile("kinect9");
  ASSERT_FALSE(p.ok());
  EXPECT_NE(p.message().find("kinect9"), std::string::npos);
  EXPECT_NE(p.message().find("active-stereo"), std::string::npos);
}

TEST(SensorProfiles, DocumentedNoiseAtHalfMetre) {
  // The numbers docs/synth.md states (noise before quantisation, m).
  EXPECT_FLOAT_EQ(profileNamed("tof").noiseAtHalfMetre, 0.0030f);
  EXPECT_FLOAT_EQ(profileNamed("structured-light").noiseAtHalfMetre, 0.0010f);
  EXPECT_FLOAT_EQ(profileNamed("active-stereo").noiseAtHalfMetre, 0.0010f);
  EXPECT_NEAR(profileNamed("ideal").expectedNoiseStd(0.5f), 0.0001f / std::sqrt(12.0f), 1e-7f);
}

class ProfileStatistics : public ::testing::TestWithParam<const char*> {};

TEST_P(ProfileStatistics, NoiseStdAtHalfMetreWithinTenPercent) {
  const SensorProfile& p = profileNamed(GetParam());
  const WallStats s = measureWall(p, noiseWallDepth(p), 2);
  EXPECT_NEAR(s.noiseStd / s.expectedStd, 1.0, 0.10)
      << p.name << ": measured " << s.noiseStd << " m, documented " << s.expectedStd << " m";
}

TEST_P(ProfileStatistics, DropoutFractionWithinTenPercent) {
  const SensorProfile& p = profileNamed(GetParam());
  const WallStats s = measureWall(p, noiseWallDepth(p), 8);
  const double expected = static_cast<double>(p.expectedWallDropout());
  if (expected == 0.0)
    EXPECT_EQ(s.dropout, 0.0) << p.name;
  else
    EXPECT_NEAR(s.dropout / expected, 1.0, 0.10)
        << p.name << ": measured " << s.dropout << ", documented " << expected;
}

TEST_P(ProfileStatistics, MinimumRangeWithinTenPercent) {
  const SensorProfile& p = profileNamed(GetParam());
  // The nearest wall distance at which most of the wall is seen, bisected to 1 mm.
  auto seen = [&](float z) { return 1.0 - measureWall(p, z, 1).dropout > 0.5; };
  float lo = 0.5f * p.minRange, hi = 2.0f * p.minRange;
  ASSERT_FALSE(seen(lo));
  ASSERT_TRUE(seen(hi));
  while (hi - lo > 0.001f) {
    const float mid = 0.5f * (lo + hi);
    (seen(mid) ? hi : lo) = mid;
  }
  const float found = hi;
  EXPECT_NEAR(found / p.minRange, 1.0f, 0.10f) << p.name << ": found " << found << " m";
  EXPECT_EQ(measureWall(p, 0.85f * p.minRange, 1).dropout, 1.0) << p.name;
}

INSTANTIATE_TEST_SUITE_P(AllProfiles, ProfileStatistics,
                         ::testing::Values("ideal", "tof", "structured-light", "active-stereo"));

TEST(SensorProfiles, ActiveStereoSpeckleFractionWithinTenPercent) {
  const SensorProfile& p = profileNamed("active-stereo");
  const WallStats s = measureWall(p, 0.5f, 8);
  // Speckle offsets are 2-8 cm, all beyond 6 sigma at 0.5 m; Gaussian noise never is.
  EXPECT_NEAR(s.outlierFraction / static_cast<double>(p.speckleFraction), 1.0, 0.10)
      << s.outlierFraction;
}

// A ball in front of a wall, through the given profile; returns {ideal, degraded}.
struct BallScene {
  DepthRenderer renderer;
  explicit BallScene(const SensorProfile& p, float ballRadius = 0.05f, float wallDepth = 0.9f)
      : renderer(p.intrinsics) {
    const Plane wall{Vec3::UnitZ(), wallDepth};
    renderer.setBackground(std::span(&wall, 1), {});
    const RoundCone ball{{0.0f, 0.0f, 0.6f}, {0.0f, 0.0f, 0.6f}, ballRadius, ballRadius};
    renderer.draw(std::span(&ball, 1), PixelLabel::Hand0);
  }
};

TEST(SensorArtefacts, TimeOfFlightHasFlyingPixelsBetweenBallAndWall) {
  const SensorProfile& p = profileNamed("tof");
  BallScene scene(p);
  SensorSimulator sensor(p, 3);
  DepthFrame frame;
  sensor.apply(scene.renderer.depth(), scene.renderer.labels(), 0, 0.0, frame);
  int flying = 0;
  for (const std::uint16_t d : frame.depth)
    flying += d > 700 && d < 850;  // between 0.65 and 0.9 m minus noise
  EXPECT_GT(flying, 20);
  SensorSimulator ideal(profileNamed("ideal"), 3);
  ideal.apply(scene.renderer.depth(), scene.renderer.labels(), 0, 0.0, frame);
  int idealFlying = 0;
  for (const std::uint16_t d : frame.depth) idealFlying += d > 7000 && d < 8500;  // 0.1 mm units
  EXPECT_EQ(idealFlying, 0);
}

TEST(SensorArtefacts, StructuredLightShadowsTheLeftSideOfNearObjectsOnly) {
  const SensorProfile& p = profileNamed("structured-light");
  BallScene scene(p);
  SensorProfile noRandom = p;
  noRandom.dropoutFraction = 0.0f;
  SensorSimulator sensor(noRandom, 3);
  DepthFrame frame;
  sensor.apply(scene.renderer.depth(), scene.renderer.labels(), 0, 0.0, frame);
  // Along the centre row: ball spans u = cx +- fx r / sqrt(z^2 - r^2).
  const int row = 240;
  int leftHoles = 0, rightHoles = 0;
  for (int u = 0; u < 640; ++u) {
    if (frame.at(u, row) != 0) continue;
    (u < 320 ? leftHoles : rightHoles)++;
  }
  // Shadow width = fx b (1/z_ball_edge - 1/z_wall) ~ 570 * 0.075 * (1/0.6 - 1/0.9) = 23.7 px.
  EXPECT_NEAR(leftHoles, 24, 4);
  EXPECT_LE(rightHoles, 2);
}

TEST(SensorArtefacts, StructuredLightDropsThinFeaturesButKeepsThickOnes) {
  const SensorProfile& p = profileNamed("structured-light");
  for (const float radius : {0.0025f, 0.02f}) {
    DepthRenderer renderer(p.intrinsics);
    const Plane wall{Vec3::UnitZ(), 0.9f};
    renderer.setBackground(std::span(&wall, 1), {});
    const RoundCone rod{{0.0f, -0.1f, 0.6f}, {0.0f, 0.1f, 0.6f}, radius, radius};
    renderer.draw(std::span(&rod, 1), PixelLabel::Hand0);
    SensorSimulator sensor(p, 5);
    DepthFrame frame;
    sensor.apply(renderer.depth(), renderer.labels(), 0, 0.0, frame);
    int rodPixels = 0, rodSeen = 0;
    for (std::size_t i = 0; i < frame.depth.size(); ++i) {
      if (renderer.labels()[i] != PixelLabel::Hand0) continue;
      ++rodPixels;
      rodSeen += frame.depth[i] != 0;
    }
    const double seen = static_cast<double>(rodSeen) / rodPixels;
    if (radius < 0.01f)
      EXPECT_LT(seen, 0.2) << "a 5 mm rod at 0.6 m is 4.8 px wide";
    else
      EXPECT_GT(seen, 0.85) << "a 4 cm rod at 0.6 m is 38 px wide";
  }
}

TEST(SensorArtefacts, ActiveStereoFattensForegroundAlongRows) {
  const SensorProfile& p = profileNamed("active-stereo");
  BallScene scene(p);
  SensorProfile clean = p;
  clean.dropoutFraction = clean.holeFraction = clean.speckleFraction = clean.noiseAtHalfMetre =
      0.0f;
  SensorSimulator sensor(clean, 1);
  DepthFrame frame;
  sensor.apply(scene.renderer.depth(), scene.renderer.labels(), 0, 0.0, frame);
  int renderedNear = 0, reportedNear = 0;
  for (int u = 0; u < 640; ++u) {
    renderedNear += scene.renderer.depth()[240 * 640 + static_cast<std::size_t>(u)] < 0.8f;
    reportedNear += frame.at(u, 240) != 0 && frame.at(u, 240) < 800;
  }
  EXPECT_EQ(reportedNear, renderedNear + 2 * p.edgeFatteningPx);
}

TEST(SensorReproducibility, SameSeedSameBytesAnyOrder) {
  const SensorProfile& p = profileNamed("active-stereo");
  BallScene scene(p);
  DepthFrame a, b, c;
  SensorSimulator first(p, 42), second(p, 42), other(p, 43);
  for (int f = 0; f < 3; ++f)
    first.apply(scene.renderer.depth(), scene.renderer.labels(), f, 0.0, a);
  second.apply(scene.renderer.depth(), scene.renderer.labels(), 2, 0.0, b);  // frame 2 alone
  EXPECT_EQ(a.depth, b.depth);
  other.apply(scene.renderer.depth(), scene.renderer.labels(), 2, 0.0, c);
  EXPECT_NE(a.depth, c.depth);
  second.apply(scene.renderer.depth(), scene.renderer.labels(), 1, 0.0, b);
  EXPECT_NE(a.depth, b.depth);  // frames differ from each other
}

}  // namespace
}  // namespace dynahand::synth
