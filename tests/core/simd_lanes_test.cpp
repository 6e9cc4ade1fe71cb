// The SIMD layer on its own (core/simd): every operation of lanes.h on every level the CPU has
// gives the scalar level's bits, on random values and on the edge cases the kernels rely on
// (halves, signed zeros, infinities, NaN, floats outside the int32 range, int32 overflow).
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <random>
#include <string_view>

#include "core/simd/lanes.h"
#include "core/simd/simd.h"

namespace dynahand {
namespace {

#define DYNAHAND_SIMD_KERNELS "core/lanes_ops.inl"
#include "core/simd/for_each_level.inl"

constexpr const char* kOpNames[] = {"a + b",
                                    "a - b",
                                    "a * b",
                                    "a / b",
                                    "abs(a)",
                                    "min(a, b)",
                                    "max(a, b)",
                                    "sqrt(abs(a))",
                                    "toFloat(i)",
                                    "truncate(a)",
                                    "i + j",
                                    "i - j",
                                    "mulLow(i, j)",
                                    "a < b",
                                    "a <= b",
                                    "a > b",
                                    "a >= b",
                                    "a == b",
                                    "i > j",
                                    "(a < b) & (i > j)",
                                    "select(a < b, i, j)",
                                    "select(a > b, a, b)",
                                    "iota()",
                                    "splat(a[3])",
                                    "all(a <= a)",
                                    "i == j",
                                    "i == i",
                                    "laneMask(i[0] & 7)"};
constexpr int kOps = static_cast<int>(std::size(kOpNames));
int opIndex(std::string_view name) {
  for (int op = 0; op < kOps; ++op)
    if (name == kOpNames[op]) return op;
  ADD_FAILURE() << "no operation " << name;
  return 0;
}

struct Results {
  std::uint32_t lanes[kOps][8];
};

Results run(simd::Level level, const float* a, const float* b, const std::int32_t* i,
            const std::int32_t* j) {
  Results r{};
  EXPECT_EQ(simd::forceLevel(level), level);
  DYNAHAND_SIMD_DISPATCH(applyOps, a, b, i, j, r.lanes);
  return r;
}

// Compares every level with the scalar one on eight lanes of input.
void compareLevels(const float* a, const float* b, const std::int32_t* i, const std::int32_t* j) {
  const Results reference = run(simd::Level::Scalar, a, b, i, j);
  for (int l = 1; l <= static_cast<int>(simd::bestLevel()); ++l) {
    const auto level = static_cast<simd::Level>(l);
    const Results wide = run(level, a, b, i, j);
    for (int op = 0; op < kOps; ++op)
      for (int lane = 0; lane < 8; ++lane)
        ASSERT_EQ(wide.lanes[op][lane], reference.lanes[op][lane])
            << simd::levelName(level) << ": " << kOpNames[op] << ", lane " << lane << ", a "
            << a[lane] << ", b " << b[lane] << ", i " << i[lane] << ", j " << j[lane];
  }
  simd::forceLevel(simd::bestLevel());
}

TEST(SimdLanes, EveryLevelGivesTheScalarBitsOnRandomValues) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> value(-3000.0f, 3000.0f);
  for (int trial = 0; trial < 2000; ++trial) {
    float a[8], b[8];
    std::int32_t i[8], j[8];
    for (int lane = 0; lane < 8; ++lane) {
      a[lane] = value(rng);
      b[lane] = trial % 4 == 0 ? a[lane] : value(rng);  // equal lanes for the compares
      i[lane] = static_cast<std::int32_t>(rng());
      j[lane] = trial % 3 == 0 ? static_cast<std::int32_t>(rng() % 2000) - 1000
                               : static_cast<std::int32_t>(rng());
    }
    compareLevels(a, b, i, j);
  }
  std::printf("levels compared with the scalar one: %d (best: %s)\n",
              static_cast<int>(simd::bestLevel()), simd::levelName(simd::bestLevel()));
}

TEST(SimdLanes, EveryLevelGivesTheScalarBitsOnEdgeCases) {
  const float inf = std::numeric_limits<float>::infinity();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float edges[] = {0.5f,          -0.5f,         1.5f,           -1.5f,          0.0f, -0.0f,
                         2147483520.0f, 2147483648.0f, -2147483648.0f, -2147483904.0f, inf,  -inf,
                         nan,           1e-40f,        -1e-40f,        4194303.5f};
  const std::int32_t ints[] = {0, 1, -1, INT32_MAX, INT32_MIN, 65536, -65536, 46341};
  constexpr int kEdges = static_cast<int>(std::size(edges));
  for (int s = 0; s < kEdges; ++s) {
    float a[8], b[8];
    std::int32_t i[8], j[8];
    for (int lane = 0; lane < 8; ++lane) {
      a[lane] = edges[(s + lane) % kEdges];
      b[lane] = edges[(s + 3 * lane + 1) % kEdges];
      i[lane] = ints[(s + lane) % 8];
      j[lane] = ints[(s + 5 * lane + 2) % 8];
    }
    compareLevels(a, b, i, j);
  }
}

// The scalar level follows x86's rules where C++ leaves them open.
TEST(SimdLanes, TheScalarLevelFollowsTheX86Rules) {
  const float a[8] = {2147483648.0f, -2147483904.0f, std::numeric_limits<float>::quiet_NaN(),
                      -2.7f,         2.7f,           -0.0f,
                      1e9f,          -1e9f};
  const float b[8] = {};
  const std::int32_t i[8] = {INT32_MAX, INT32_MIN, 65536, 3, -3, 0, 7, -7};
  const std::int32_t j[8] = {1, 1, 65536, -4, 4, 0, 7, 7};
  const Results r = run(simd::Level::Scalar, a, b, i, j);
  simd::forceLevel(simd::bestLevel());
  const int truncateOp = opIndex("truncate(a)"), addOp = opIndex("i + j"), subOp = opIndex("i - j"),
            mulOp = opIndex("mulLow(i, j)");
  const auto asInt = [](std::uint32_t x) { return static_cast<std::int32_t>(x); };
  EXPECT_EQ(asInt(r.lanes[truncateOp][0]), INT32_MIN);  // out of range
  EXPECT_EQ(asInt(r.lanes[truncateOp][1]), INT32_MIN);
  EXPECT_EQ(asInt(r.lanes[truncateOp][2]), INT32_MIN);  // NaN
  EXPECT_EQ(asInt(r.lanes[truncateOp][3]), -2);         // toward zero
  EXPECT_EQ(asInt(r.lanes[truncateOp][4]), 2);
  EXPECT_EQ(asInt(r.lanes[addOp][0]), INT32_MIN);  // wraps
  EXPECT_EQ(asInt(r.lanes[subOp][1]), INT32_MAX);
  EXPECT_EQ(asInt(r.lanes[mulOp][2]), 0);  // 2^32: the low 32 bits
  EXPECT_EQ(asInt(r.lanes[mulOp][3]), -12);
  const int minOp = opIndex("min(a, b)"),
            maxOp = opIndex("max(a, b)");  // x86's order: b where a is NaN, b of two zeros
  EXPECT_FALSE(std::isnan(std::bit_cast<float>(r.lanes[minOp][2])));
  EXPECT_EQ(r.lanes[minOp][5], std::bit_cast<std::uint32_t>(0.0f));  // min(-0, +0) = +0
  EXPECT_EQ(r.lanes[maxOp][5], std::bit_cast<std::uint32_t>(0.0f));
}

TEST(SimdLanes, Transpose8SwapsRowsAndLanesOnEveryLevel) {
  float rows[8][8];
  for (int k = 0; k < 8; ++k)
    for (int f = 0; f < 8; ++f) rows[k][f] = static_cast<float>(10 * k + f);
  for (int l = 0; l <= static_cast<int>(simd::bestLevel()); ++l) {
    const auto level = static_cast<simd::Level>(l);
    ASSERT_EQ(simd::forceLevel(level), level);
    float out[8][8] = {};
    DYNAHAND_SIMD_DISPATCH(transposeRows, rows, out);
    for (int k = 0; k < 8; ++k)
      for (int f = 0; f < 8; ++f)
        ASSERT_EQ(out[f][k], rows[k][f]) << simd::levelName(level) << " row " << k << " lane " << f;
  }
  simd::forceLevel(simd::bestLevel());
}

TEST(SimdLanes, ForcingALevelTheCpuLacksGivesTheBestOne) {
  EXPECT_EQ(simd::forceLevel(simd::Level::Scalar), simd::Level::Scalar);
  EXPECT_EQ(simd::level(), simd::Level::Scalar);
  EXPECT_EQ(simd::forceLevel(simd::Level::Avx2),
            static_cast<int>(simd::bestLevel()) >= static_cast<int>(simd::Level::Avx2)
                ? simd::Level::Avx2
                : simd::bestLevel());
  EXPECT_EQ(simd::forceLevel(simd::Level::Avx512), simd::bestLevel());  // the widest level
  simd::forceLevel(simd::bestLevel());
  EXPECT_EQ(simd::level(), simd::bestLevel());
}

}  // namespace
}  // namespace dynahand
