// Out of memory as a user meets it: a plan that cannot fit is refused before the work with the
// limit named (exit code 2), memory that runs out during the work (inside parallel regions
// too) ends the command with "out of memory" (exit code 1), never an abort; no partial file.
// The limits are real: `ulimit -v` set in the shell that runs `zeroset`.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "cli/cli_support.h"
#include "support/sanitizers.h"

namespace zeroset {
namespace {

using test::fresh_dir;
using test::run_command;
using test::zs;

// AddressSanitizer reserves terabytes of address space for its shadow memory at start-up, so a
// sanitized `zeroset` cannot start under `ulimit -v` at all: the tests of the process limit
// run in the ordinary build only.
#if ZEROSET_TEST_UNDER_ASAN
#define ZS_SKIP_UNDER_ASAN() GTEST_SKIP() << "AddressSanitizer cannot run under ulimit -v"
#else
#define ZS_SKIP_UNDER_ASAN() (void)0
#endif

// `zeroset ARGS` with the address space limited to `kib` KiB, in `dir`.
test::CommandResult under_limit(long kib, const std::string& dir, const std::string& args) {
  return run_command("cd '" + dir + "' && ulimit -v " + std::to_string(kib) + " && exec " +
                     zs(args));
}

// Files other than `keep` in `dir` (temporary or partial outputs).
int other_files(const std::string& dir, const std::string& keep = "") {
  int n = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir)) n += e.path().filename() != keep;
  return n;
}

// The case of the report: 1500 cells need about 4.5 GB, and ulimit -v 3000000 allows 3 GB.
TEST(HostileFaults, MeshBeyondTheProcessLimitIsRefusedWithTheLimitNamed) {
  ZS_SKIP_UNDER_ASAN();
  const std::string dir = fresh_dir("faults_mesh_limit");
  const auto r = under_limit(3'000'000, dir, "mesh sphere -r 1500 --grid dense -o m.obj");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("the process limit (ulimit -v) allows about 3"), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("use --resolution"), std::string::npos) << r.output;
  EXPECT_EQ(other_files(dir), 0) << r.output;
}

// Threads whose stacks do not fit under the limit (1000 × 8 MiB in 1 GiB): the OpenMP stages
// (mesh, sample) end with a message and exit code 1 instead of libgomp's abort. Fewer threads
// under the same limit work. (The renderer starts at most one thread per tile of the picture,
// std::threads whose failure is an ordinary error.)
TEST(HostileFaults, ThreadsThatCannotStartAreAFailureWithAMessage) {
  ZS_SKIP_UNDER_ASAN();
  const std::string dir = fresh_dir("faults_threads");
  for (const char* args : {"--threads 1000 mesh sphere -r 8 -o m.obj",
                           "--threads 1000 sample sphere --max-count 50 -o f.ply"}) {
    const auto r = under_limit(1'000'000, dir, args);
    EXPECT_EQ(r.exit_code, 1) << args << "\n" << r.output;
    EXPECT_NE(r.output.find("zeroset: error:"), std::string::npos) << args << "\n" << r.output;
    EXPECT_EQ(r.output.find("libgomp"), std::string::npos) << args << "\n" << r.output;
    EXPECT_EQ(other_files(dir), 0) << args << "\n" << r.output;
  }
  const auto ok = under_limit(1'000'000, dir, "--threads 2 mesh sphere -r 8 -o m.obj");
  EXPECT_EQ(ok.exit_code, 0) << ok.output;
}

// The resolution the refusal offers does fit under the same limit.
TEST(HostileFaults, TheOfferedResolutionFits) {
  ZS_SKIP_UNDER_ASAN();
  const std::string dir = fresh_dir("faults_mesh_offer");
  const auto refused =
      under_limit(500'000, dir, "mesh sphere -r 800 --grid dense --improve off -o m.obj");
  ASSERT_EQ(refused.exit_code, 2) << refused.output;
  const auto at = refused.output.find("use --resolution ");
  ASSERT_NE(at, std::string::npos) << refused.output;
  const int offered = std::stoi(refused.output.substr(at + 17));
  EXPECT_GT(offered, 100) << refused.output;
  const auto r = under_limit(
      500'000, dir,
      "mesh sphere -r " + std::to_string(offered) + " --grid dense --improve off -o m.obj");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(std::filesystem::exists(dir + "/m.obj")) << r.output;
}

// Floaters beyond the process limit are refused before the run, like a grid: the limit named,
// a count offered, nothing written; the offered count then runs under the same limit. (The
// capture of std::bad_alloc inside parallel regions is tested on its own in ExceptionTrap.)
TEST(HostileFaults, FloatersBeyondTheProcessLimitAreRefusedWithACountThatFits) {
  ZS_SKIP_UNDER_ASAN();
  const std::string dir = fresh_dir("faults_sample_limit");
  for (const long kib : {500'000L, 1'100'000L}) {
    const auto r = under_limit(
        kib, dir, "sample sphere --max-count 20000000 --seed-count 3000000 --steps 3 -o p.ply");
    EXPECT_EQ(r.exit_code, 2) << kib << " KiB\n" << r.output;
    EXPECT_NE(r.output.find("the process limit (ulimit -v) allows about"), std::string::npos)
        << kib << " KiB\n"
        << r.output;
    EXPECT_NE(r.output.find("use --max-count "), std::string::npos) << r.output;
    EXPECT_EQ(other_files(dir), 0) << kib << " KiB: a partial or temporary file is left";
  }
  const auto refused = under_limit(500'000, dir, "sample sphere --max-count 20000000 -o p.ply");
  const auto at = refused.output.find("use --max-count ");
  ASSERT_NE(at, std::string::npos) << refused.output;
  const long long offered = std::stoll(refused.output.substr(at + 16));
  EXPECT_GT(offered, 100'000) << refused.output;
  const auto r =
      under_limit(500'000, dir,
                  "sample sphere --max-count " + std::to_string(offered) + " --seed-count " +
                      std::to_string(offered) + " --steps 2 -o p.ply");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(std::filesystem::exists(dir + "/p.ply")) << r.output;
}

// A clip of absurd length is refused where it is read, with the limit and the JSON pointer.
TEST(HostileFaults, AMillionClipsAreRefusedAtOnce) {
  const std::string dir = fresh_dir("faults_clips");
  std::string clips;
  for (int k = 0; k < 1'000'000; ++k) clips += k ? ",\"sphere:2\"" : "\"sphere:2\"";
  std::ofstream(dir + "/million.json")
      << "{\"zeroset_scene\": 1, \"name\": \"kummer\", \"clip\": [" << clips << "]}";
  auto r = run_command(zs("info " + dir + "/million.json"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("/clip/256"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("at most 256 parts"), std::string::npos) << r.output;
  std::string flags;
  for (int k = 0; k < 257; ++k) flags += " --clip sphere:2";
  r = run_command(zs("mesh sphere -r 16" + flags + " -o " + dir + "/m.obj"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("at most 256 parts"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir + "/m.obj"));
}

}  // namespace
}  // namespace zeroset
