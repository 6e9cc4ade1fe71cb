// The SIMD layer's eight-lane types and the few operations the kernels need, once per level
// (simd.h): namespaces simd::scalar (plain C++, the reference), simd::sse2 (two 128-bit halves),
// simd::avx2 (one 256-bit register) and simd::avx512 (the same, compiled for AVX-512VL). Each
// level defines
//   FloatW  eight floats;   IntW  eight int32;   MaskW  eight booleans (a compare's result);
// with the same functions and the same results bit for bit: IEEE single-precision arithmetic
// lane by lane, int32 arithmetic wrapping modulo 2^32, x86's conversion rules (truncation of a
// float outside the int32 range or NaN gives INT32_MIN), x86's min and max, compares false on
// NaN.
//
// A kernel's source file includes this at the top; its kernels live in a kernel file that
// for_each_level.inl compiles once per level inside a namespace that sees that level's names,
// and simd.h's DYNAHAND_SIMD_DISPATCH calls the build for simd::level(). Intrinsics appear in
// the layer's files only (this one, lanes_x86_256.inl, simd.cpp).
#pragma once

#include <bit>
#include <cmath>
#include <cstdint>

#include "core/simd/simd.h"

#if DYNAHAND_SIMD_X86
#include <immintrin.h>
#endif

#define DYNAHAND_SIMD_INLINE inline __attribute__((always_inline))

namespace dynahand::simd {

inline constexpr int kLanes = 8;

// Row k: all ones in lane k, zeros elsewhere (laneMask).
alignas(32) inline constexpr std::int32_t kLaneMaskTable[kLanes][kLanes] = {
    {-1, 0, 0, 0, 0, 0, 0, 0}, {0, -1, 0, 0, 0, 0, 0, 0}, {0, 0, -1, 0, 0, 0, 0, 0},
    {0, 0, 0, -1, 0, 0, 0, 0}, {0, 0, 0, 0, -1, 0, 0, 0}, {0, 0, 0, 0, 0, -1, 0, 0},
    {0, 0, 0, 0, 0, 0, -1, 0}, {0, 0, 0, 0, 0, 0, 0, -1}};

// Folds a kernel's eight per-lane answers (value[k] and its index[k], each lane's own first
// best) into a running best, lane by lane: the largest value, the lowest index among equal
// values, so the answer is the one a scan one element at a time finds.
inline void foldLargestLane(const float (&value)[kLanes], const std::int32_t (&index)[kLanes],
                            float& best, std::int32_t& which) {
  for (int k = 0; k < kLanes; ++k) {
    if (value[k] > best || (value[k] == best && index[k] < which)) {
      best = value[k];
      which = index[k];
    }
  }
}
// foldLargestLane for the least value.
inline void foldLeastLane(const float (&value)[kLanes], const std::int32_t (&index)[kLanes],
                          float& best, std::int32_t& which) {
  for (int k = 0; k < kLanes; ++k) {
    if (value[k] < best || (value[k] == best && index[k] < which)) {
      best = value[k];
      which = index[k];
    }
  }
}

namespace scalar {

struct FloatW {
  float lane[kLanes];
};
struct IntW {
  std::int32_t lane[kLanes];
};
struct MaskW {
  unsigned bits;  // bit i: lane i
};

DYNAHAND_SIMD_INLINE FloatW splat(float x) {
  FloatW r;
  for (float& l : r.lane) l = x;
  return r;
}
DYNAHAND_SIMD_INLINE IntW splat(std::int32_t x) {
  IntW r;
  for (std::int32_t& l : r.lane) l = x;
  return r;
}
// 0, 1, ..., 7.
DYNAHAND_SIMD_INLINE IntW iota() {
  IntW r;
  for (int i = 0; i < kLanes; ++i) r.lane[i] = i;
  return r;
}
DYNAHAND_SIMD_INLINE FloatW load(const float* p) {
  FloatW r;
  for (int i = 0; i < kLanes; ++i) r.lane[i] = p[i];
  return r;
}
DYNAHAND_SIMD_INLINE IntW load(const std::int32_t* p) {
  IntW r;
  for (int i = 0; i < kLanes; ++i) r.lane[i] = p[i];
  return r;
}
DYNAHAND_SIMD_INLINE void store(float* p, FloatW a) {
  for (int i = 0; i < kLanes; ++i) p[i] = a.lane[i];
}
DYNAHAND_SIMD_INLINE void store(std::int32_t* p, IntW a) {
  for (int i = 0; i < kLanes; ++i) p[i] = a.lane[i];
}

#define DYNAHAND_SIMD_SCALAR_BINARY(Type, op, expr)       \
  DYNAHAND_SIMD_INLINE Type operator op(Type a, Type b) { \
    Type r;                                               \
    for (int i = 0; i < kLanes; ++i) r.lane[i] = expr;    \
    return r;                                             \
  }
DYNAHAND_SIMD_SCALAR_BINARY(FloatW, +, a.lane[i] + b.lane[i])
DYNAHAND_SIMD_SCALAR_BINARY(FloatW, -, a.lane[i] - b.lane[i])
DYNAHAND_SIMD_SCALAR_BINARY(FloatW, *, a.lane[i] * b.lane[i])
DYNAHAND_SIMD_SCALAR_BINARY(FloatW, /, a.lane[i] / b.lane[i])
// Wrapping, as the vector instructions do (no signed overflow).
DYNAHAND_SIMD_SCALAR_BINARY(IntW, +,
                            static_cast<std::int32_t>(static_cast<std::uint32_t>(a.lane[i]) +
                                                      static_cast<std::uint32_t>(b.lane[i])))
DYNAHAND_SIMD_SCALAR_BINARY(IntW, -,
                            static_cast<std::int32_t>(static_cast<std::uint32_t>(a.lane[i]) -
                                                      static_cast<std::uint32_t>(b.lane[i])))
#undef DYNAHAND_SIMD_SCALAR_BINARY

// The low 32 bits of each product.
DYNAHAND_SIMD_INLINE IntW mulLow(IntW a, IntW b) {
  IntW r;
  for (int i = 0; i < kLanes; ++i)
    r.lane[i] = static_cast<std::int32_t>(static_cast<std::uint32_t>(a.lane[i]) *
                                          static_cast<std::uint32_t>(b.lane[i]));
  return r;
}
DYNAHAND_SIMD_INLINE FloatW abs(FloatW a) {
  FloatW r;
  for (int i = 0; i < kLanes; ++i)
    r.lane[i] = std::bit_cast<float>(std::bit_cast<std::uint32_t>(a.lane[i]) & 0x7fffffffu);
  return r;
}
// x86's minimum and maximum: a < b ? a : b and a > b ? a : b (so b where either is NaN, and
// b of two zeros), not std::min's order.
DYNAHAND_SIMD_INLINE FloatW min(FloatW a, FloatW b) {
  FloatW r;
  for (int i = 0; i < kLanes; ++i) r.lane[i] = a.lane[i] < b.lane[i] ? a.lane[i] : b.lane[i];
  return r;
}
DYNAHAND_SIMD_INLINE FloatW max(FloatW a, FloatW b) {
  FloatW r;
  for (int i = 0; i < kLanes; ++i) r.lane[i] = a.lane[i] > b.lane[i] ? a.lane[i] : b.lane[i];
  return r;
}
// The correctly rounded square root (NaN below zero).
DYNAHAND_SIMD_INLINE FloatW sqrt(FloatW a) {
  FloatW r;
  for (int i = 0; i < kLanes; ++i) r.lane[i] = std::sqrt(a.lane[i]);
  return r;
}
DYNAHAND_SIMD_INLINE FloatW toFloat(IntW a) {
  FloatW r;
  for (int i = 0; i < kLanes; ++i) r.lane[i] = static_cast<float>(a.lane[i]);
  return r;
}
// Toward zero; INT32_MIN outside [-2^31, 2^31) and for NaN (x86's "integer indefinite").
DYNAHAND_SIMD_INLINE IntW truncate(FloatW a) {
  IntW r;
  for (int i = 0; i < kLanes; ++i) {
    const float x = a.lane[i];
    r.lane[i] = x >= -2147483648.0f && x < 2147483648.0f ? static_cast<std::int32_t>(x) : INT32_MIN;
  }
  return r;
}

#define DYNAHAND_SIMD_SCALAR_COMPARE(Type, op)                                                   \
  DYNAHAND_SIMD_INLINE MaskW operator op(Type a, Type b) {                                       \
    unsigned bits = 0;                                                                           \
    for (int i = 0; i < kLanes; ++i) bits |= static_cast<unsigned>(a.lane[i] op b.lane[i]) << i; \
    return {bits};                                                                               \
  }
DYNAHAND_SIMD_SCALAR_COMPARE(FloatW, <)
DYNAHAND_SIMD_SCALAR_COMPARE(FloatW, <=)
DYNAHAND_SIMD_SCALAR_COMPARE(FloatW, >)
DYNAHAND_SIMD_SCALAR_COMPARE(FloatW, >=)
DYNAHAND_SIMD_SCALAR_COMPARE(FloatW, ==)
DYNAHAND_SIMD_SCALAR_COMPARE(IntW, >)
#undef DYNAHAND_SIMD_SCALAR_COMPARE

DYNAHAND_SIMD_INLINE MaskW operator&(MaskW a, MaskW b) {
  return {a.bits & b.bits};
}
// Bit i set where lane i is true.
DYNAHAND_SIMD_INLINE unsigned bits(MaskW m) {
  return m.bits;
}
DYNAHAND_SIMD_INLINE bool all(MaskW m) {
  return m.bits == 0xffu;
}
// a where m, else b.
DYNAHAND_SIMD_INLINE IntW select(MaskW m, IntW a, IntW b) {
  IntW r;
  for (int i = 0; i < kLanes; ++i) r.lane[i] = ((m.bits >> i) & 1u) != 0 ? a.lane[i] : b.lane[i];
  return r;
}
DYNAHAND_SIMD_INLINE FloatW select(MaskW m, FloatW a, FloatW b) {
  FloatW r;
  for (int i = 0; i < kLanes; ++i) r.lane[i] = ((m.bits >> i) & 1u) != 0 ? a.lane[i] : b.lane[i];
  return r;
}
// True in lane k (0-7) alone.
DYNAHAND_SIMD_INLINE MaskW laneMask(int k) {
  return {1u << k};
}
DYNAHAND_SIMD_INLINE MaskW operator==(IntW a, IntW b) {
  unsigned bits = 0;
  for (int i = 0; i < kLanes; ++i) bits |= static_cast<unsigned>(a.lane[i] == b.lane[i]) << i;
  return {bits};
}
// r[k] = the eight lanes of row k -> r[f] = lane f of the eight rows (an 8 x 8 transpose).
DYNAHAND_SIMD_INLINE void transpose8(FloatW (&r)[kLanes]) {
  for (int i = 0; i < kLanes; ++i)
    for (int j = i + 1; j < kLanes; ++j) {
      const float t = r[i].lane[j];
      r[i].lane[j] = r[j].lane[i];
      r[j].lane[i] = t;
    }
}

}  // namespace scalar

#if DYNAHAND_SIMD_X86

namespace sse2 {

struct FloatW {
  __m128 lo, hi;
};
struct IntW {
  __m128i lo, hi;
};
struct MaskW {
  __m128i lo, hi;  // all ones in a true lane
};

DYNAHAND_SIMD_INLINE FloatW splat(float x) {
  return {_mm_set1_ps(x), _mm_set1_ps(x)};
}
DYNAHAND_SIMD_INLINE IntW splat(std::int32_t x) {
  return {_mm_set1_epi32(x), _mm_set1_epi32(x)};
}
DYNAHAND_SIMD_INLINE IntW iota() {
  return {_mm_setr_epi32(0, 1, 2, 3), _mm_setr_epi32(4, 5, 6, 7)};
}
DYNAHAND_SIMD_INLINE FloatW load(const float* p) {
  return {_mm_loadu_ps(p), _mm_loadu_ps(p + 4)};
}
DYNAHAND_SIMD_INLINE IntW load(const std::int32_t* p) {
  const auto* v = reinterpret_cast<const __m128i*>(p);
  return {_mm_loadu_si128(v), _mm_loadu_si128(v + 1)};
}
DYNAHAND_SIMD_INLINE void store(float* p, FloatW a) {
  _mm_storeu_ps(p, a.lo);
  _mm_storeu_ps(p + 4, a.hi);
}
DYNAHAND_SIMD_INLINE void store(std::int32_t* p, IntW a) {
  _mm_storeu_si128(reinterpret_cast<__m128i*>(p), a.lo);
  _mm_storeu_si128(reinterpret_cast<__m128i*>(p + 4), a.hi);
}
DYNAHAND_SIMD_INLINE FloatW operator+(FloatW a, FloatW b) {
  return {_mm_add_ps(a.lo, b.lo), _mm_add_ps(a.hi, b.hi)};
}
DYNAHAND_SIMD_INLINE FloatW operator-(FloatW a, FloatW b) {
  return {_mm_sub_ps(a.lo, b.lo), _mm_sub_ps(a.hi, b.hi)};
}
DYNAHAND_SIMD_INLINE FloatW operator*(FloatW a, FloatW b) {
  return {_mm_mul_ps(a.lo, b.lo), _mm_mul_ps(a.hi, b.hi)};
}
DYNAHAND_SIMD_INLINE FloatW operator/(FloatW a, FloatW b) {
  return {_mm_div_ps(a.lo, b.lo), _mm_div_ps(a.hi, b.hi)};
}
DYNAHAND_SIMD_INLINE IntW operator+(IntW a, IntW b) {
  return {_mm_add_epi32(a.lo, b.lo), _mm_add_epi32(a.hi, b.hi)};
}
DYNAHAND_SIMD_INLINE IntW operator-(IntW a, IntW b) {
  return {_mm_sub_epi32(a.lo, b.lo), _mm_sub_epi32(a.hi, b.hi)};
}
// SSE2 has no 32-bit low multiply: two 32x32 -> 64 products of the even and odd lanes.
DYNAHAND_SIMD_INLINE __m128i mulLow4(__m128i a, __m128i b) {
  const __m128i even = _mm_mul_epu32(a, b);
  const __m128i odd = _mm_mul_epu32(_mm_srli_si128(a, 4), _mm_srli_si128(b, 4));
  return _mm_unpacklo_epi32(_mm_shuffle_epi32(even, _MM_SHUFFLE(0, 0, 2, 0)),
                            _mm_shuffle_epi32(odd, _MM_SHUFFLE(0, 0, 2, 0)));
}
DYNAHAND_SIMD_INLINE IntW mulLow(IntW a, IntW b) {
  return {mulLow4(a.lo, b.lo), mulLow4(a.hi, b.hi)};
}
DYNAHAND_SIMD_INLINE FloatW abs(FloatW a) {
  const __m128 magnitude = _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff));
  return {_mm_and_ps(a.lo, magnitude), _mm_and_ps(a.hi, magnitude)};
}
DYNAHAND_SIMD_INLINE FloatW min(FloatW a, FloatW b) {
  return {_mm_min_ps(a.lo, b.lo), _mm_min_ps(a.hi, b.hi)};
}
DYNAHAND_SIMD_INLINE FloatW max(FloatW a, FloatW b) {
  return {_mm_max_ps(a.lo, b.lo), _mm_max_ps(a.hi, b.hi)};
}
DYNAHAND_SIMD_INLINE FloatW sqrt(FloatW a) {
  return {_mm_sqrt_ps(a.lo), _mm_sqrt_ps(a.hi)};
}
DYNAHAND_SIMD_INLINE FloatW toFloat(IntW a) {
  return {_mm_cvtepi32_ps(a.lo), _mm_cvtepi32_ps(a.hi)};
}
DYNAHAND_SIMD_INLINE IntW truncate(FloatW a) {
  return {_mm_cvttps_epi32(a.lo), _mm_cvttps_epi32(a.hi)};
}
DYNAHAND_SIMD_INLINE MaskW operator<(FloatW a, FloatW b) {
  return {_mm_castps_si128(_mm_cmplt_ps(a.lo, b.lo)), _mm_castps_si128(_mm_cmplt_ps(a.hi, b.hi))};
}
DYNAHAND_SIMD_INLINE MaskW operator<=(FloatW a, FloatW b) {
  return {_mm_castps_si128(_mm_cmple_ps(a.lo, b.lo)), _mm_castps_si128(_mm_cmple_ps(a.hi, b.hi))};
}
DYNAHAND_SIMD_INLINE MaskW operator>(FloatW a, FloatW b) {
  return {_mm_castps_si128(_mm_cmpgt_ps(a.lo, b.lo)), _mm_castps_si128(_mm_cmpgt_ps(a.hi, b.hi))};
}
DYNAHAND_SIMD_INLINE MaskW operator>=(FloatW a, FloatW b) {
  return {_mm_castps_si128(_mm_cmpge_ps(a.lo, b.lo)), _mm_castps_si128(_mm_cmpge_ps(a.hi, b.hi))};
}
DYNAHAND_SIMD_INLINE MaskW operator==(FloatW a, FloatW b) {
  return {_mm_castps_si128(_mm_cmpeq_ps(a.lo, b.lo)), _mm_castps_si128(_mm_cmpeq_ps(a.hi, b.hi))};
}
DYNAHAND_SIMD_INLINE MaskW operator>(IntW a, IntW b) {
  return {_mm_cmpgt_epi32(a.lo, b.lo), _mm_cmpgt_epi32(a.hi, b.hi)};
}
DYNAHAND_SIMD_INLINE MaskW operator&(MaskW a, MaskW b) {
  return {_mm_and_si128(a.lo, b.lo), _mm_and_si128(a.hi, b.hi)};
}
DYNAHAND_SIMD_INLINE unsigned bits(MaskW m) {
  return static_cast<unsigned>(_mm_movemask_ps(_mm_castsi128_ps(m.lo))) |
         static_cast<unsigned>(_mm_movemask_ps(_mm_castsi128_ps(m.hi))) << 4;
}
DYNAHAND_SIMD_INLINE bool all(MaskW m) {
  return bits(m) == 0xffu;
}
DYNAHAND_SIMD_INLINE IntW select(MaskW m, IntW a, IntW b) {
  return {_mm_or_si128(_mm_and_si128(m.lo, a.lo), _mm_andnot_si128(m.lo, b.lo)),
          _mm_or_si128(_mm_and_si128(m.hi, a.hi), _mm_andnot_si128(m.hi, b.hi))};
}
DYNAHAND_SIMD_INLINE FloatW select(MaskW m, FloatW a, FloatW b) {
  const __m128 lo = _mm_castsi128_ps(m.lo), hi = _mm_castsi128_ps(m.hi);
  return {_mm_or_ps(_mm_and_ps(lo, a.lo), _mm_andnot_ps(lo, b.lo)),
          _mm_or_ps(_mm_and_ps(hi, a.hi), _mm_andnot_ps(hi, b.hi))};
}
DYNAHAND_SIMD_INLINE MaskW laneMask(int k) {
  const auto* row = reinterpret_cast<const __m128i*>(kLaneMaskTable[k]);
  return {_mm_load_si128(row), _mm_load_si128(row + 1)};
}
DYNAHAND_SIMD_INLINE MaskW operator==(IntW a, IntW b) {
  return {_mm_cmpeq_epi32(a.lo, b.lo), _mm_cmpeq_epi32(a.hi, b.hi)};
}
// Four 4 x 4 transposes: the quarters of the 8 x 8 block, the off-diagonal ones swapped.
DYNAHAND_SIMD_INLINE void transpose8(FloatW (&r)[kLanes]) {
  __m128 a0 = r[0].lo, a1 = r[1].lo, a2 = r[2].lo, a3 = r[3].lo;  // rows 0-3, lanes 0-3
  __m128 b0 = r[4].lo, b1 = r[5].lo, b2 = r[6].lo, b3 = r[7].lo;  // rows 4-7, lanes 0-3
  __m128 c0 = r[0].hi, c1 = r[1].hi, c2 = r[2].hi, c3 = r[3].hi;  // rows 0-3, lanes 4-7
  __m128 d0 = r[4].hi, d1 = r[5].hi, d2 = r[6].hi, d3 = r[7].hi;  // rows 4-7, lanes 4-7
  _MM_TRANSPOSE4_PS(a0, a1, a2, a3);
  _MM_TRANSPOSE4_PS(b0, b1, b2, b3);
  _MM_TRANSPOSE4_PS(c0, c1, c2, c3);
  _MM_TRANSPOSE4_PS(d0, d1, d2, d3);
  r[0] = {a0, b0}, r[1] = {a1, b1}, r[2] = {a2, b2}, r[3] = {a3, b3};
  r[4] = {c0, d0}, r[5] = {c1, d1}, r[6] = {c2, d2}, r[7] = {c3, d3};
}

}  // namespace sse2

DYNAHAND_SIMD_BEGIN_AVX2
#define DYNAHAND_SIMD_MASK_REGISTERS 0
namespace avx2 {
#include "core/simd/lanes_x86_256.inl"
}  // namespace avx2
#undef DYNAHAND_SIMD_MASK_REGISTERS
DYNAHAND_SIMD_END

// The same 256-bit lanes compiled for AVX-512VL: the compiler has 32 vector registers (loops
// that keep many values in registers spill less), compares write mask registers, and the
// arithmetic is the same instructions, so the same bits.
DYNAHAND_SIMD_BEGIN_AVX512
#define DYNAHAND_SIMD_MASK_REGISTERS 1
namespace avx512 {
#include "core/simd/lanes_x86_256.inl"
}  // namespace avx512
#undef DYNAHAND_SIMD_MASK_REGISTERS
DYNAHAND_SIMD_END

#endif  // DYNAHAND_SIMD_X86

}  // namespace dynahand::simd
