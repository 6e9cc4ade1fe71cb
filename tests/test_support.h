// Helpers shared by the test programs.
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

namespace dynahand::test {

// ../shared/data beside the checkout, or empty when it is absent (a user's clone).
inline std::filesystem::path sharedDataDir() {
  const char* env = std::getenv("DYNAHAND_SHARED_DIR");
  std::filesystem::path dir = env ? env : DYNAHAND_SHARED_DIR;
  dir /= "data";
  return std::filesystem::is_directory(dir) ? dir : std::filesystem::path{};
}

// Skips the current test with a clear message when ../shared/data is absent.
#define DYNAHAND_REQUIRE_SHARED_DATA(dirVar)                              \
  const std::filesystem::path dirVar = ::dynahand::test::sharedDataDir(); \
  if (dirVar.empty())                                                     \
  GTEST_SKIP() << "../shared/data not found (set DYNAHAND_SHARED_DIR); skipping data test"

// A fresh scratch folder under the build tree for files a test writes, one per test (CTest
// runs the tests of one program in parallel: a folder shared by name would be wiped by one
// test while another writes into it).
inline std::filesystem::path scratchDir(const std::string& name) {
  std::filesystem::path dir = std::filesystem::path(DYNAHAND_BINARY_DIR) / "test-scratch" / name;
  if (const auto* test = ::testing::UnitTest::GetInstance()->current_test_info())
    dir /= std::string(test->test_suite_name()) + "." + test->name();
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

}  // namespace dynahand::test
