// Counter-based random numbers for the synthetic sensor: a value is a pure function of
// (seed, frame, pixel, stream), so frames are reproducible and can be made in any order
// without carrying generator state. Portable (no std:: distributions, whose output
// differs between standard libraries).
#pragma once

#include <array>
#include <cstdint>

namespace dynahand::synth::detail {

// SplitMix64 finaliser: a good 64-bit mixer.
inline std::uint64_t mix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

inline std::uint64_t frameKey(std::uint64_t seed, int frame) {
  return mix64(seed ^ mix64(static_cast<std::uint64_t>(frame) + 0x51ED27u));
}

// Random bits for one (pixel, stream) of a frame.
inline std::uint64_t bits(std::uint64_t key, std::uint64_t index, std::uint64_t stream) {
  return mix64(key ^ (index * 0xD1B54A32D192ED03ull) ^ (stream * 0x8CB92BA72F3D8DD7ull));
}

// Uniform in [0, 1).
inline float uniform(std::uint64_t r) {
  return static_cast<float>(r >> 40) * (1.0f / 16777216.0f);
}

// Uniform in [0, 1) from the low 24 bits (independent of uniform() and normal()).
inline float uniformLow(std::uint64_t r) {
  return static_cast<float>(r & 0xFFFFFFu) * (1.0f / 16777216.0f);
}

// Standard normal by inverse-CDF table lookup (4096 equal-probability bins; the value
// uses the top 12 bits; unit variance by construction, tails cut at about 3.5 sigma).
float normal(std::uint64_t r);

}  // namespace dynahand::synth::detail
