// Compiles the kernel file named by DYNAHAND_SIMD_KERNELS once per simd::Level, each build in
// its own namespace (simd_scalar, simd_sse2, simd_avx2, simd_avx512, inside the namespace this
// is included from) that sees that level's FloatW, IntW, MaskW and operations (lanes.h); the
// AVX2 and AVX-512 builds are compiled for those. DYNAHAND_SIMD_DISPATCH (simd.h) calls the build for simd::level().
//
//   #define DYNAHAND_SIMD_KERNELS "track/finger_sampling.inl"
//   #include "core/simd/for_each_level.inl"
//
// No include guard: once per kernel file, at namespace scope, after what its kernels use; the
// file including it includes core/simd/lanes.h first (at global scope). A kernel file includes
// no headers itself.
#ifndef DYNAHAND_SIMD_KERNELS
#error "define DYNAHAND_SIMD_KERNELS (the kernel file) before including for_each_level.inl"
#endif

namespace simd_scalar {
using ::dynahand::simd::kLanes;
using namespace ::dynahand::simd::scalar;
#include DYNAHAND_SIMD_KERNELS
}  // namespace simd_scalar

#if DYNAHAND_SIMD_X86
namespace simd_sse2 {
using ::dynahand::simd::kLanes;
using namespace ::dynahand::simd::sse2;
#include DYNAHAND_SIMD_KERNELS
}  // namespace simd_sse2

DYNAHAND_SIMD_BEGIN_AVX2
namespace simd_avx2 {
using ::dynahand::simd::kLanes;
using namespace ::dynahand::simd::avx2;
#include DYNAHAND_SIMD_KERNELS
}  // namespace simd_avx2
DYNAHAND_SIMD_END

DYNAHAND_SIMD_BEGIN_AVX512
namespace simd_avx512 {
using ::dynahand::simd::kLanes;
using namespace ::dynahand::simd::avx512;
#include DYNAHAND_SIMD_KERNELS
}  // namespace simd_avx512
DYNAHAND_SIMD_END
#endif

#undef DYNAHAND_SIMD_KERNELS
