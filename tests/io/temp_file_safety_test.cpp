// The temp files of the output transaction in a directory others can write to: a symbolic link
// planted at a name the temp file might take redirects nothing, a temp file swapped for another
// file is refused, replaced files keep their permission bits, and transactions writing beside
// each other (in one process, in threads, in two processes) never share a temp file.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "support/scratch_dir.h"
#include "zeroset/error.h"
#include "zeroset/io/atomic_file.h"
#include "zeroset/io/output_transaction.h"

namespace zeroset {
namespace {

namespace fs = std::filesystem;

class TempFileSafetyTest : public test::ScratchDirTest {
 protected:
  static unsigned mode_of(const std::string& p) {
    struct stat st {};
    return ::lstat(p.c_str(), &st) == 0 ? static_cast<unsigned>(st.st_mode & 07777) : ~0u;
  }
  static bool is_plain_file(const std::string& p) {
    return fs::is_regular_file(fs::symlink_status(p));
  }
  /// The names in the directory, links included (not followed).
  std::set<std::string> names() const {
    std::set<std::string> out;
    for (const auto& e : fs::directory_iterator(dir_)) out.insert(e.path().filename().string());
    return out;
  }
  /// Symbolic links to `victim` at the temp names the transaction used to take in this process
  /// (".STEM.tmp-PID-ID.EXT" for the first `ids` IDs) and at other guesses; their names.
  std::set<std::string> plant_links(const std::string& stem, const std::string& ext,
                                    const std::string& victim, int ids) const {
    std::set<std::string> planted;
    const std::string pid = std::to_string(::getpid());
    for (int id = 0; id < ids; ++id)
      planted.insert("." + stem + ".tmp-" + pid + "-" + std::to_string(id) + ext);
    for (const std::string& guess :
         std::vector<std::string>{"0000000000000000", "vvvvvvvvvvvvvvvv", "0", pid})
      planted.insert("." + stem + ".tmp-" + guess + ext);
    for (const std::string& name : planted) fs::create_symlink(victim, path(name));
    return planted;
  }
};

TEST_F(TempFileSafetyTest, ALinkPlantedAtTheOldTempNamesDoesNotRedirectTheWrite) {
  put(path("victim.txt"), "secret");
  std::set<std::string> expected = plant_links("m", ".obj", path("victim.txt"), 500);
  write_file_atomically(path("m.obj"), [](std::ostream& out) { out << "the mesh"; });
  EXPECT_EQ(text_of(path("victim.txt")), "secret");
  EXPECT_TRUE(is_plain_file(path("m.obj")));
  EXPECT_EQ(text_of(path("m.obj")), "the mesh");
  // Every planted link is still there and still a link; nothing else was left behind.
  for (const std::string& name : expected) EXPECT_TRUE(fs::is_symlink(path(name))) << name;
  expected.insert({"victim.txt", "m.obj"});
  EXPECT_EQ(names(), expected);
}

TEST_F(TempFileSafetyTest, ADanglingLinkPlantedInATransactionRedirectsNoOutput) {
  // The links lead to files that do not exist yet: following one would create it.
  std::set<std::string> expected = plant_links("a", ".png", path("made-by-link.png"), 100);
  const std::set<std::string> more = plant_links("a", ".json", path("made-by-link.json"), 100);
  expected.insert(more.begin(), more.end());
  {
    OutputTransaction tx;
    tx.declare(path("a.png"), "-o");
    tx.declare(path("a.json"), "--stats");
    tx.write(path("a.png"), [](std::ostream& out) { out << "png"; });
    tx.write(path("a.json"), [](std::ostream& out) { out << "{}"; });
    tx.commit();
  }
  EXPECT_FALSE(fs::exists(path("made-by-link.png")));
  EXPECT_FALSE(fs::exists(path("made-by-link.json")));
  EXPECT_TRUE(is_plain_file(path("a.png")));
  EXPECT_EQ(text_of(path("a.json")), "{}");
  expected.insert({"a.png", "a.json"});
  EXPECT_EQ(names(), expected);
}

TEST_F(TempFileSafetyTest, TempFilesAreMadeAtDeclareWithRandomNamesSharedByATransaction) {
  OutputTransaction tx1;
  tx1.declare(path("frame_0000.png"), "-o");
  tx1.declare(path("frame_0001.png"), "-o");
  OutputTransaction tx2;
  tx2.declare(path("frame_0000.png"), "-o");
  const std::regex pattern(R"(\.frame_000[01]\.tmp-([0-9a-v]{16})\.png)");
  std::smatch m0, m1, m2;
  const std::string t0 = fs::path(tx1.temp_path(path("frame_0000.png"))).filename().string();
  const std::string t1 = fs::path(tx1.temp_path(path("frame_0001.png"))).filename().string();
  const std::string t2 = fs::path(tx2.temp_path(path("frame_0000.png"))).filename().string();
  ASSERT_TRUE(std::regex_match(t0, m0, pattern)) << t0;
  ASSERT_TRUE(std::regex_match(t1, m1, pattern)) << t1;
  ASSERT_TRUE(std::regex_match(t2, m2, pattern)) << t2;
  // One token per transaction: the frames' temp names form a pattern (ffmpeg reads them so).
  EXPECT_EQ(m0[1], m1[1]);
  EXPECT_NE(m0[1], m2[1]);
  // Made already: an empty regular file.
  for (const std::string& t : {t0, t1, t2}) {
    EXPECT_TRUE(is_plain_file(path(t))) << t;
    EXPECT_EQ(fs::file_size(path(t)), 0u) << t;
  }
}

TEST_F(TempFileSafetyTest, ATempFileSwappedForALinkOrAnotherFileIsRefused) {
  put(path("victim.txt"), "secret");
  for (const bool hard : {false, true}) {
    OutputTransaction tx;
    tx.declare(path("out.txt"), "-o");
    const std::string temp = tx.temp_path(path("out.txt"));
    fs::remove(temp);
    if (hard) {
      fs::create_hard_link(path("victim.txt"), temp);
    } else {
      fs::create_symlink(path("victim.txt"), temp);
    }
    EXPECT_THROW(tx.write(path("out.txt"), [](std::ostream& out) { out << "x"; }), WriteError)
        << (hard ? "hard link" : "symbolic link");
  }
  EXPECT_EQ(text_of(path("victim.txt")), "secret");
  EXPECT_EQ(names(), (std::set<std::string>{"victim.txt"}));
  // Swapped after writing, before the commit: not moved into place.
  {
    OutputTransaction tx;
    tx.declare(path("out.txt"), "-o");
    const std::string temp = tx.temp_path(path("out.txt"));
    tx.write(path("out.txt"), [](std::ostream& out) { out << "x"; });
    fs::remove(temp);
    fs::create_symlink(path("victim.txt"), temp);
    EXPECT_THROW(tx.commit(), WriteError);
  }
  EXPECT_FALSE(fs::exists(fs::symlink_status(path("out.txt"))));
  EXPECT_EQ(names(), (std::set<std::string>{"victim.txt"}));
}

TEST_F(TempFileSafetyTest, AReplacedFileKeepsItsPermissionBits) {
  for (const unsigned mode : {0600u, 0640u, 0604u, 0755u, 0444u}) {  // read-only last
    put(path("f.txt"), "old");
    fs::permissions(path("f.txt"), static_cast<fs::perms>(mode));
    write_file_atomically(path("f.txt"), [](std::ostream& out) { out << "new"; });
    EXPECT_EQ(mode_of(path("f.txt")), mode) << std::oct << mode;
    EXPECT_EQ(text_of(path("f.txt")), "new");
  }
  // Through a symbolic link: its target's bits.
  put(path("real.txt"), "old");
  fs::permissions(path("real.txt"), static_cast<fs::perms>(0600));
  fs::create_symlink("real.txt", path("link.txt"));
  write_file_atomically(path("link.txt"), [](std::ostream& out) { out << "new"; });
  EXPECT_EQ(mode_of(path("real.txt")), 0600u);
  EXPECT_TRUE(fs::is_symlink(path("link.txt")));
  // Written by another program (ffmpeg) into the temp file.
  put(path("v.mp4"), "old");
  fs::permissions(path("v.mp4"), static_cast<fs::perms>(0640));
  {
    OutputTransaction tx;
    tx.declare(path("v.mp4"), "--video");
    std::ofstream(tx.external_temp_path(path("v.mp4")), std::ios::binary) << "video";
    tx.commit();
  }
  EXPECT_EQ(mode_of(path("v.mp4")), 0640u);
  EXPECT_EQ(text_of(path("v.mp4")), "video");
}

TEST_F(TempFileSafetyTest, ANewFileGetsTheUsualModeOfTheUmask) {
  for (const unsigned mask : {022u, 027u, 077u, 0u}) {
    const mode_t old = ::umask(static_cast<mode_t>(mask));
    const std::string p = path("new-" + std::to_string(mask) + ".txt");
    write_file_atomically(p, [](std::ostream& out) { out << "x"; });
    ::umask(old);
    EXPECT_EQ(mode_of(p), 0666u & ~mask) << std::oct << mask;
  }
}

TEST_F(TempFileSafetyTest, AnEmptyFileFromAnotherProgramIsNothingWritten) {
  OutputTransaction tx;
  tx.declare(path("v.mp4"), "--video");
  tx.external_temp_path(path("v.mp4"));  // the program ran and wrote nothing
  EXPECT_THROW(tx.commit(), WriteError);
}

TEST_F(TempFileSafetyTest, ATempFileThatCannotBeMadeIsBadInputAndLeavesNothing) {
  // A name the directory takes but its temp file's name is too long for.
  const std::string long_name = "a." + std::string(240, 'x');
  try {
    OutputTransaction tx;
    tx.declare(path(long_name), "-o");
    FAIL() << "declared";
  } catch (const IoError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(long_name), std::string::npos) << what;
    EXPECT_NE(what.find("cannot create the temp file"), std::string::npos) << what;
    EXPECT_NE(what.find(std::strerror(ENAMETOOLONG)), std::string::npos) << what;
  }
  EXPECT_TRUE(names().empty());
  if (::geteuid() == 0) return;  // root writes where permissions forbid
  // A directory that may be written but not searched.
  fs::create_directories(path("no-search"));
  fs::permissions(path("no-search"), static_cast<fs::perms>(0200));
  OutputTransaction tx;
  EXPECT_THROW(tx.declare(path("no-search/x.txt"), "-o"), IoError);
  fs::permissions(path("no-search"), static_cast<fs::perms>(0700));
  EXPECT_TRUE(fs::is_empty(path("no-search")));
}

TEST_F(TempFileSafetyTest, TwoTransactionsInOneProcessWritingOneFileDoNotCollide) {
  OutputTransaction outer;
  outer.declare(path("a.txt"), "-o");
  {
    OutputTransaction inner;
    inner.declare(path("a.txt"), "-o");
    EXPECT_NE(inner.temp_path(path("a.txt")), outer.temp_path(path("a.txt")));
    inner.write(path("a.txt"), [](std::ostream& out) { out << "inner"; });
    outer.write(path("a.txt"), [](std::ostream& out) { out << "outer"; });
    inner.commit();
  }
  EXPECT_EQ(text_of(path("a.txt")), "inner");
  outer.commit();
  EXPECT_EQ(text_of(path("a.txt")), "outer");
  EXPECT_EQ(names(), (std::set<std::string>{"a.txt"}));
}

/// Writes `path` `rounds` times with `rounds` lines of `letter` each time; false on an error.
bool write_rounds(const std::string& path, char letter, int rounds) {
  try {
    for (int r = 0; r < rounds; ++r)
      write_file_atomically(path, [&](std::ostream& out) {
        for (int line = 0; line < 200; ++line) out << std::string(80, letter) << '\n';
      });
    return true;
  } catch (const std::exception&) {
    return false;
  }
}

bool is_whole_text_of(const std::string& text, char letter) {
  std::string expected;
  for (int line = 0; line < 200; ++line) expected += std::string(80, letter) + '\n';
  return text == expected;
}

TEST_F(TempFileSafetyTest, ThreadsWritingOneFileAtOnceDoNotCollide) {
  bool ok[4] = {};
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t)
    threads.emplace_back([&, t] { ok[t] = write_rounds(path("shared.txt"), char('a' + t), 50); });
  for (std::thread& t : threads) t.join();
  for (int t = 0; t < 4; ++t) EXPECT_TRUE(ok[t]) << t;
  const std::string text = text_of(path("shared.txt"));
  EXPECT_TRUE(is_whole_text_of(text, 'a') || is_whole_text_of(text, 'b') ||
              is_whole_text_of(text, 'c') || is_whole_text_of(text, 'd'));
  EXPECT_EQ(names(), (std::set<std::string>{"shared.txt"}));
}

TEST_F(TempFileSafetyTest, TwoProcessesWritingOneFileAtOnceDoNotCollide) {
  std::vector<pid_t> children;
  for (const char letter : {'p', 'q'}) {
    const pid_t child = ::fork();
    ASSERT_GE(child, 0);
    if (child == 0) ::_exit(write_rounds(path("shared.txt"), letter, 100) ? 0 : 1);
    children.push_back(child);
  }
  for (const pid_t child : children) {
    int status = 0;
    ASSERT_EQ(::waitpid(child, &status, 0), child);
    EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "status " << status;
  }
  const std::string text = text_of(path("shared.txt"));
  EXPECT_TRUE(is_whole_text_of(text, 'p') || is_whole_text_of(text, 'q'));
  EXPECT_EQ(names(), (std::set<std::string>{"shared.txt"}));
}

}  // namespace
}  // namespace zeroset
