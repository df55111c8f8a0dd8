// The memory estimate: the parsers of the files it reads, the rule that the tightest limit
// wins, and the real process limit (ulimit -v) seen from a child process.
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <string>

#include "zeroset/io/memory.h"

namespace zeroset {
namespace {

TEST(MemoryFiles, CgroupLimitReadsBytesAndUnlimited) {
  EXPECT_EQ(parse_cgroup_limit("2147483648\n"), 2147483648.0);
  EXPECT_FALSE(parse_cgroup_limit("max\n"));
  // cgroup v1 writes 2^63 rounded down to a page for "no limit".
  EXPECT_FALSE(parse_cgroup_limit("9223372036854771712\n"));
  EXPECT_FALSE(parse_cgroup_limit(""));
  EXPECT_FALSE(parse_cgroup_limit("12abc"));
  EXPECT_FALSE(parse_cgroup_limit("-5"));
  EXPECT_EQ(parse_byte_count(" 5926498304\n"), 5926498304.0);
  EXPECT_FALSE(parse_byte_count("lots"));
}

TEST(MemoryFiles, MemoryStatFindsItsKey) {
  const char* stat =
      "anon 1000\nfile 500000\nactive_file 200\ninactive_file 300000\ntotal_inactive_file 7\n";
  EXPECT_EQ(parse_memory_stat(stat, "inactive_file"), 300000.0);
  EXPECT_EQ(parse_memory_stat(stat, "total_inactive_file"), 7.0);
  EXPECT_EQ(parse_memory_stat(stat, "anon"), 1000.0);
  EXPECT_FALSE(parse_memory_stat(stat, "file_mapped"));
  EXPECT_FALSE(parse_memory_stat("", "anon"));
}

TEST(MemoryFiles, StatmGivesMappedAndDataBytes) {
  double mapped = 0, data = 0;
  ASSERT_TRUE(parse_statm("1000 200 50 10 0 300 0\n", 4096, mapped, data));
  EXPECT_EQ(mapped, 1000.0 * 4096);
  EXPECT_EQ(data, 300.0 * 4096);
  EXPECT_FALSE(parse_statm("1000 200", 4096, mapped, data));
}

TEST(MemoryFiles, CgroupPathOfV2AndV1) {
  const char* v1 =
      "9:name=systemd:/\n4:memory:/jobs/a1\n3:cpu,cpuacct:/\n0::/user.slice/session-2.scope\n";
  EXPECT_EQ(parse_cgroup_path(v1, true), "/jobs/a1");
  EXPECT_EQ(parse_cgroup_path(v1, false), "/user.slice/session-2.scope");
  EXPECT_EQ(parse_cgroup_path("5:cpu,memory,pids:/x\n", true), "/x");
  EXPECT_FALSE(parse_cgroup_path("5:cpu,pids:/x\n", true));
  EXPECT_EQ(parse_cgroup_path("0::/\n", false), "/");
  EXPECT_FALSE(parse_cgroup_path("garbage\n", false));
}

TEST(MemoryLimits, TheTightestLimitWinsAndIsNamed) {
  MemoryFacts f;
  f.physical = 16e9;
  EXPECT_EQ(least_memory_limit(f).source, "physical memory");
  EXPECT_EQ(least_memory_limit(f).bytes, 16e9);

  f.address_limit = 3.072e9;  // ulimit -v 3000000
  f.mapped = 0.172e9;
  MemoryLimit l = least_memory_limit(f);
  EXPECT_EQ(l.source, "the process limit (ulimit -v)");
  EXPECT_DOUBLE_EQ(l.bytes, 2.9e9);
  EXPECT_EQ(l.describe(), "the process limit (ulimit -v) allows about 2.9 GB");
  EXPECT_EQ(memory_shortfall(5.21e9, l),
            "would need about 5.2 GB of memory and the process limit (ulimit -v) allows about "
            "2.9 GB");

  f.cgroups.push_back({.limit = 2e9, .used = 0.5e9});
  f.cgroups.push_back({.limit = 8e9, .used = 7e9});  // an ancestor nearly full: 1 GB left
  l = least_memory_limit(f);
  EXPECT_EQ(l.source, "the cgroup memory limit");
  EXPECT_DOUBLE_EQ(l.bytes, 1e9);

  f.data_limit = 1.2e9;
  f.data = 0.4e9;
  l = least_memory_limit(f);
  EXPECT_EQ(l.source, "the process data limit (ulimit -d)");
  EXPECT_DOUBLE_EQ(l.bytes, 0.8e9);
}

TEST(MemoryLimits, AnExhaustedLimitIsZeroNotNegative) {
  MemoryFacts f;
  f.address_limit = 1e9;
  f.mapped = 2e9;
  const MemoryLimit l = least_memory_limit(f);
  EXPECT_TRUE(l.known);
  EXPECT_EQ(l.bytes, 0);
  EXPECT_FALSE(least_memory_limit({}).known);
}

// ulimit -v in a child process: available_memory() names it and counts what is mapped already.
TEST(MemoryLimits, ThisProcessSeesItsAddressSpaceLimit) {
  const MemoryLimit before = available_memory();
  ASSERT_TRUE(before.known);
  EXPECT_GT(before.bytes, 0);
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    double mapped = 0, data = 0;
    parse_statm(
        [] {
          char buf[256] = {};
          FILE* f = std::fopen("/proc/self/statm", "r");
          if (!f) std::_Exit(10);
          const size_t n = std::fread(buf, 1, sizeof buf - 1, f);
          std::fclose(f);
          return std::string(buf, n);
        }(),
        static_cast<double>(::sysconf(_SC_PAGE_SIZE)), mapped, data);
    const rlimit r{static_cast<rlim_t>(mapped + 1e9), static_cast<rlim_t>(mapped + 1e9)};
    if (::setrlimit(RLIMIT_AS, &r) != 0) std::_Exit(11);
    const MemoryLimit l = available_memory();
    if (l.source != "the process limit (ulimit -v)") std::_Exit(12);
    // About 1 GB: the limit minus what this process maps (a little more than when measured).
    if (!(l.bytes > 0.9e9 && l.bytes <= 1e9)) std::_Exit(13);
    std::_Exit(0);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0) << "10: no statm, 11: setrlimit failed, 12: limit not named, "
                                       "13: wrong size";
}

}  // namespace
}  // namespace zeroset
