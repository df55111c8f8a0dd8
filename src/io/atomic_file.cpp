#include "zeroset/io/atomic_file.h"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

#include <fmt/core.h>

#include "zeroset/error.h"

namespace zeroset {
namespace fs = std::filesystem;

std::string file_extension(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  if (!ext.empty() && ext[0] == '.') ext.erase(0, 1);
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

std::string read_text_file(const std::string& path, std::size_t max_bytes, std::string_view what) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) throw IoError(path, "is a directory, not a file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path, std::string("cannot open: ") + std::strerror(errno));
  std::string text;
  std::vector<char> piece(1 << 16);
  while (in && text.size() <= max_bytes) {
    in.read(piece.data(), static_cast<std::streamsize>(piece.size()));
    text.append(piece.data(), static_cast<std::size_t>(in.gcount()));
  }
  if (in.bad()) throw IoError(path, "read failed");
  if (text.size() > max_bytes)
    throw BadInput(fmt::format("{}: larger than {} may be ({} MiB)", path, what, max_bytes >> 20));
  return text;
}

}  // namespace zeroset
