#pragma once
// A fresh directory per test case, removed after it: for tests that list what a run left
// behind (temp files included), so no other test's files may be there.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "file_bytes.h"

namespace zeroset::test {

class ScratchDirTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = std::filesystem::temp_directory_path() /
           ("zeroset_scratch_" + std::string(info->test_suite_name()) + "_" +
            std::to_string(::getpid()) + "_" + info->name());
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  /// `name` inside the test's directory.
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  /// Writes `text` to `p`, replacing it.
  static void put(const std::string& p, const std::string& text) {
    std::ofstream(p, std::ios::binary) << text;
  }
  static std::string text_of(const std::string& p) { return file_bytes(p); }

  std::filesystem::path dir_;
};

}  // namespace zeroset::test
