#pragma once
// What the tests of the `zeroset` command share: running the built binary, scratch files.
#include <filesystem>
#include <string>

#include "support/run_command.h"

namespace zeroset::test {

/// The command line that runs the built `zeroset` with `args`.
inline std::string zs(const std::string& args) { return std::string(ZEROSET_BINARY) + " " + args; }

/// The tests' scratch directory (made if missing).
inline std::string temp_dir() {
  auto d = std::filesystem::temp_directory_path() / "zeroset_cli_test";
  std::filesystem::create_directories(d);
  return d.string();
}

/// temp_dir()/name, emptied: each test has its own, since ctest runs tests side by side.
inline std::string fresh_dir(const std::string& name) {
  const auto d = std::filesystem::path(temp_dir()) / name;
  std::filesystem::remove_all(d);
  std::filesystem::create_directories(d);
  return d.string();
}

}  // namespace zeroset::test
