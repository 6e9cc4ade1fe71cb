// The 256-bit lanes of lanes.h (FloatW, IntW, MaskW in one register each), included once for
// AVX2 (namespace simd::avx2) and once for AVX-512VL (simd::avx512, with
// DYNAHAND_SIMD_MASK_REGISTERS: MaskW in a mask register), inside lanes.h's target regions. No
// include guard, no includes.

struct FloatW {
  __m256 v;
};
struct IntW {
  __m256i v;
};
#if DYNAHAND_SIMD_MASK_REGISTERS
struct MaskW {
  __mmask8 k;  // bit i: lane i (an AVX-512 mask register)
};
#else
struct MaskW {
  __m256i v;  // all ones in a true lane
};
#endif

DYNAHAND_SIMD_INLINE FloatW splat(float x) {
  return {_mm256_set1_ps(x)};
}
DYNAHAND_SIMD_INLINE IntW splat(std::int32_t x) {
  return {_mm256_set1_epi32(x)};
}
DYNAHAND_SIMD_INLINE IntW iota() {
  return {_mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7)};
}
DYNAHAND_SIMD_INLINE FloatW load(const float* p) {
  return {_mm256_loadu_ps(p)};
}
DYNAHAND_SIMD_INLINE IntW load(const std::int32_t* p) {
  return {_mm256_loadu_si256(reinterpret_cast<const __m256i*>(p))};
}
DYNAHAND_SIMD_INLINE void store(float* p, FloatW a) {
  _mm256_storeu_ps(p, a.v);
}
DYNAHAND_SIMD_INLINE void store(std::int32_t* p, IntW a) {
  _mm256_storeu_si256(reinterpret_cast<__m256i*>(p), a.v);
}
DYNAHAND_SIMD_INLINE FloatW operator+(FloatW a, FloatW b) {
  return {_mm256_add_ps(a.v, b.v)};
}
DYNAHAND_SIMD_INLINE FloatW operator-(FloatW a, FloatW b) {
  return {_mm256_sub_ps(a.v, b.v)};
}
DYNAHAND_SIMD_INLINE FloatW operator*(FloatW a, FloatW b) {
  return {_mm256_mul_ps(a.v, b.v)};
}
DYNAHAND_SIMD_INLINE FloatW operator/(FloatW a, FloatW b) {
  return {_mm256_div_ps(a.v, b.v)};
}
DYNAHAND_SIMD_INLINE IntW operator+(IntW a, IntW b) {
  return {_mm256_add_epi32(a.v, b.v)};
}
DYNAHAND_SIMD_INLINE IntW operator-(IntW a, IntW b) {
  return {_mm256_sub_epi32(a.v, b.v)};
}
DYNAHAND_SIMD_INLINE IntW mulLow(IntW a, IntW b) {
  return {_mm256_mullo_epi32(a.v, b.v)};
}
DYNAHAND_SIMD_INLINE FloatW abs(FloatW a) {
  return {_mm256_and_ps(a.v, _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff)))};
}
DYNAHAND_SIMD_INLINE FloatW min(FloatW a, FloatW b) {
  return {_mm256_min_ps(a.v, b.v)};
}
DYNAHAND_SIMD_INLINE FloatW max(FloatW a, FloatW b) {
  return {_mm256_max_ps(a.v, b.v)};
}
DYNAHAND_SIMD_INLINE FloatW sqrt(FloatW a) {
  return {_mm256_sqrt_ps(a.v)};
}
DYNAHAND_SIMD_INLINE FloatW toFloat(IntW a) {
  return {_mm256_cvtepi32_ps(a.v)};
}
DYNAHAND_SIMD_INLINE IntW truncate(FloatW a) {
  return {_mm256_cvttps_epi32(a.v)};
}
#if DYNAHAND_SIMD_MASK_REGISTERS
// Compares write a mask register and selects blend through it: one instruction less per
// select than a vector mask (the same bits).
DYNAHAND_SIMD_INLINE MaskW operator<(FloatW a, FloatW b) {
  return {_mm256_cmp_ps_mask(a.v, b.v, _CMP_LT_OQ)};
}
DYNAHAND_SIMD_INLINE MaskW operator<=(FloatW a, FloatW b) {
  return {_mm256_cmp_ps_mask(a.v, b.v, _CMP_LE_OQ)};
}
DYNAHAND_SIMD_INLINE MaskW operator>(FloatW a, FloatW b) {
  return {_mm256_cmp_ps_mask(a.v, b.v, _CMP_GT_OQ)};
}
DYNAHAND_SIMD_INLINE MaskW operator>=(FloatW a, FloatW b) {
  return {_mm256_cmp_ps_mask(a.v, b.v, _CMP_GE_OQ)};
}
DYNAHAND_SIMD_INLINE MaskW operator==(FloatW a, FloatW b) {
  return {_mm256_cmp_ps_mask(a.v, b.v, _CMP_EQ_OQ)};
}
DYNAHAND_SIMD_INLINE MaskW operator>(IntW a, IntW b) {
  return {_mm256_cmpgt_epi32_mask(a.v, b.v)};
}
DYNAHAND_SIMD_INLINE MaskW operator&(MaskW a, MaskW b) {
  return {static_cast<__mmask8>(a.k & b.k)};
}
DYNAHAND_SIMD_INLINE unsigned bits(MaskW m) {
  return static_cast<unsigned>(m.k);
}
DYNAHAND_SIMD_INLINE bool all(MaskW m) {
  return m.k == 0xff;
}
DYNAHAND_SIMD_INLINE IntW select(MaskW m, IntW a, IntW b) {
  return {_mm256_mask_blend_epi32(m.k, b.v, a.v)};
}
DYNAHAND_SIMD_INLINE FloatW select(MaskW m, FloatW a, FloatW b) {
  return {_mm256_mask_blend_ps(m.k, b.v, a.v)};
}
DYNAHAND_SIMD_INLINE MaskW laneMask(int k) {
  return {static_cast<__mmask8>(1u << k)};
}
DYNAHAND_SIMD_INLINE MaskW operator==(IntW a, IntW b) {
  return {_mm256_cmpeq_epi32_mask(a.v, b.v)};
}
#else
DYNAHAND_SIMD_INLINE MaskW operator<(FloatW a, FloatW b) {
  return {_mm256_castps_si256(_mm256_cmp_ps(a.v, b.v, _CMP_LT_OQ))};
}
DYNAHAND_SIMD_INLINE MaskW operator<=(FloatW a, FloatW b) {
  return {_mm256_castps_si256(_mm256_cmp_ps(a.v, b.v, _CMP_LE_OQ))};
}
DYNAHAND_SIMD_INLINE MaskW operator>(FloatW a, FloatW b) {
  return {_mm256_castps_si256(_mm256_cmp_ps(a.v, b.v, _CMP_GT_OQ))};
}
DYNAHAND_SIMD_INLINE MaskW operator>=(FloatW a, FloatW b) {
  return {_mm256_castps_si256(_mm256_cmp_ps(a.v, b.v, _CMP_GE_OQ))};
}
DYNAHAND_SIMD_INLINE MaskW operator==(FloatW a, FloatW b) {
  return {_mm256_castps_si256(_mm256_cmp_ps(a.v, b.v, _CMP_EQ_OQ))};
}
DYNAHAND_SIMD_INLINE MaskW operator>(IntW a, IntW b) {
  return {_mm256_cmpgt_epi32(a.v, b.v)};
}
DYNAHAND_SIMD_INLINE MaskW operator&(MaskW a, MaskW b) {
  return {_mm256_and_si256(a.v, b.v)};
}
DYNAHAND_SIMD_INLINE unsigned bits(MaskW m) {
  return static_cast<unsigned>(_mm256_movemask_ps(_mm256_castsi256_ps(m.v)));
}
DYNAHAND_SIMD_INLINE bool all(MaskW m) {
  return bits(m) == 0xffu;
}
DYNAHAND_SIMD_INLINE IntW select(MaskW m, IntW a, IntW b) {
  return {_mm256_blendv_epi8(b.v, a.v, m.v)};
}
DYNAHAND_SIMD_INLINE FloatW select(MaskW m, FloatW a, FloatW b) {
  return {_mm256_blendv_ps(b.v, a.v, _mm256_castsi256_ps(m.v))};
}
DYNAHAND_SIMD_INLINE MaskW laneMask(int k) {
  return {_mm256_load_si256(reinterpret_cast<const __m256i*>(kLaneMaskTable[k]))};
}
DYNAHAND_SIMD_INLINE MaskW operator==(IntW a, IntW b) {
  return {_mm256_cmpeq_epi32(a.v, b.v)};
}
#endif
DYNAHAND_SIMD_INLINE void transpose8(FloatW (&r)[kLanes]) {
  const __m256 t0 = _mm256_unpacklo_ps(r[0].v, r[1].v), t1 = _mm256_unpackhi_ps(r[0].v, r[1].v);
  const __m256 t2 = _mm256_unpacklo_ps(r[2].v, r[3].v), t3 = _mm256_unpackhi_ps(r[2].v, r[3].v);
  const __m256 t4 = _mm256_unpacklo_ps(r[4].v, r[5].v), t5 = _mm256_unpackhi_ps(r[4].v, r[5].v);
  const __m256 t6 = _mm256_unpacklo_ps(r[6].v, r[7].v), t7 = _mm256_unpackhi_ps(r[6].v, r[7].v);
  const __m256 s0 = _mm256_shuffle_ps(t0, t2, 0x44), s1 = _mm256_shuffle_ps(t0, t2, 0xEE);
  const __m256 s2 = _mm256_shuffle_ps(t1, t3, 0x44), s3 = _mm256_shuffle_ps(t1, t3, 0xEE);
  const __m256 s4 = _mm256_shuffle_ps(t4, t6, 0x44), s5 = _mm256_shuffle_ps(t4, t6, 0xEE);
  const __m256 s6 = _mm256_shuffle_ps(t5, t7, 0x44), s7 = _mm256_shuffle_ps(t5, t7, 0xEE);
  r[0].v = _mm256_permute2f128_ps(s0, s4, 0x20);
  r[1].v = _mm256_permute2f128_ps(s1, s5, 0x20);
  r[2].v = _mm256_permute2f128_ps(s2, s6, 0x20);
  r[3].v = _mm256_permute2f128_ps(s3, s7, 0x20);
  r[4].v = _mm256_permute2f128_ps(s0, s4, 0x31);
  r[5].v = _mm256_permute2f128_ps(s1, s5, 0x31);
  r[6].v = _mm256_permute2f128_ps(s2, s6, 0x31);
  r[7].v = _mm256_permute2f128_ps(s3, s7, 0x31);
}
