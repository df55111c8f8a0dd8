#include "temp_file_detail.h"

#include <fcntl.h>
#include <sys/random.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <random>

#include "zeroset/error.h"

namespace zeroset::detail {
namespace fs = std::filesystem;

std::string random_token() {
  unsigned char bytes[16];
  size_t got = 0;
  while (got < sizeof bytes) {
    const ssize_t k = ::getrandom(bytes + got, sizeof bytes - got, 0);
    if (k > 0) {
      got += static_cast<size_t>(k);
    } else if (k < 0 && errno != EINTR) {
      break;  // no getrandom (an old kernel, a sandbox)
    }
  }
  if (got < sizeof bytes) {
    std::random_device device;
    for (unsigned char& b : bytes) b = static_cast<unsigned char>(device());
  }
  static constexpr char kDigits[] = "0123456789abcdefghijklmnopqrstuv";
  std::string token(sizeof bytes, '0');
  for (size_t i = 0; i < sizeof bytes; ++i) token[i] = kDigits[bytes[i] & 31];
  return token;
}

std::string temp_name(const fs::path& target, const std::string& token) {
  const std::string stem = target.stem().string().substr(0, 180);
  fs::path dir = target.parent_path();
  if (dir.empty()) dir = ".";
  return (dir / ("." + stem + ".tmp-" + token + target.extension().string())).string();
}

TempFile create_temp_file(const fs::path& target, const std::string& token, mode_t mode,
                          const std::string& path) {
  // A name that exists (a file, a symbolic link, dangling or not) is never opened: O_EXCL fails
  // on it and the next attempt takes a name nobody can have guessed.
  constexpr int kAttempts = 64;
  std::string name = temp_name(target, token);
  for (int attempt = 1;; ++attempt) {
    const int fd = ::open(name.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, mode);
    if (fd >= 0) {
      struct stat st {};
      const bool ok = ::fstat(fd, &st) == 0;
      const int err = errno;
      ::close(fd);
      if (!ok) {
        ::unlink(name.c_str());
        throw IoError(path, "cannot create the temp file '" + name + "': " + std::strerror(err));
      }
      return TempFile{name, st.st_dev, st.st_ino};
    }
    const int err = errno;
    if ((err == EEXIST || err == EINTR) && attempt < kAttempts) {
      if (err == EEXIST) name = temp_name(target, random_token());
      continue;
    }
    throw IoError(path, "cannot create the temp file '" + name + "': " + std::strerror(err));
  }
}

int open_temp_for_writing(const TempFile& t, const std::string& path) {
  // O_NONBLOCK: a FIFO put in the temp file's place must not hang the open.
  const int fd = ::open(t.path.c_str(), O_WRONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    const int err = errno;
    throw WriteError(
        path, "cannot open its temp file '" + t.path + "': " +
                  (err == ELOOP ? "it was replaced by a symbolic link" : std::strerror(err)));
  }
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode) || st.st_dev != t.dev || st.st_ino != t.ino) {
    ::close(fd);
    throw WriteError(path, "its temp file '" + t.path + "' was replaced by another file");
  }
  if (::ftruncate(fd, 0) != 0) {
    const int err = errno;
    ::close(fd);
    throw WriteError(path, "cannot truncate its temp file '" + t.path + "': " + std::strerror(err));
  }
  return fd;
}

bool is_made_file(const TempFile& t) {
  struct stat st {};
  return ::lstat(t.path.c_str(), &st) == 0 && S_ISREG(st.st_mode) && st.st_dev == t.dev &&
         st.st_ino == t.ino;
}

// ------------------------------------------------------------------------------ FdOutBuf
namespace {
constexpr size_t kFdBufSize = size_t{1} << 16;
}

FdOutBuf::FdOutBuf(int fd) : fd_(fd), buf_(new char[kFdBufSize]) {
  setp(buf_.get(), buf_.get() + kFdBufSize);
}

bool FdOutBuf::write_all(const char* p, size_t n) {
  if (error_ != 0) return false;
  while (n > 0) {
    const ssize_t k = ::write(fd_, p, n);
    if (k < 0 && errno == EINTR) continue;
    if (k <= 0) {
      error_ = k < 0 ? errno : EIO;
      return false;
    }
    p += k;
    n -= static_cast<size_t>(k);
  }
  return true;
}

bool FdOutBuf::drain() {
  const size_t n = static_cast<size_t>(pptr() - pbase());
  setp(buf_.get(), buf_.get() + kFdBufSize);
  return write_all(buf_.get(), n);
}

FdOutBuf::int_type FdOutBuf::overflow(int_type ch) {
  if (!drain()) return traits_type::eof();
  if (traits_type::eq_int_type(ch, traits_type::eof())) return traits_type::not_eof(ch);
  *pptr() = traits_type::to_char_type(ch);
  pbump(1);
  return ch;
}

std::streamsize FdOutBuf::xsputn(const char* s, std::streamsize n) {
  if (n <= 0) return 0;
  if (n < epptr() - pptr()) {
    std::memcpy(pptr(), s, static_cast<size_t>(n));
    pbump(static_cast<int>(n));
    return n;
  }
  return drain() && write_all(s, static_cast<size_t>(n)) ? n : 0;
}

int FdOutBuf::sync() { return drain() ? 0 : -1; }

}  // namespace zeroset::detail
