#include "core/simd/simd.h"

#include "core/cpu_features.h"

#include <atomic>

#if DYNAHAND_SIMD_X86
#include <xmmintrin.h>
#endif

namespace dynahand::simd {
namespace {

Level detectBestLevel() {
#if DYNAHAND_SIMD_X86
  if (cpuHasAvx2() && cpuHasAvx512vl()) return Level::Avx512;
  if (cpuHasAvx2()) return Level::Avx2;
  return Level::Sse2;
#else
  return Level::Scalar;
#endif
}

std::atomic<Level>& currentLevel() {
  static std::atomic<Level> current{bestLevel()};
  return current;
}

}  // namespace

Level bestLevel() {
  static const Level best = detectBestLevel();
  return best;
}

Level level() {
  return currentLevel().load(std::memory_order_relaxed);
}

Level forceLevel(Level wanted) {
  const Level chosen =
      static_cast<int>(wanted) <= static_cast<int>(bestLevel()) ? wanted : bestLevel();
  currentLevel().store(chosen, std::memory_order_relaxed);
  return chosen;
}

const char* levelName(Level level) {
  switch (level) {
    case Level::Scalar:
      return "scalar";
    case Level::Sse2:
      return "sse2";
    case Level::Avx2:
      return "avx2";
    case Level::Avx512:
      return "avx512";
  }
  return "?";
}

#if DYNAHAND_SIMD_X86
FlushDenormals::FlushDenormals() : saved_(_mm_getcsr()) {
  _mm_setcsr(saved_ | 0x8040u);  // FTZ | DAZ
}
FlushDenormals::~FlushDenormals() {
  _mm_setcsr(saved_);
}
#else
FlushDenormals::FlushDenormals() = default;
FlushDenormals::~FlushDenormals() = default;
#endif

}  // namespace dynahand::simd
