// The SIMD layer's one dispatch point: which instruction set the vector kernels run on.
//
// Kernels are written once against the eight-lane types of lanes.h (FloatW, IntW, MaskW) and
// compiled for every level by for_each_level.inl; a kernel's caller picks the build for
// simd::level() (DYNAHAND_SIMD_DISPATCH). Every level gives the same bits: the lanes do the
// same IEEE operations in the same order (no fused multiply-add: the build has
// -ffp-contract=off), and the scalar level is the reference the others are tested against.
#pragma once

// The x86 levels are built with GCC or Clang on x86-64; elsewhere only the scalar one.
#if defined(__x86_64__) && defined(__GNUC__)
#define DYNAHAND_SIMD_X86 1
#else
#define DYNAHAND_SIMD_X86 0
#endif

// Functions defined between DYNAHAND_SIMD_BEGIN_AVX2 (or _AVX512) and DYNAHAND_SIMD_END are
// compiled for AVX2 (AVX-512F and VL), and run only where simd::level() says the CPU has it.
#if defined(__clang__)
#define DYNAHAND_SIMD_BEGIN_AVX2 \
  _Pragma("clang attribute push(__attribute__((target(\"avx2\"))), apply_to = function)")
#define DYNAHAND_SIMD_BEGIN_AVX512                                                           \
  _Pragma(                                                                                   \
      "clang attribute push(__attribute__((target(\"avx2,avx512f,avx512vl\"))), apply_to = " \
      "function)")
#define DYNAHAND_SIMD_END _Pragma("clang attribute pop")
#else
#define DYNAHAND_SIMD_BEGIN_AVX2 _Pragma("GCC push_options") _Pragma("GCC target(\"avx2\")")
#define DYNAHAND_SIMD_BEGIN_AVX512 \
  _Pragma("GCC push_options") _Pragma("GCC target(\"avx2,avx512f,avx512vl\")")
#define DYNAHAND_SIMD_END _Pragma("GCC pop_options")
#endif

// Calls `function` (a void function of a kernel file compiled by for_each_level.inl, named
// without its level namespace) built for simd::level().
#if DYNAHAND_SIMD_X86
#define DYNAHAND_SIMD_DISPATCH(function, ...) \
  do {                                        \
    switch (::dynahand::simd::level()) {      \
      case ::dynahand::simd::Level::Avx512:   \
        simd_avx512::function(__VA_ARGS__);   \
        break;                                \
      case ::dynahand::simd::Level::Avx2:     \
        simd_avx2::function(__VA_ARGS__);     \
        break;                                \
      case ::dynahand::simd::Level::Sse2:     \
        simd_sse2::function(__VA_ARGS__);     \
        break;                                \
      case ::dynahand::simd::Level::Scalar:   \
        simd_scalar::function(__VA_ARGS__);   \
        break;                                \
    }                                         \
  } while (false)
#else
#define DYNAHAND_SIMD_DISPATCH(function, ...) simd_scalar::function(__VA_ARGS__)
#endif

namespace dynahand::simd {

/// The instruction sets the kernels are built for, narrowest first. The build's baseline is
/// plain x86-64 (SSE2); the wider levels run where the CPU has them. Avx512 runs the AVX2
/// instructions compiled for AVX-512F and VL (32 registers).
enum class Level { Scalar = 0, Sse2 = 1, Avx2 = 2, Avx512 = 3 };

inline constexpr int kLevelCount = 4;

/// The widest level the CPU supports (Scalar off x86-64 or without GCC's CPU detection).
Level bestLevel();

/// The level the kernels run on: bestLevel() unless forceLevel chose a narrower one.
/// Process-wide; reading it is one relaxed atomic load.
Level level();

/// Makes the kernels run on `wanted`, or on bestLevel() where the CPU lacks it; returns the
/// level now in use. For tests and benchmarks comparing levels: not for concurrent tracking.
Level forceLevel(Level wanted);

/// "scalar", "sse2", "avx2", "avx512".
const char* levelName(Level level);

/// Denormals flushed to zero (x86: FTZ and DAZ) while it lives, the caller's mode restored
/// after: values decaying toward zero (a solver's velocities at rest) pass through the
/// denormal range, where each float operation costs about 100 cycles. Deterministic either
/// way (the same mode every time). No effect off x86-64.
class FlushDenormals {
 public:
  FlushDenormals();
  ~FlushDenormals();
  FlushDenormals(const FlushDenormals&) = delete;
  FlushDenormals& operator=(const FlushDenormals&) = delete;

 private:
  unsigned saved_ = 0;
};

}  // namespace dynahand::simd
