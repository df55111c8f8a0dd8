// The outputs of `zeroset` under a hostile but fair user: two outputs naming one file, symbolic
// links, links planted at temp names in a shared directory, a full disk, SIGINT and SIGTERM in
// the middle of a long run, animations rerun with fewer frames or interrupted, two runs writing
// one file. Every run leaves each target whole (old or new) and no temp file.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <string>
#include <thread>
#include <vector>

#include "cli/cli_support.h"
#include "zeroset/io/image.h"

namespace zeroset {
namespace {

namespace fs = std::filesystem;
using test::fresh_dir;
using test::run_command;
using test::zs;

/// Every file under `dir` (relative names) with its bytes.
std::map<std::string, std::string> contents(const std::string& dir) {
  std::map<std::string, std::string> out;
  if (!fs::is_directory(dir)) return out;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    std::string bytes;
    if (e.is_regular_file()) {
      std::ifstream in(e.path(), std::ios::binary);
      bytes.assign(std::istreambuf_iterator<char>(in), {});
    }
    out[e.path().lexically_relative(dir).string()] = bytes;
  }
  return out;
}

bool has_temp_file(const std::string& dir) {
  for (const auto& [name, bytes] : contents(dir))
    if (name.find(".tmp-") != std::string::npos) return true;
  return false;
}

/// A temp file with bytes in it: an output written and waiting for the commit. (Temp files are
/// made empty when the outputs are declared, before any work.)
bool has_staged_file(const std::string& dir) {
  for (const auto& [name, bytes] : contents(dir))
    if (name.find(".tmp-") != std::string::npos && !bytes.empty()) return true;
  return false;
}

unsigned mode_of(const std::string& path) {
  struct stat st {};
  return ::lstat(path.c_str(), &st) == 0 ? static_cast<unsigned>(st.st_mode & 07777) : ~0u;
}

void put(const std::string& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

/// Starts `zeroset args...` with the default signal actions, no core files and, when
/// `file_limit` > 0, that limit on the size of the files it writes (ulimit -f), output into
/// `log`.
pid_t spawn(const std::vector<std::string>& args, const std::string& log, rlim_t file_limit = 0) {
  const pid_t pid = ::fork();
  if (pid != 0) return pid;
  for (const int sig : {SIGINT, SIGTERM, SIGHUP, SIGQUIT, SIGPIPE, SIGXFSZ}) ::signal(sig, SIG_DFL);
  const struct rlimit no_core { 0, 0 };  // SIGQUIT's default action dumps core
  ::setrlimit(RLIMIT_CORE, &no_core);
  if (file_limit > 0) {
    const struct rlimit limit { file_limit, file_limit };
    ::setrlimit(RLIMIT_FSIZE, &limit);
  }
  const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  ::dup2(fd, 1);
  ::dup2(fd, 2);
  std::vector<char*> argv{const_cast<char*>(ZEROSET_BINARY)};
  for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  ::execv(ZEROSET_BINARY, argv.data());
  ::_exit(127);
}

/// Waits for `pid`; its status as a shell gives it (128 + signal when a signal ended it).
int wait_status(pid_t pid) {
  int status = 0;
  ::waitpid(pid, &status, 0);
  return WIFSIGNALED(status) ? 128 + WTERMSIG(status) : WEXITSTATUS(status);
}

/// Polls `ready` every millisecond for up to a minute while `pid` runs; false when it ended or
/// the minute passed first.
bool wait_until(pid_t pid, const std::function<bool()>& ready) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (std::chrono::steady_clock::now() < end) {
    if (ready()) return true;
    int status = 0;
    if (::waitpid(pid, &status, WNOHANG) == pid) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return false;
}

// ---- outputs naming one file ------------------------------------------------------------------

TEST(HostileOutputs, TwoOutputsNamingOneFileAreRefusedBeforeAnyWork) {
  const std::string d = fresh_dir("hostile-same-file");
  fs::create_directories(d + "/sub");
  fs::create_symlink("m.obj", d + "/m.json");  // dangling: m.obj does not exist yet
  fs::create_symlink("p.png", d + "/p.json");
  const std::vector<std::string> cases = {
      "render sphere --size 16x16 -o " + d + "/a.png --stats " + d + "/a.png",
      "render sphere --size 16x16 -o " + d + "/a.png --stats " + d + "/./a.png",
      "render sphere --size 16x16 -o " + d + "/a.png --stats " + d + "/sub/../a.png",
      "mesh sphere -r 8 -o " + d + "/m.obj --stats " + d + "/m.json",
      "sample sphere --steps 2 --png " + d + "/p.png --stats " + d + "/p.json",
      "mesh sphere -r 8 --png " + d + "/q.png --png-raw " + d + "/q.png"};
  for (const std::string& args : cases) {
    const auto r = run_command(zs(args));
    EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.output;
    EXPECT_NE(r.output.find("same file"), std::string::npos) << args << "\n" << r.output;
    EXPECT_EQ(r.output.find("wrote"), std::string::npos) << args << "\n" << r.output;
  }
  EXPECT_EQ(contents(d).size(), 3u);  // sub and the two links, nothing written
  EXPECT_TRUE(fs::is_symlink(d + "/m.json"));
}

TEST(HostileOutputs, NamesTooLongAndTooManyFramesAreRefusedBeforeAnyWork) {
  const std::string d = fresh_dir("hostile-limits");
  const std::string long_name = d + "/" + std::string(256, 'a');
  const std::vector<std::string> cases = {
      "mesh kummer -r 96 -o " + long_name + ".obj",
      "render kummer --size 64x64 -o " + long_name + ".png",
      "mesh sphere -r 8 -o " + d + "/ok.obj --stats " + long_name + ".json",
      // Every frame is a pending file of the run's one transaction.
      "animate kummer --param mu=1:2 --frames 70000 --size 8x8 -o " + d + "/frames"};
  for (const std::string& args : cases) {
    const auto start = std::chrono::steady_clock::now();
    const auto r = run_command(zs(args));
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.output;
    EXPECT_TRUE(r.output.find("bytes long") != std::string::npos ||
                r.output.find("at most 65535 frames") != std::string::npos)
        << args << "\n"
        << r.output;
    EXPECT_LT(seconds, 5) << args;  // refused, not attempted
  }
  EXPECT_TRUE(contents(d).empty());
}

// ---- symbolic links ---------------------------------------------------------------------------

TEST(HostileOutputs, AnOutputThroughASymbolicLinkReplacesItsTargetAndTheLinkStays) {
  const std::string d = fresh_dir("hostile-symlink");
  fs::create_directories(d + "/store");
  put(d + "/store/a.png", "not yet a picture");
  fs::create_symlink("store/a.png", d + "/a.png");
  fs::create_symlink(d + "/store/b.json", d + "/b.json");  // absolute and dangling
  const auto r = run_command(
      zs("render sphere --size 24x16 --aa 1 -o " + d + "/a.png --stats " + d + "/b.json"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(fs::is_symlink(d + "/a.png"));
  EXPECT_TRUE(fs::is_symlink(d + "/b.json"));
  const Image img = read_image(d + "/store/a.png");
  EXPECT_EQ(img.width, 24);
  EXPECT_EQ(img.height, 16);
  EXPECT_NE(contents(d).at("store/b.json").find("\"rays\""), std::string::npos);
  EXPECT_FALSE(has_temp_file(d));
}

// ---- temp files in a shared directory -------------------------------------------------------

/// A shell command that, in `dir`, plants symbolic links to `victim` at the temp names the
/// outputs `names` (relative to `dir`) used to take, ".STEM.tmp-PID-ID.EXT" for the IDs 0 to 7
/// and the shell's PID, then becomes `zeroset args` (exec keeps the PID).
std::string with_planted_links(const std::string& dir, const std::vector<std::string>& names,
                               const std::string& victim, const std::string& args) {
  std::string cmd = "cd '" + dir + "' && for i in 0 1 2 3 4 5 6 7; do";
  for (const std::string& name : names) {
    const fs::path p(name);
    const std::string head = (p.parent_path() / ("." + p.stem().string())).string();
    cmd += " ln -s '" + victim + "' '" + head + ".tmp-'$$-$i'" + p.extension().string() + "' &&";
  }
  return cmd + " :; done && exec " + zs(args);
}

TEST(HostileOutputs, ALinkPlantedAtATempNameRedirectsNoOutput) {
  const std::string d = fresh_dir("hostile-planted-links");
  const std::string victim = d + "/victim.txt";
  put(victim, "precious");
  fs::create_directories(d + "/frames");
  const std::vector<std::pair<std::string, std::vector<std::string>>> cases = {
      {"mesh sphere -r 8 -o " + d + "/m.obj", {"m.obj"}},
      {"render sphere --size 16x16 --aa 1 -o " + d + "/a.png --stats " + d + "/a.json",
       {"a.png", "a.json"}},
      {"sample sphere --max-count 50 --steps 2 -o " + d + "/s.ply", {"s.ply"}},
      {"animate torus --param r=0.2:0.9 --size 16x16 --aa 1 --no-video --frames 2 -o " + d +
           "/frames",
       {"frames/frame_0000.png", "frames/frame_0001.png"}}};
  size_t planted = 0;
  for (const auto& [args, outputs] : cases) {
    const auto r = run_command(with_planted_links(d, outputs, victim, "-q " + args));
    ASSERT_EQ(r.exit_code, 0) << args << "\n" << r.output;
    planted += 8 * outputs.size();
    EXPECT_EQ(contents(d).at("victim.txt"), "precious") << args;
    for (const std::string& out : outputs) {
      EXPECT_TRUE(fs::is_regular_file(fs::symlink_status(d + "/" + out))) << out;
      EXPECT_FALSE(contents(d).at(out).empty()) << out;
    }
  }
  // The planted links are all there, still links; no other temp name is left.
  size_t links = 0;
  for (const auto& [name, bytes] : contents(d)) {
    if (name.find(".tmp-") == std::string::npos) continue;
    EXPECT_TRUE(fs::is_symlink(d + "/" + name)) << name;
    ++links;
  }
  EXPECT_EQ(links, planted);
  EXPECT_FALSE(fs::is_symlink(d + "/m.obj"));
}

TEST(HostileOutputs, AReplacedOutputKeepsItsPermissionBits) {
  const std::string d = fresh_dir("hostile-modes");
  put(d + "/m.obj", "old mesh");
  fs::permissions(d + "/m.obj", static_cast<fs::perms>(0600));
  put(d + "/a.png", "old picture");
  fs::permissions(d + "/a.png", static_cast<fs::perms>(0640));
  auto r =
      run_command("umask 022 && exec " + zs("-q mesh sphere -r 8 -o " + d + "/m.obj --png " + d +
                                            "/a.png --size 16x16 --stats " + d + "/new.json"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(contents(d).at("m.obj"), "old mesh");
  EXPECT_EQ(mode_of(d + "/m.obj"), 0600u);
  EXPECT_EQ(mode_of(d + "/a.png"), 0640u);
  // A new file gets the usual mode: 0666 less the umask.
  EXPECT_EQ(mode_of(d + "/new.json"), 0644u);
  r = run_command("umask 027 && exec " + zs("-q render sphere --size 16x16 -o " + d + "/b.png"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(mode_of(d + "/b.png"), 0640u);
}

TEST(HostileOutputs, TwoRunsWritingOneOutputAtOnceDoNotCollide) {
  const std::string d = fresh_dir("hostile-two-runs");
  const std::vector<std::string> args = {"-q", "mesh", "sphere", "-r", "12", "-o", d + "/m.obj"};
  for (int round = 0; round < 3; ++round) {
    const pid_t a = spawn(args, d + "/../hostile-two-runs-a.log");
    const pid_t b = spawn(args, d + "/../hostile-two-runs-b.log");
    ASSERT_GT(a, 0);
    ASSERT_GT(b, 0);
    EXPECT_EQ(wait_status(a), 0);
    EXPECT_EQ(wait_status(b), 0);
  }
  auto r = run_command(zs("-q mesh sphere -r 12 -o " + d + "/ref.obj"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto files = contents(d);
  EXPECT_EQ(files.size(), 2u);  // m.obj and ref.obj: no temp file
  EXPECT_EQ(files.at("m.obj"), files.at("ref.obj"));
}

// ---- failing writes and bad paths ------------------------------------------------------------

TEST(HostileOutputs, AFullDiskIsAFailureAndTheEarlierOutputsAreNotWritten) {
  if (!fs::exists("/dev/full")) GTEST_SKIP() << "no /dev/full";
  const std::string d = fresh_dir("hostile-full");
  auto r = run_command(zs("render sphere --size 16x16 -o " + d + "/x.png --stats /dev/full"));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("'/dev/full': write failed"), std::string::npos) << r.output;
  EXPECT_TRUE(contents(d).empty());
  // An old file stays as it was.
  put(d + "/x.png", "old");
  r = run_command(zs("render sphere --size 16x16 -o " + d + "/x.png --stats /dev/full"));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_EQ(contents(d), (std::map<std::string, std::string>{{"x.png", "old"}}));
  EXPECT_TRUE(fs::is_character_file("/dev/full"));
  // A device that takes the bytes is written in place, not replaced.
  r = run_command(zs("render sphere --size 16x16 -o " + d + "/y.png --stats /dev/null"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(fs::is_character_file("/dev/null"));
}

TEST(HostileOutputs, StandardOutputOnAFullDiskIsAFailure) {
  if (!fs::exists("/dev/full")) GTEST_SKIP() << "no /dev/full";
  for (const char* args :
       {"list", "eval sphere --at 1,0,0", "completion bash", "info sphere", "info kummer --json"}) {
    // Standard output to the full device, its errors to the test (the group's 2>&1).
    const auto r = run_command("{ " + zs(args) + " > /dev/full; }");
    EXPECT_EQ(r.exit_code, 1) << args << "\n" << r.output;
    // The reason is known when the last write failed (an earlier failed flush of a long
    // output, as the completion script's, leaves only the stream's error flag).
    EXPECT_TRUE(r.output.find("writing standard output failed") != std::string::npos ||
                r.output.find("No space left on device") != std::string::npos)
        << args << "\n"
        << r.output;
    EXPECT_EQ(run_command(zs(args) + " > /dev/null").exit_code, 0) << args;
  }
}

TEST(HostileOutputs, TheViewersScreenshotAndStatsNamingOneFileAreRefused) {
#if !defined(ZEROSET_HAVE_VIEWER)
  GTEST_SKIP() << "built without the viewer";
#endif
  const std::string d = fresh_dir("hostile-view-same");
  for (const std::string& stats : {d + "/same.png", d + "/./same.png"}) {
    const auto r = run_command(
        zs("view kummer --frames 2 --screenshot " + d + "/same.png --stats-out " + stats));
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find("--stats-out"), std::string::npos) << r.output;
    EXPECT_TRUE(contents(d).empty()) << r.output;
  }
}

TEST(HostileOutputs, AnOutputPathWrongBeforeAnyWorkIsBadInput) {
  const std::string d = fresh_dir("hostile-bad-path");
  for (const std::string& args :
       {"render sphere -o " + d + "/none/x.png", "render sphere -o " + d + "/x.png --stats " + d,
        "mesh sphere -o " + d + "/x.obj --stats " + d + "/none/s.json",
        "sample sphere -o " + d + "/none/s.ply"}) {
    const auto r = run_command(zs(args));
    EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.output;
    EXPECT_NE(r.output.find("error: '"), std::string::npos) << args << "\n" << r.output;
  }
  EXPECT_TRUE(contents(d).empty());
}

// ---- signals ----------------------------------------------------------------------------------

/// Runs `args` with an old `target` in `d`; sends `sig` once `ready` holds (or, without it,
/// after half a second); expects the process ended by the signal, no temp file and `d` as
/// it was.
void expect_interrupted_cleanly(const std::string& d, const std::vector<std::string>& args, int sig,
                                const std::function<bool()>& ready = {}) {
  const std::map<std::string, std::string> before = contents(d);
  const std::string log = d + ".log";
  const pid_t pid = spawn(args, log);
  ASSERT_GT(pid, 0);
  if (ready) {
    ASSERT_TRUE(wait_until(pid, ready)) << "the moment to interrupt never came";
  } else {
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
  }
  ::kill(pid, sig);
  const int status = wait_status(pid);
  std::ifstream in(log);
  const std::string output{std::istreambuf_iterator<char>(in), {}};
  EXPECT_EQ(status, 128 + sig) << output;
  EXPECT_FALSE(has_temp_file(d));
  EXPECT_EQ(contents(d), before) << output;
}

TEST(HostileOutputs, SignalsDuringALongRenderLeaveTheOldPicture) {
  const std::string d = fresh_dir("hostile-signal-render");
  put(d + "/a.png", "old picture");
  for (const int sig : {SIGINT, SIGTERM, SIGHUP, SIGQUIT, SIGPIPE})
    expect_interrupted_cleanly(d,
                               {"render", "kummer", "--size", "3000x3000", "--aa", "3", "-o",
                                d + "/a.png", "--stats", d + "/a.json"},
                               sig);
}

TEST(HostileOutputs, ASignalWhileAMeshIsStagedRemovesIt) {
  // The mesh is staged before the --png picture is drawn: the signal comes while its temp file
  // holds it.
  const std::string d = fresh_dir("hostile-signal-mesh");
  put(d + "/m.obj", "old mesh");
  const auto staged = [&] { return has_staged_file(d); };
  for (const int sig : {SIGINT, SIGTERM, SIGHUP, SIGQUIT, SIGPIPE})
    expect_interrupted_cleanly(d,
                               {"mesh", "sphere", "-r", "24", "--improve", "off", "-o",
                                d + "/m.obj", "--png", d + "/m.png", "--size", "4000x4000"},
                               sig, staged);
}

TEST(HostileOutputs, AFileSizeLimitIsAnErrorThatLeavesTheOldFile) {
  // ulimit -f: the write fails with "File too large" instead of SIGXFSZ ending the process
  // silently with a temp file left behind.
  const std::string d = fresh_dir("hostile-file-size");
  put(d + "/m.obj", "old mesh");
  const std::map<std::string, std::string> before = contents(d);
  const std::string log = d + ".log";
  const pid_t pid =
      spawn({"mesh", "sphere", "-r", "32", "--improve", "off", "-o", d + "/m.obj"}, log, 16 * 1024);
  ASSERT_GT(pid, 0);
  const int status = wait_status(pid);
  std::ifstream in(log);
  const std::string output{std::istreambuf_iterator<char>(in), {}};
  EXPECT_NE(status, 0) << output;
  EXPECT_LT(status, 128) << "ended by a signal: " << output;
  EXPECT_NE(output.find("File too large"), std::string::npos) << output;
  EXPECT_FALSE(has_temp_file(d));
  EXPECT_EQ(contents(d), before) << output;
}

TEST(HostileOutputs, ASignalWhileFloatersAreStagedRemovesThem) {
  const std::string d = fresh_dir("hostile-signal-sample");
  const auto staged = [&] { return has_staged_file(d); };
  expect_interrupted_cleanly(d,
                             {"sample", "sphere", "--max-count", "200", "--steps", "5", "-o",
                              d + "/s.ply", "--png", d + "/s.png", "--size", "4000x4000"},
                             SIGTERM, staged);
}

// ---- animations -------------------------------------------------------------------------------

const std::vector<std::string> kAnimate = {"animate", "torus", "--param", "r=0.2:0.9", "--size",
                                           "40x32",   "--aa",  "1",       "--no-video"};

std::string animate(const std::string& extra) {
  return zs("animate torus --param r=0.2:0.9 --size 40x32 --aa 1 --no-video " + extra);
}

// A stale frame that cannot be removed is refused before any work: the run changes nothing,
// rather than replacing the frames and then failing.
TEST(HostileOutputs, AStaleFrameThatCannotBeRemovedIsRefusedBeforeAnyWork) {
  const std::string d = fresh_dir("hostile-animate-stuck");
  for (int f = 0; f < 5; ++f) put(d + "/frame_000" + std::to_string(f) + ".png", "old frame");
  const std::string stuck = d + "/frame_0004.png";
  if (run_command("chattr +i " + stuck + " 2>&1").exit_code != 0)
    GTEST_SKIP() << "chattr +i is not permitted here";
  const std::map<std::string, std::string> before = contents(d);
  const auto r = run_command(animate("--frames 3 -o " + d));
  run_command("chattr -i " + stuck);
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("frame_0004.png"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("immutable"), std::string::npos) << r.output;
  EXPECT_EQ(contents(d), before) << "the run changed the directory";
  EXPECT_FALSE(has_temp_file(d));
}

// ... nor a stale video: an earlier run's DIR/animation.mp4 goes when this run writes none.
TEST(HostileOutputs, ASecondAnimationWithFewerFramesLeavesNoStaleFrame) {
  const std::string d = fresh_dir("hostile-animate-fewer");
  put(d + "/notes.txt", "mine");
  put(d + "/frame_12.png", "not the command's pattern");
  auto r = run_command(animate("--frames 6 -o " + d));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  put(d + "/animation.mp4", "an earlier run's video");
  r = run_command(animate("--frames 3 -o " + d));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("removed " + d + "/animation.mp4"), std::string::npos) << r.output;
  std::vector<std::string> names;
  for (const auto& [name, bytes] : contents(d)) names.push_back(name);
  EXPECT_EQ(names, (std::vector<std::string>{"frame_0000.png", "frame_0001.png", "frame_0002.png",
                                             "frame_12.png", "notes.txt"}));
  // A part of a 4-frame animation keeps the other parts' frames and removes frames 4 and up.
  put(d + "/frame_0005.png", "stale");
  r = run_command(animate("--frames 4 --frame-range 3 -o " + d));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  names.clear();
  for (const auto& [name, bytes] : contents(d)) names.push_back(name);
  EXPECT_EQ(names, (std::vector<std::string>{"frame_0000.png", "frame_0001.png", "frame_0002.png",
                                             "frame_0003.png", "frame_12.png", "notes.txt"}));
}

TEST(HostileOutputs, AnInterruptedAnimationLeavesTheDirectoryAsItWas) {
  const std::string root = fresh_dir("hostile-animate-signal");
  const std::string d = root + "/frames";
  auto r = run_command(animate("--frames 3 -o " + d));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  // Interrupted once some of its 400 frames are staged: the old 3 frames, byte for byte.
  std::vector<std::string> args = kAnimate;
  for (const char* a : {"--frames", "400", "-o"}) args.push_back(a);
  args.push_back(d);
  const auto staged = [&] { return has_staged_file(d); };
  for (const int sig : {SIGINT, SIGTERM}) expect_interrupted_cleanly(d, args, sig, staged);
  // A directory the run made is removed again.
  const std::string fresh = root + "/new/frames";
  args.back() = fresh;
  fs::create_directories(root + "/new");
  expect_interrupted_cleanly(root + "/new", args, SIGTERM, [&] { return has_staged_file(fresh); });
  EXPECT_FALSE(fs::exists(fresh));
}

}  // namespace
}  // namespace zeroset
