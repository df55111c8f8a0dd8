#pragma once
// A file's bytes, for tests that compare what two runs wrote.
#include <fstream>
#include <sstream>
#include <string>

namespace zeroset::test {

/// The whole file (empty when it cannot be read).
inline std::string file_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace zeroset::test
