#include "zeroset/io/output_transaction.h"

#include <fcntl.h>
#if defined(__linux__)
#include <linux/fs.h>
#endif
#include <signal.h>
#include <sys/ioctl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <new>
#include <ostream>
#include <utility>

#include "temp_file_detail.h"
#include "zeroset/error.h"
#include "zeroset/io/atomic_file.h"

namespace zeroset {
namespace fs = std::filesystem;

// ------------------------------------------------------------------- signal-safe clean-up
// The paths a signal handler removes: C strings copied when an output is declared (never in
// the handler), in fixed arrays of atomic pointers. Whoever takes a pointer out of its slot
// (exchange with nullptr) owns it: the handler unlinks it, the transaction frees it; never
// both, whichever thread the signal lands on.
namespace {

constexpr int kFileSlots = kMaxPendingOutputs;
constexpr int kDirSlots = 256;
std::atomic<char*> g_files[kFileSlots];
std::atomic<char*> g_dirs[kDirSlots];
std::atomic<int> g_next_file{0};  // where the search for a free slot starts

int register_path(std::atomic<char*>* slots, int count, std::atomic<int>* next,
                  const std::string& path) {
  char* copy = ::strdup(path.c_str());
  if (copy == nullptr) throw std::bad_alloc();
  const int start = next ? next->load(std::memory_order_relaxed) : 0;
  for (int k = 0; k < count; ++k) {
    const int i = (start + k) % count;
    char* expected = nullptr;
    if (slots[i].compare_exchange_strong(expected, copy)) {
      if (next) next->store((i + 1) % count, std::memory_order_relaxed);
      return i;
    }
  }
  std::free(copy);
  throw Error("'" + path + "': more than " + std::to_string(count) +
              " output files or directories pending at once");
}

void unregister_path(std::atomic<char*>* slots, int slot) {
  if (slot < 0) return;
  std::free(slots[slot].exchange(nullptr));
}

extern "C" void remove_pending_outputs(int sig) {
  const int saved_errno = errno;
  for (auto& slot : g_files)
    if (char* p = slot.exchange(nullptr)) ::unlink(p);
  // Directories made for outputs, deepest first: repeat while one more could be removed (rmdir
  // refuses a directory that is not empty, so a user's files are never touched).
  char* dirs[kDirSlots];
  int n = 0;
  for (auto& slot : g_dirs)
    if (char* p = slot.exchange(nullptr)) dirs[n++] = p;
  for (bool removed = true; removed;) {
    removed = false;
    for (int i = 0; i < n; ++i)
      if (dirs[i] && ::rmdir(dirs[i]) == 0) dirs[i] = nullptr, removed = true;
  }
  struct sigaction dfl {};
  dfl.sa_handler = SIG_DFL;
  sigemptyset(&dfl.sa_mask);
  ::sigaction(sig, &dfl, nullptr);
  errno = saved_errno;
  // Pending while the handler runs (the signal is blocked in it), delivered when it returns:
  // the process ends as the signal's default action ends it.
  ::raise(sig);
}

// ----------------------------------------------------------------------- output paths
fs::path parent_or_dot(const fs::path& p) {
  fs::path dir = p.parent_path();
  return dir.empty() ? fs::path(".") : dir;
}

/// `path` with every symbolic link at its end followed (dangling ones too): the file a write
/// through it has to replace.
fs::path follow_links(const std::string& path) {
  fs::path p(path);
  std::error_code ec;
  for (int hops = 0; fs::is_symlink(fs::symlink_status(p, ec)); ++hops) {
    if (hops == 40) throw IoError(path, "too many levels of symbolic links");
    const fs::path to = fs::read_symlink(p, ec);
    if (ec) throw IoError(path, "cannot read the symbolic link: " + ec.message());
    p = to.is_absolute() ? to : parent_or_dot(p) / to;
  }
  return p;
}

struct CheckedPath {
  fs::path target;  // links followed
  bool direct;      // an existing file that is not a regular file: written in place
};

CheckedPath check_output_path(const std::string& path) {
  if (path.empty()) throw IoError(path, "empty output path");
  CheckedPath c{follow_links(path), false};
  std::error_code ec;
  const fs::file_status st = fs::status(c.target, ec);
  if (fs::is_directory(st)) throw IoError(path, "is a directory, not a file");
  if (fs::exists(st) && !fs::is_regular_file(st)) {
    c.direct = true;
    if (::access(c.target.c_str(), W_OK) != 0) throw IoError(path, "is not writable");
    return c;
  }
  const fs::path dir = parent_or_dot(c.target);
  if (!fs::is_directory(dir, ec))
    throw IoError(path, "directory '" + dir.string() + "' does not exist");
  if (::access(dir.c_str(), W_OK) != 0)
    throw IoError(path, "directory '" + dir.string() + "' is not writable");
  // A name the file system cannot hold would fail only when the finished file is moved into
  // place, after the work.
  const std::string name = c.target.filename().string();
  const long name_max = ::pathconf(dir.c_str(), _PC_NAME_MAX);
  if (name_max > 0 && name.size() > static_cast<std::size_t>(name_max))
    throw IoError(path, "the file name is " + std::to_string(name.size()) +
                            " bytes long; the directory allows at most " +
                            std::to_string(name_max));
  return c;
}

fs::path canonical_or_absolute(const fs::path& p) {
  std::error_code ec;
  const fs::path absolute = fs::absolute(p, ec).lexically_normal();
  fs::path c = fs::weakly_canonical(absolute, ec);
  return ec ? absolute : c;
}

thread_local OutputTransaction* t_active = nullptr;

std::string errno_text(int err) { return err != 0 ? std::strerror(err) : "unknown error"; }

/// Closes a file descriptor when it goes out of scope (an exception of a writer).
class FdCloser {
 public:
  explicit FdCloser(int fd) : fd_(fd) {}
  ~FdCloser() {
    if (fd_ >= 0) ::close(fd_);
  }
  FdCloser(const FdCloser&) = delete;
  FdCloser& operator=(const FdCloser&) = delete;
  int get() const { return fd_; }
  /// Closes it now: 0, or close(2)'s errno (NFS reports failed writes here).
  int close() {
    const int fd = std::exchange(fd_, -1);
    return fd < 0 || ::close(fd) == 0 ? 0 : errno;
  }

 private:
  int fd_;
};

/// Why `path`, a file of an earlier run that a commit removes, could not be removed (empty:
/// it can, or it is gone already). Checked when the removal is planned, before any work, and
/// again before a commit's first rename, so a commit that could not finish changes nothing.
std::string removal_obstacle(const std::string& path) {
  struct stat st {};
  if (::lstat(path.c_str(), &st) != 0) return errno == ENOENT ? "" : errno_text(errno);
  if (S_ISDIR(st.st_mode)) return "it is a directory";
  const fs::path dir = parent_or_dot(fs::path(path));
  struct stat ds {};
  if (::stat(dir.c_str(), &ds) != 0) return errno_text(errno);
  if (::access(dir.c_str(), W_OK | X_OK) != 0)
    return "directory '" + dir.string() + "' is not writable";
  const uid_t me = ::geteuid();
  if ((ds.st_mode & S_ISVTX) && me != 0 && st.st_uid != me && ds.st_uid != me)
    return "it belongs to another user, in a directory with the sticky bit";
#if defined(__linux__) && defined(FS_IOC_GETFLAGS)
  if (S_ISREG(st.st_mode)) {
    const int fd = ::open(path.c_str(), O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC);
    if (fd >= 0) {
      int flags = 0;
      const bool known = ::ioctl(fd, FS_IOC_GETFLAGS, &flags) == 0;
      ::close(fd);
      if (known && (flags & (FS_IMMUTABLE_FL | FS_APPEND_FL)))
        return "it is immutable or append-only (chattr)";
    }
  }
#endif
  return "";
}

}  // namespace

void remove_pending_outputs_on_signals() {
  // SIGHUP: the terminal closed; SIGQUIT: Ctrl-\; SIGPIPE: an output that is a pipe or FIFO
  // whose reader quit (the process ends silently, as tools in a pipeline do).
  for (int sig : {SIGINT, SIGTERM, SIGHUP, SIGQUIT, SIGPIPE}) {
    struct sigaction old {};
    if (::sigaction(sig, nullptr, &old) != 0 || old.sa_handler == SIG_IGN) continue;
    struct sigaction sa {};
    sa.sa_handler = remove_pending_outputs;
    sigemptyset(&sa.sa_mask);
    ::sigaction(sig, &sa, nullptr);
  }
  // A write past the file-size limit (ulimit -f) would end the process without a word; ignored,
  // the write fails with EFBIG instead, which the writer reports ("File too large") and the
  // transaction cleans up after.
  struct sigaction xfsz {};
  if (::sigaction(SIGXFSZ, nullptr, &xfsz) == 0 && xfsz.sa_handler == SIG_DFL) {
    xfsz.sa_handler = SIG_IGN;
    sigemptyset(&xfsz.sa_mask);
    ::sigaction(SIGXFSZ, &xfsz, nullptr);
  }
}

void check_writable(const std::string& path) { check_output_path(path); }

// -------------------------------------------------------------------------- transaction
struct OutputTransaction::Output {
  std::string path;  // as given
  std::string flag;
  fs::path target;        // links followed
  detail::TempFile temp;  // path empty: written directly
  int mode = -1;          // the permission bits of the file it replaces; -1: a new file
  int slot = -1;          // of `temp` in the signal clean-up
  bool written = false;
  bool external = false;
  bool renamed = false;
};

OutputTransaction::OutputTransaction() : token_(detail::random_token()), outer_(t_active) {
  t_active = this;
}

OutputTransaction::~OutputTransaction() {
  if (!committed_) roll_back();
  t_active = outer_;
}

OutputTransaction* OutputTransaction::active() { return t_active; }

void OutputTransaction::declare(const std::string& path, const std::string& flag) {
  const CheckedPath c = check_output_path(path);
  // Two outputs replacing one file: the second would overwrite the first. (Devices such as
  // /dev/null are written in place and may take several.)
  const std::string name = canonical_or_absolute(c.target).string();
  struct stat st {};
  const bool exists = ::stat(c.target.c_str(), &st) == 0;
  const std::pair<unsigned long long, unsigned long long> inode{st.st_dev, st.st_ino};
  if (!c.direct) {
    const auto by_name = by_name_.find(name);
    const auto by_inode = exists ? by_inode_.find(inode) : by_inode_.end();
    if (by_name != by_name_.end() || by_inode != by_inode_.end()) {
      const Output& o = outputs_[by_name != by_name_.end() ? by_name->second : by_inode->second];
      throw InvalidArgument(
          flag, path,
          "names the same file as " + o.flag + " " + o.path + "; give each output its own file");
    }
  }
  Output o;
  o.path = path;
  o.flag = flag;
  o.target = c.target;
  // The push_back below must not throw; capacity grows geometrically (an animation declares
  // every frame: reserving one more each time would copy them all each time).
  if (outputs_.size() == outputs_.capacity())
    outputs_.reserve(std::max<std::size_t>(16, 2 * outputs_.capacity()));
  if (!c.direct) {
    // The temp file is made now, before any work, under a name nobody can guess and never
    // through a symbolic link (a path where it cannot be made is bad input). It replaces an
    // existing file with that file's permission bits, set when it is written (until then it is
    // the owner's alone); a new file gets 0666 less the umask, as any new file.
    if (exists) o.mode = static_cast<int>(st.st_mode & 0777);
    o.temp = detail::create_temp_file(c.target, token_, exists ? 0600 : 0666, path);
    try {
      o.slot = register_path(g_files, kFileSlots, &g_next_file, o.temp.path);
      by_name_[name] = outputs_.size();
      if (exists) by_inode_[inode] = outputs_.size();
      by_path_.emplace(path, outputs_.size());
    } catch (...) {
      unregister_path(g_files, o.slot);
      ::unlink(o.temp.path.c_str());
      by_name_.erase(name);
      if (exists) by_inode_.erase(inode);
      throw;
    }
  } else {
    by_path_.emplace(path, outputs_.size());
  }
  outputs_.push_back(std::move(o));
}

OutputTransaction::Output& OutputTransaction::find_or_declare(const std::string& path) {
  if (const auto it = by_path_.find(path); it != by_path_.end()) return outputs_[it->second];
  declare(path, "output");
  return outputs_.back();
}

void OutputTransaction::write(const std::string& path,
                              const std::function<void(std::ostream&)>& write) {
  Output& o = find_or_declare(path);
  if (o.written || o.external) throw Error("internal error: '" + path + "' written twice");
  int raw = -1;
  if (o.temp.path.empty()) {  // a device or a FIFO, written in place
    raw = ::open(o.target.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
    if (raw < 0) throw WriteError(path, "cannot open: " + errno_text(errno));
  } else {
    raw = detail::open_temp_for_writing(o.temp, path);
  }
  FdCloser fd(raw);
  o.written = true;
  const int mode = o.mode;  // `o` may move while `write` runs (a writer declaring an output)
  detail::FdOutBuf buf(fd.get());
  std::ostream out(&buf);
  write(out);
  out.flush();
  int err = buf.error();
  if (out && err == 0 && mode >= 0 && ::fchmod(fd.get(), static_cast<mode_t>(mode)) != 0)
    err = errno;
  if (const int close_err = fd.close(); err == 0) err = close_err;
  if (!out || err != 0) throw WriteError(path, "write failed: " + errno_text(err));
}

std::string OutputTransaction::temp_path(const std::string& path) const {
  const auto it = by_path_.find(path);
  if (it == by_path_.end()) throw Error("internal error: '" + path + "' was not declared");
  const Output& o = outputs_[it->second];
  return o.temp.path.empty() ? o.target.string() : o.temp.path;
}

std::string OutputTransaction::external_temp_path(const std::string& path) {
  const std::string temp = temp_path(path);
  outputs_[by_path_.at(path)].external = true;
  return temp;
}

void OutputTransaction::create_directories(const std::string& dir) {
  fs::path p = fs::path(dir).lexically_normal();
  if (!p.has_filename()) p = p.parent_path();
  std::vector<fs::path> missing;
  std::error_code ec;
  for (fs::path q = p; !q.empty() && !fs::exists(fs::symlink_status(q, ec)); q = q.parent_path()) {
    missing.push_back(q);
    if (q == q.parent_path()) break;
  }
  for (auto it = missing.rbegin(); it != missing.rend(); ++it) {
    dir_slots_.push_back(register_path(g_dirs, kDirSlots, nullptr, it->string()));
    made_dirs_.push_back(it->string());
    if (!fs::create_directory(*it, ec) && ec)
      throw IoError(dir, "cannot create the directory '" + it->string() + "': " + ec.message());
  }
  if (!fs::is_directory(p, ec)) throw IoError(dir, "exists and is not a directory");
}

void OutputTransaction::remove_on_commit(const std::string& path) {
  if (const std::string why = removal_obstacle(path); !why.empty())
    throw IoError(path, "this run must remove this file of an earlier run and cannot: " + why);
  remove_at_commit_.push_back(path);
}

void OutputTransaction::commit() {
  if (committed_) throw Error("internal error: an output transaction committed twice");
  std::error_code ec;
  for (const Output& o : outputs_)
    if (!o.written && !(o.external && external_output_exists(o)))
      throw WriteError(o.path, o.external ? "the program that makes it wrote nothing"
                                          : "internal error: declared but never written");
  // Everything that can fail is checked before the first rename.
  for (const std::string& p : remove_at_commit_)
    if (const std::string why = removal_obstacle(p); !why.empty())
      throw WriteError(p, "this run must remove this file of an earlier run and cannot: " + why);
  for (Output& o : outputs_) {
    if (o.temp.path.empty()) continue;
    if (o.external) {
      finish_external_output(o);
    } else if (!detail::is_made_file(o.temp)) {
      throw WriteError(o.path, "its temp file '" + o.temp.path + "' was replaced by another file");
    }
    if (::rename(o.temp.path.c_str(), o.target.c_str()) != 0)
      throw WriteError(o.path, "cannot move into place: " + errno_text(errno));
    o.renamed = true;
    unregister_path(g_files, o.slot);
    o.slot = -1;
  }
  committed_ = true;
  for (const int slot : dir_slots_) unregister_path(g_dirs, slot);
  dir_slots_.clear();
  for (const std::string& p : remove_at_commit_) {
    fs::remove(p, ec);
    if (ec) throw WriteError(p, "cannot remove this file of an earlier run: " + ec.message());
  }
}

bool OutputTransaction::external_output_exists(const Output& o) {
  // Its temp file exists from the start: the program wrote something if it is not empty.
  struct stat st {};
  if (o.temp.path.empty()) return ::stat(o.target.c_str(), &st) == 0;
  return ::lstat(o.temp.path.c_str(), &st) == 0 && S_ISREG(st.st_mode) && st.st_size > 0;
}

void OutputTransaction::finish_external_output(const Output& o) {
  if (o.mode < 0) return;
  const int raw = ::open(o.temp.path.c_str(), O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC);
  if (raw < 0) throw WriteError(o.path, "cannot open its temp file: " + errno_text(errno));
  FdCloser fd(raw);
  if (::fchmod(fd.get(), static_cast<mode_t>(o.mode)) != 0)
    throw WriteError(o.path, "cannot set the permissions of its temp file: " + errno_text(errno));
}

void OutputTransaction::roll_back() noexcept {
  for (Output& o : outputs_) {
    if (!o.temp.path.empty() && !o.renamed) ::unlink(o.temp.path.c_str());
    unregister_path(g_files, o.slot);
    o.slot = -1;
  }
  for (size_t k = made_dirs_.size(); k-- > 0;) {
    ::rmdir(made_dirs_[k].c_str());
    unregister_path(g_dirs, dir_slots_[k]);
  }
  dir_slots_.clear();
}

void write_file_atomically(const std::string& path,
                           const std::function<void(std::ostream&)>& write) {
  if (OutputTransaction* tx = OutputTransaction::active()) return tx->write(path, write);
  OutputTransaction tx;
  tx.write(path, write);
  tx.commit();
}

}  // namespace zeroset
