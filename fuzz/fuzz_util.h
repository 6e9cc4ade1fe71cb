// Helpers shared by the fuzz targets: the input as text, a scratch folder per fuzzing
// process for readers that only take a path, and the check that turns a broken promise of
// a reader into a crash libFuzzer reports.
#pragma once

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <span>
#include <string>
#include <string_view>

namespace dynahand::fuzz {

inline std::string_view text(std::span<const std::uint8_t> bytes) {
  return {reinterpret_cast<const char*>(bytes.data()), bytes.size()};
}

inline void writeFile(const std::filesystem::path& file, std::span<const std::uint8_t> bytes) {
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
}

// A scratch folder per fuzzing process (fuzz.sh runs several at once), reused by every
// input; removed at exit.
inline const std::filesystem::path& scratch() {
  static const std::filesystem::path dir = [] {
    const std::filesystem::path d =
        std::filesystem::temp_directory_path() / ("dynahand-fuzz-" + std::to_string(::getpid()));
    std::filesystem::create_directories(d);
    std::atexit([] {
      std::error_code ignored;
      std::filesystem::remove_all(
          std::filesystem::temp_directory_path() / ("dynahand-fuzz-" + std::to_string(::getpid())),
          ignored);
    });
    return d;
  }();
  return dir;
}

// The bytes as a file named `name` in the scratch folder; returns its path.
inline std::filesystem::path scratchFile(const std::string& name,
                                         std::span<const std::uint8_t> bytes) {
  const std::filesystem::path file = scratch() / name;
  writeFile(file, bytes);
  return file;
}

// A reader broke one of its own promises: report it and abort (libFuzzer saves the input).
[[noreturn]] inline void fail(const char* what, const char* file, int line) {
  std::fprintf(stderr, "fuzz check failed at %s:%d: %s\n", file, line, what);
  std::abort();
}

}  // namespace dynahand::fuzz

#define FUZZ_CHECK(condition) \
  ((condition) ? static_cast<void>(0) : ::dynahand::fuzz::fail(#condition, __FILE__, __LINE__))
