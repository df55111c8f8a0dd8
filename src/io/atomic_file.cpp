#include "zeroset/io/atomic_file.h"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "zeroset/error.h"

namespace zeroset {
namespace fs = std::filesystem;

namespace {

fs::path parent_or_dot(const fs::path& p) {
  fs::path dir = p.parent_path();
  return dir.empty() ? fs::path(".") : dir;
}

std::string temp_name_for(const fs::path& target) {
  static std::atomic<unsigned> counter{0};
  std::ostringstream s;
  s << "." << target.filename().string() << ".tmp-" << ::getpid() << "-" << counter++;
  return (parent_or_dot(target) / s.str()).string();
}

}  // namespace

void check_writable(const std::string& path) {
  if (path.empty()) throw IoError(path, "empty output path");
  const fs::path p(path);
  std::error_code ec;
  if (fs::is_directory(p, ec)) throw IoError(path, "is a directory, not a file");
  const fs::path dir = parent_or_dot(p);
  if (!fs::is_directory(dir, ec))
    throw IoError(path, "directory '" + dir.string() + "' does not exist");
  if (::access(dir.c_str(), W_OK) != 0)
    throw IoError(path, "directory '" + dir.string() + "' is not writable");
}

void write_file_atomically(const std::string& path,
                           const std::function<void(std::ostream&)>& write) {
  check_writable(path);
  const std::string tmp = temp_name_for(path);
  try {
    {
      std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
      if (!out) throw IoError(path, std::string("cannot create: ") + std::strerror(errno));
      write(out);
      out.flush();
      if (!out) throw IoError(path, "write failed (disk full?)");
    }
    std::error_code ec;
    fs::rename(tmp, path, ec);
    if (ec) throw IoError(path, "cannot move into place: " + ec.message());
  } catch (...) {
    std::error_code ignored;
    fs::remove(tmp, ignored);
    throw;
  }
}

std::string file_extension(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  if (!ext.empty() && ext[0] == '.') ext.erase(0, 1);
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

std::string read_text_file(const std::string& path) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) throw IoError(path, "is a directory, not a file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path, std::string("cannot open: ") + std::strerror(errno));
  std::ostringstream s;
  s << in.rdbuf();
  if (in.bad()) throw IoError(path, "read failed");
  return s.str();
}

}  // namespace zeroset
