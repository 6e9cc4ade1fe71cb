// The fuzz input layout shared by the fuzz target and the seed writer:
//   byte 0: which reader (FuzzMode); single-file modes read all the bytes after it;
//   two-file modes read bytes 1-2 as the length L of part A (little endian), then
//   part A (L bytes) and part B (the rest).
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace dynahand::fuzz {

enum class FuzzMode : std::uint8_t {
  DepthPng16 = 0,       // whole: PNG bytes, decoded as 16-bit depth
  NyuPng = 1,           // whole: PNG bytes, decoded as NYU packed depth
  CameraJson = 2,       // whole: camera.json text
  IntelJson = 3,        // whole: NAME.json text
  GroundTruthLine = 4,  // whole: one groundtruth.jsonl line
  CanonicalFolder = 5,  // A: camera.json, B: depth/000000.png; opened and read whole
  IntelRecording = 6,   // A: NAME.json, B: NAME.rs; opened and read whole
  Count = 7
};

struct FuzzInput {
  FuzzMode mode = FuzzMode::DepthPng16;
  std::span<const std::uint8_t> whole;  // everything after the mode byte
  std::span<const std::uint8_t> a;
  std::span<const std::uint8_t> b;
};

inline FuzzInput splitFuzzInput(std::span<const std::uint8_t> data) {
  FuzzInput in;
  if (data.empty()) return in;
  in.mode = static_cast<FuzzMode>(data[0] % static_cast<std::uint8_t>(FuzzMode::Count));
  data = data.subspan(1);
  in.whole = data;
  std::size_t lengthA = data.size();
  if (data.size() >= 2) {
    lengthA = std::min<std::size_t>(data[0] | (std::size_t{data[1]} << 8), data.size() - 2);
    data = data.subspan(2);
  }
  in.a = data.first(lengthA);
  in.b = data.subspan(lengthA);
  return in;
}

inline std::vector<std::uint8_t> singleFuzzInput(FuzzMode mode,
                                                 std::span<const std::uint8_t> bytes) {
  std::vector<std::uint8_t> out{static_cast<std::uint8_t>(mode)};
  out.insert(out.end(), bytes.begin(), bytes.end());
  return out;
}

inline std::vector<std::uint8_t> joinFuzzInput(FuzzMode mode, std::span<const std::uint8_t> a,
                                               std::span<const std::uint8_t> b) {
  std::vector<std::uint8_t> out{static_cast<std::uint8_t>(mode),
                                static_cast<std::uint8_t>(a.size() & 0xff),
                                static_cast<std::uint8_t>((a.size() >> 8) & 0xff)};
  out.insert(out.end(), a.begin(), a.end());
  out.insert(out.end(), b.begin(), b.end());
  return out;
}

}  // namespace dynahand::fuzz
