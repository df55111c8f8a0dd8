#pragma once
// Scratch files for tests: one directory per test suite under the system's temporary directory.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

namespace zeroset::test {

/// TMPDIR/zeroset_test_SUITE/NAME, where SUITE is the running test's suite; the directory is
/// made on first use. Cases run as separate processes, so a name is unique within its suite.
inline std::string temp_path(const std::string& name) {
  const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const std::string suite = info ? info->test_suite_name() : "outside_a_test";
  const auto dir = std::filesystem::temp_directory_path() / ("zeroset_test_" + suite);
  std::filesystem::create_directories(dir);
  return (dir / name).string();
}

}  // namespace zeroset::test
