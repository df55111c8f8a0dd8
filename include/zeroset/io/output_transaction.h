#pragma once
/// All output files of one command as one transaction (docs/architecture.md, "Errors"): each
/// output is written into a temp file beside its target and renamed into place only when every
/// output was written; after an error, an exception or SIGINT/SIGTERM no temp file is left and
/// every target is as before. Temp files have names nobody can guess and are made exclusively,
/// never through a symbolic link, so that a link planted in a shared directory redirects nothing.
#include <functional>
#include <map>
#include <ostream>
#include <string>
#include <vector>

namespace zeroset {

/// A command's outputs, staged and committed together. While it lives it is the active
/// transaction of its thread: write_file_atomically (and so every writer of the library:
/// write_mesh, write_png, write_json, ...) stages into it instead of writing on its own.
///
///     OutputTransaction tx;
///     tx.declare(output, "--output");    // before any work: refused paths exit 2
///     tx.declare(stats, "--stats");
///     ... work, write_png(image, output), write_json(j, stats) ...
///     tx.commit();                       // every output renamed into place
///
/// Each output's temp file, ".NAME.tmp-TOKEN.EXT" beside its target, is made when the output is
/// declared, with open(O_CREAT | O_EXCL | O_NOFOLLOW): TOKEN is random (80 bits, one per
/// transaction, so that the temp names of numbered frames still form a pattern; a name that is
/// taken is never opened, another random one is tried). Writing reopens it without following
/// links and checks it is still the file made. A file replaced keeps its permission bits; a new
/// file gets 0666 less the umask.
///
/// Destroyed without commit() (an exception, an error), it removes its temp files and the
/// directories it created. A target that is a symbolic link is written through: the temp file
/// goes beside the link's final target and replaces that, the link stays. A target that exists
/// and is not a regular file (/dev/null, /dev/stdout, a FIFO) cannot be replaced by a rename:
/// it is written directly, at write time.
/// The most files all transactions of a process may have pending at once (the signal handler
/// removes them from a fixed table): a command that would declare more refuses before its work.
inline constexpr int kMaxPendingOutputs = 1 << 16;

class OutputTransaction {
 public:
  OutputTransaction();
  ~OutputTransaction();
  OutputTransaction(const OutputTransaction&) = delete;
  OutputTransaction& operator=(const OutputTransaction&) = delete;

  /// The transaction the library's writers of this thread stage into (the innermost living
  /// one), or nullptr.
  static OutputTransaction* active();

  /// Declares the output `path` (set by `flag`, named in messages) before any work and makes its
  /// temp file. Throws IoError (bad input) when it cannot be created (no such directory, not
  /// writable, a directory, its temp file cannot be made) and InvalidArgument when an output
  /// declared before names the same file, by any spelling (./a.png, a symbolic link to it, a hard
  /// link). Throws Error when more outputs are pending in the process than the signal clean-up can
  /// hold (65,536).
  void declare(const std::string& path, const std::string& flag);

  /// Writes the output `path` (declared now if it was not) through `write` into its temp file.
  /// Throws WriteError when writing fails (disk full, I/O error); an exception of `write`
  /// propagates. Each output is written once.
  void write(const std::string& path, const std::function<void(std::ostream&)>& write);

  /// The temp file the declared output `path` is staged in (its target itself when written
  /// directly), e.g. for another program to read before commit().
  std::string temp_path(const std::string& path) const;

  /// The temp file of the declared output `path`, for another program to write (ffmpeg); it
  /// must not be empty at commit(). Its name keeps the target's extension.
  std::string external_temp_path(const std::string& path);

  /// Creates `dir` and its missing parents; those it created are removed again (when empty) if
  /// the transaction does not commit. Throws IoError when that fails.
  void create_directories(const std::string& dir);

  /// Removes `path` at commit(), after every output is in place (an earlier run's stale file).
  /// Throws IoError now when it could not be removed (a directory, a directory that is not
  /// writable, another user's file under a sticky bit, an immutable file), and commit() checks
  /// again before its first rename: a commit either finishes or changes nothing.
  void remove_on_commit(const std::string& path);

  /// Renames every output into place and removes the files given to remove_on_commit. Throws
  /// WriteError when an output was not written, its temp file was replaced by another file
  /// (a directory others can write to) or a rename fails; the outputs not yet renamed
  /// are then removed (those renamed before stay: renames in place do not fail but when the
  /// directory was changed under the command).
  void commit();

  /// True once commit() succeeded.
  bool committed() const { return committed_; }

 private:
  struct Output;
  void roll_back() noexcept;
  Output& find_or_declare(const std::string& path);
  static bool external_output_exists(const Output& o);
  static void finish_external_output(const Output& o);

  std::vector<Output> outputs_;
  // Which output has a file: by its path as given, its canonical path and (when it exists) its
  // device and inode.
  std::map<std::string, size_t> by_path_;
  std::map<std::string, size_t> by_name_;
  std::map<std::pair<unsigned long long, unsigned long long>, size_t> by_inode_;
  std::vector<std::string> made_dirs_;  // in the order made: parents first
  std::vector<int> dir_slots_;          // their signal clean-up slots
  std::vector<std::string> remove_at_commit_;
  std::string token_;  // the random part of this transaction's temp names
  bool committed_ = false;
  OutputTransaction* outer_;
};

/// Makes SIGINT, SIGTERM, SIGHUP, SIGQUIT and SIGPIPE remove the temp files and new directories
/// of every pending transaction of the process, then end it with the signal's default action
/// (exit status 128 + signal); SIGXFSZ (a write beyond `ulimit -f`) is ignored, so the write
/// fails with a message instead of ending the process silently. The handler only calls
/// async-signal-safe functions (unlink, rmdir, sigaction, raise) on paths registered before.
/// Signals set to be ignored stay ignored. For programs (the CLI, the viewer); a library embedded
/// elsewhere (the Python module) leaves the signals to its host, and its transactions clean up when
/// the host's interrupt unwinds them.
void remove_pending_outputs_on_signals();

}  // namespace zeroset
