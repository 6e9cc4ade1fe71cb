// What the CPU running us supports, for the hot loops that pick a wider instruction set at
// run time (the build's baseline is plain x86-64).
#pragma once

namespace dynahand {

// Whether the CPU has AVX. Safe from static initialisers, which may run before the
// compiler's own CPU detection: it runs that first.
inline bool cpuHasAvx() {
#if defined(__x86_64__) && defined(__GNUC__)
  __builtin_cpu_init();
  return __builtin_cpu_supports("avx") != 0;
#else
  return false;
#endif
}

// Whether the CPU has AVX2 (integer operations on 256-bit vectors).
inline bool cpuHasAvx2() {
#if defined(__x86_64__) && defined(__GNUC__)
  __builtin_cpu_init();
  return __builtin_cpu_supports("avx2") != 0;
#else
  return false;
#endif
}

// Whether the CPU has AVX-512F and AVX-512VL (mask registers on 256-bit vectors).
inline bool cpuHasAvx512vl() {
#if defined(__x86_64__) && defined(__GNUC__)
  __builtin_cpu_init();
  return __builtin_cpu_supports("avx512f") != 0 && __builtin_cpu_supports("avx512vl") != 0;
#else
  return false;
#endif
}

}  // namespace dynahand
