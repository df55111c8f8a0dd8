// One transaction for a command's outputs: all or nothing, same files refused, symbolic links
// written through, write failures told apart from bad paths, temp files gone after a signal.
#include "zeroset/io/output_transaction.h"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <stdexcept>

#include "support/scratch_dir.h"
#include "zeroset/error.h"
#include "zeroset/io/atomic_file.h"

namespace zeroset {
namespace {

namespace fs = std::filesystem;

class OutputTransactionTest : public test::ScratchDirTest {
 protected:
  /// Every name in `d` (recursively, relative), temp files included.
  std::set<std::string> files(const fs::path& d = {}) const {
    std::set<std::string> names;
    const fs::path root = d.empty() ? dir_ : d;
    for (const auto& e : fs::recursive_directory_iterator(root))
      names.insert(e.path().lexically_relative(root).string());
    return names;
  }
  static auto writes(const std::string& text) {
    return [text](std::ostream& out) { out << text; };
  }
};

TEST_F(OutputTransactionTest, OutputsAppearTogetherAtCommit) {
  put(path("a.txt"), "old a");
  {
    OutputTransaction tx;
    tx.declare(path("a.txt"), "-o");
    tx.declare(path("b.txt"), "--stats");
    write_file_atomically(path("a.txt"), writes("new a"));  // the library's writers stage
    EXPECT_EQ(text_of(path("a.txt")), "old a");
    tx.write(path("b.txt"), writes("b"));
    EXPECT_FALSE(fs::exists(path("b.txt")));
    EXPECT_EQ(files().size(), 3u);  // a.txt and two temp files
    tx.commit();
  }
  EXPECT_EQ(files(), (std::set<std::string>{"a.txt", "b.txt"}));
  EXPECT_EQ(text_of(path("a.txt")), "new a");
  EXPECT_EQ(text_of(path("b.txt")), "b");
}

TEST_F(OutputTransactionTest, AnErrorBeforeCommitLeavesEveryTargetAsItWas) {
  put(path("a.txt"), "old a");
  try {
    OutputTransaction tx;
    tx.declare(path("a.txt"), "-o");
    tx.declare(path("b.txt"), "--stats");
    tx.write(path("a.txt"), writes("new a"));
    tx.write(path("b.txt"), [](std::ostream& out) {
      out << "half";
      throw std::runtime_error("the work failed");
    });
    tx.commit();
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "the work failed");
  }
  EXPECT_EQ(files(), (std::set<std::string>{"a.txt"}));
  EXPECT_EQ(text_of(path("a.txt")), "old a");
}

TEST_F(OutputTransactionTest, ADeclaredOutputNeverWrittenFailsTheCommitAndWritesNothing) {
  {
    OutputTransaction tx;
    tx.declare(path("a.txt"), "-o");
    tx.declare(path("b.txt"), "--png");
    tx.write(path("a.txt"), writes("a"));
    EXPECT_THROW(tx.commit(), WriteError);
  }
  EXPECT_TRUE(files().empty());
}

TEST_F(OutputTransactionTest, TwoOutputsNamingOneFileAreRefusedBySpelling) {
  fs::create_directories(path("sub"));
  put(path("real.png"), "x");
  fs::create_symlink("real.png", path("link.png"));
  fs::create_hard_link(path("real.png"), path("hard.png"));
  const std::string same[][2] = {{path("a.png"), path("a.png")},
                                 {path("a.png"), path("./a.png")},
                                 {path("a.png"), path("sub/../a.png")},
                                 {path("real.png"), path("link.png")},
                                 {path("real.png"), path("hard.png")}};
  for (const auto& [first, second] : same) {
    OutputTransaction tx;
    tx.declare(first, "-o");
    try {
      tx.declare(second, "--stats");
      ADD_FAILURE() << first << " and " << second << " were both accepted";
    } catch (const InvalidArgument& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("same file"), std::string::npos) << what;
      EXPECT_NE(what.find("--stats"), std::string::npos) << what;
      EXPECT_NE(what.find("-o"), std::string::npos) << what;
    }
  }
  // Relative spellings, as a command line gives them.
  const fs::path cwd = fs::current_path();
  fs::current_path(dir_);
  for (const auto& [first, second] :
       {std::pair{"a.png", "./a.png"}, std::pair{"a.png", "sub/../a.png"},
        std::pair{"real.png", "link.png"}}) {
    OutputTransaction tx;
    tx.declare(first, "-o");
    EXPECT_THROW(tx.declare(second, "--stats"), InvalidArgument) << first << " " << second;
  }
  fs::current_path(cwd);
  EXPECT_EQ(files(), (std::set<std::string>{"sub", "real.png", "link.png", "hard.png"}));
  // Different files in one directory are fine.
  OutputTransaction tx;
  tx.declare(path("a.png"), "-o");
  EXPECT_NO_THROW(tx.declare(path("a.json"), "--stats"));
}

TEST_F(OutputTransactionTest, ASymbolicLinkIsWrittenThroughAndStaysALink) {
  fs::create_directories(path("elsewhere"));
  put(path("elsewhere/real.txt"), "old");
  fs::create_symlink("elsewhere/real.txt", path("link.txt"));
  fs::create_symlink("link.txt", path("link2.txt"));              // a chain
  fs::create_symlink("elsewhere/new.txt", path("dangling.txt"));  // its target does not exist yet
  write_file_atomically(path("link2.txt"), writes("new"));
  write_file_atomically(path("dangling.txt"), writes("made"));
  EXPECT_TRUE(fs::is_symlink(path("link.txt")));
  EXPECT_TRUE(fs::is_symlink(path("link2.txt")));
  EXPECT_TRUE(fs::is_symlink(path("dangling.txt")));
  EXPECT_EQ(text_of(path("elsewhere/real.txt")), "new");
  EXPECT_EQ(text_of(path("elsewhere/new.txt")), "made");
  EXPECT_EQ(files(), (std::set<std::string>{"elsewhere", "elsewhere/real.txt", "elsewhere/new.txt",
                                            "link.txt", "link2.txt", "dangling.txt"}));
  // A link into a directory that does not exist is a bad path, found before any work.
  fs::create_symlink("nowhere/x.txt", path("bad.txt"));
  OutputTransaction tx;
  EXPECT_THROW(tx.declare(path("bad.txt"), "-o"), IoError);
}

TEST_F(OutputTransactionTest, BadPathsAreBadInputAndWriteFailuresAreNot) {
  OutputTransaction tx;
  EXPECT_THROW(tx.declare(path("missing/a.txt"), "-o"), IoError);
  EXPECT_THROW(tx.declare(dir_.string(), "-o"), IoError);
  EXPECT_THROW(tx.declare("", "-o"), IoError);
  static_assert(std::is_base_of_v<BadInput, IoError>);
  static_assert(!std::is_base_of_v<BadInput, WriteError>);
  static_assert(std::is_base_of_v<Error, WriteError>);
  if (!fs::exists("/dev/full")) GTEST_SKIP() << "no /dev/full";
  // A device is written in place (a rename would replace it); a full disk is a WriteError.
  tx.declare(path("a.txt"), "-o");
  tx.declare("/dev/full", "--stats");
  tx.write(path("a.txt"), writes("a"));
  try {
    tx.write("/dev/full", writes(std::string(1 << 16, 'x')));
    FAIL() << "writing to /dev/full succeeded";
  } catch (const WriteError& e) {
    EXPECT_NE(std::string(e.what()).find("'/dev/full': write failed"), std::string::npos)
        << e.what();
  }
  EXPECT_TRUE(fs::is_character_file("/dev/full"));
}

TEST_F(OutputTransactionTest, DirectoriesItMadeAreRemovedUnlessItCommits) {
  put(path("keep.txt"), "k");
  {
    OutputTransaction tx;
    tx.create_directories(path("a/b/c"));
    tx.declare(path("a/b/c/f.txt"), "-o");
    tx.write(path("a/b/c/f.txt"), writes("f"));
  }
  EXPECT_EQ(files(), (std::set<std::string>{"keep.txt"}));
  {
    OutputTransaction tx;
    tx.create_directories(path("a/b"));
    tx.declare(path("a/b/f.txt"), "-o");
    tx.write(path("a/b/f.txt"), writes("f"));
    tx.commit();
  }
  EXPECT_EQ(files(), (std::set<std::string>{"keep.txt", "a", "a/b", "a/b/f.txt"}));
  OutputTransaction tx;
  EXPECT_THROW(tx.create_directories(path("keep.txt/x")), IoError);
}

TEST_F(OutputTransactionTest, FilesToRemoveGoOnlyAtCommit) {
  put(path("stale.txt"), "s");
  {
    OutputTransaction tx;
    tx.remove_on_commit(path("stale.txt"));
  }
  EXPECT_TRUE(fs::exists(path("stale.txt")));
  OutputTransaction tx;
  tx.remove_on_commit(path("stale.txt"));
  tx.commit();
  EXPECT_FALSE(fs::exists(path("stale.txt")));
}

TEST_F(OutputTransactionTest, ASignalRemovesThePendingTempFilesAndEndsTheProcess) {
  for (const int sig : {SIGINT, SIGTERM}) {
    put(path("a.txt"), "old");
    const pid_t child = ::fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
      ::signal(sig, SIG_DFL);
      remove_pending_outputs_on_signals();
      OutputTransaction tx;
      tx.create_directories(path("new/dir"));
      tx.declare(path("a.txt"), "-o");
      tx.declare(path("new/dir/b.txt"), "--stats");
      tx.write(path("a.txt"), writes("new"));
      tx.write(path("new/dir/b.txt"), writes("b"));
      ::raise(sig);
      ::_exit(0);  // not reached
    }
    int status = 0;
    ASSERT_EQ(::waitpid(child, &status, 0), child);
    ASSERT_TRUE(WIFSIGNALED(status)) << "status " << status;
    EXPECT_EQ(WTERMSIG(status), sig);
    EXPECT_EQ(files(), (std::set<std::string>{"a.txt"}));
    EXPECT_EQ(text_of(path("a.txt")), "old");
  }
}

}  // namespace
}  // namespace zeroset
