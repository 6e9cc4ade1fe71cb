#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>

#include "dynahand/core.h"

namespace dynahand {
namespace {

Pose somePose() {
  return {Vec3(0.1f, -0.2f, 0.5f), Quat(Eigen::AngleAxisf(0.7f, Vec3(1, 2, 3).normalized()))};
}

TEST(Pose, ComposeMatchesSequentialTransform) {
  const Pose a = somePose();
  const Pose b{Vec3(0.01f, 0.02f, 0.03f), Quat(Eigen::AngleAxisf(-0.3f, Vec3::UnitX()))};
  const Vec3 x(0.3f, 0.1f, -0.4f);
  EXPECT_LT(((a * b).transform(x) - a.transform(b.transform(x))).norm(), 1e-6f);
}

TEST(Pose, RotateVectorIsEigensRotationBitForBit) {
  // rotateVector is Eigen's q * v written out so that it inlines: the tracker's results
  // depend on it giving the same bits, for any quaternion and vector.
  std::uint32_t state = 12345u;
  auto next = [&state] {
    state = state * 1664525u + 1013904223u;
    return static_cast<float>(state >> 8) / static_cast<float>(1u << 24) * 2.0f - 1.0f;
  };
  for (int i = 0; i < 10000; ++i) {
    const Quat q = Quat(next(), next(), next(), next()).normalized();
    const Vec3 v(next(), next(), next() * 0.3f);
    const Vec3 eigen = q * v, ours = rotateVector(q, v);
    const Vec3 eigenInverse = q.conjugate() * v, oursInverse = inverseRotateVector(q, v);
    for (int k = 0; k < 3; ++k) {
      ASSERT_EQ(std::bit_cast<std::uint32_t>(eigen[k]), std::bit_cast<std::uint32_t>(ours[k]))
          << "sample " << i << " component " << k;
      ASSERT_EQ(std::bit_cast<std::uint32_t>(eigenInverse[k]),
                std::bit_cast<std::uint32_t>(oursInverse[k]))
          << "sample " << i << " component " << k;
    }
  }
}

TEST(Pose, InverseUndoesTransform) {
  const Pose a = somePose();
  const Vec3 x(0.3f, 0.1f, -0.4f);
  EXPECT_LT((a.inverse().transform(a.transform(x)) - x).norm(), 1e-6f);
  EXPECT_LT((a.inverseTransform(a.transform(x)) - x).norm(), 1e-6f);
  EXPECT_LT((a.toIsometry() * x - a.transform(x)).norm(), 1e-6f);
}

TEST(Pose, InterpolateEndsAndMidpoint) {
  const Pose a = Pose::identity();
  const Pose b{Vec3(1, 0, 0), Quat(Eigen::AngleAxisf(1.0f, Vec3::UnitZ()))};
  EXPECT_LT((interpolate(a, b, 0).p - a.p).norm(), 1e-7f);
  EXPECT_LT(interpolate(a, b, 1).q.angularDistance(b.q), 1e-5f);
  const Pose mid = interpolate(a, b, 0.5f);
  EXPECT_NEAR(mid.p.x(), 0.5f, 1e-6f);
  EXPECT_NEAR(mid.q.angularDistance(a.q), 0.5f, 1e-5f);
}

TEST(Result, CarriesValueOrError) {
  Result<int> good = 3;
  ASSERT_TRUE(good.ok());
  EXPECT_EQ(*good, 3);
  Result<int> bad = Error{"camera.json: missing fx"};
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.message(), "camera.json: missing fx");
}

TEST(Fnv1a, KnownVectorAndSensitivity) {
  Fnv1a empty;
  EXPECT_EQ(empty.value(), 14695981039346656037ull);
  Fnv1a a;
  a.add("a", 1);
  EXPECT_EQ(a.value(), 0xaf63dc4c8601ec8cull);  // published FNV-1a 64 test vector for "a"
  Fnv1a p, q;
  p.add(1.0f);
  q.add(std::nextafter(1.0f, 2.0f));
  EXPECT_NE(p.value(), q.value());
}

}  // namespace
}  // namespace dynahand
