#pragma once
/// The temp files of an output transaction (output_transaction.cpp): names nobody can guess,
/// made exclusively and never through a symbolic link, written through a file descriptor that
/// is checked to still be the file that was made.
#include <sys/types.h>

#include <filesystem>
#include <memory>
#include <streambuf>
#include <string>

namespace zeroset::detail {

/// 16 characters of [0-9a-v] (80 bits) from the kernel's random source (getrandom, else
/// std::random_device). Never '%': ffmpeg reads a pattern made of temp names.
std::string random_token();

/// ".STEM.tmp-TOKEN.EXT" beside `target`: hidden, with the target's extension for programs
/// that go by it (the stem shortened to 180 bytes).
std::string temp_name(const std::filesystem::path& target, const std::string& token);

/// A temp file made by create_temp_file: its name and its inode.
struct TempFile {
  std::string path;
  dev_t dev = 0;
  ino_t ino = 0;
};

/// Makes a new, empty regular file beside `target` with open(O_CREAT | O_EXCL | O_NOFOLLOW):
/// named with `token`, or, while a name is taken (EEXIST), with fresh random tokens, a bounded
/// number of times. `mode` is open(2)'s: the umask applies. Throws IoError naming `path` (the
/// output as the user gave it) with the temp file and strerror when it cannot be made.
TempFile create_temp_file(const std::filesystem::path& target, const std::string& token,
                          mode_t mode, const std::string& path);

/// Opens the temp file `t` for writing and truncates it, after checking that its name still
/// leads to the file create_temp_file made (not a symbolic link, not another file put in its
/// place). Returns the descriptor; throws WriteError naming `path` otherwise.
int open_temp_for_writing(const TempFile& t, const std::string& path);

/// True when `t.path` is still the regular file create_temp_file made (not followed if a link).
bool is_made_file(const TempFile& t);

/// An output stream buffer over a file descriptor it does not own: 64 KiB buffered, write(2)
/// retried on EINTR and short writes. The first failure's errno is kept and every later write
/// fails.
class FdOutBuf final : public std::streambuf {
 public:
  explicit FdOutBuf(int fd);
  /// errno of the first failed write, 0 when none failed.
  int error() const { return error_; }

 protected:
  int_type overflow(int_type ch) override;
  std::streamsize xsputn(const char* s, std::streamsize n) override;
  int sync() override;

 private:
  bool drain();
  bool write_all(const char* p, size_t n);

  int fd_;
  int error_ = 0;
  std::unique_ptr<char[]> buf_;
};

}  // namespace zeroset::detail
