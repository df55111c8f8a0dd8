#include "zeroset/io/memory.h"

#include <sys/resource.h>
#include <unistd.h>

#include <fmt/core.h>

#include <algorithm>
#include <charconv>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace zeroset {
namespace {

// cgroup v1 says "no limit" with 2⁶³ rounded down to a page; anything beyond an exabyte is
// treated the same way.
constexpr double kUnlimited = 1e18;

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t' || s.front() == '\n'))
    s.remove_prefix(1);
  while (!s.empty() &&
         (s.back() == ' ' || s.back() == '\t' || s.back() == '\n' || s.back() == '\r'))
    s.remove_suffix(1);
  return s;
}

std::optional<double> parse_unsigned(std::string_view s) {
  s = trim(s);
  unsigned long long v = 0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec != std::errc() || end != s.data() + s.size() || s.empty()) return std::nullopt;
  return static_cast<double>(v);
}

// Whole small file, or "" when it cannot be read (a missing cgroup file is not an error).
std::string slurp(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) return {};
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::optional<double> rlimit_bytes(int resource) {
  rlimit r{};
  if (::getrlimit(resource, &r) != 0 || r.rlim_cur == RLIM_INFINITY) return std::nullopt;
  return static_cast<double>(r.rlim_cur);
}

// Usage of one cgroup without the page cache the kernel would reclaim before failing.
double cgroup_used(const std::filesystem::path& dir, bool v1) {
  const auto usage =
      parse_byte_count(slurp(dir / (v1 ? "memory.usage_in_bytes" : "memory.current")));
  if (!usage) return 0;
  const auto inactive =
      parse_memory_stat(slurp(dir / "memory.stat"), v1 ? "total_inactive_file" : "inactive_file");
  return std::max(0.0, *usage - inactive.value_or(0.0));
}

// The cgroup of this process and its ancestors up to the mount point, each with a limit.
void read_cgroups(MemoryFacts& facts) {
  namespace fs = std::filesystem;
  const std::string self = slurp("/proc/self/cgroup");
  for (const bool v1 : {false, true}) {
    const fs::path mount = v1 ? "/sys/fs/cgroup/memory" : "/sys/fs/cgroup";
    const char* limit_file = v1 ? "memory.limit_in_bytes" : "memory.max";
    const auto path = parse_cgroup_path(self, v1);
    if (!path) continue;
    std::error_code ec;
    fs::path dir = mount / fs::path(*path).relative_path();
    // Inside a cgroup namespace the path may not exist under this mount: only its root is seen.
    if (!fs::is_directory(dir, ec)) dir = mount;
    for (;;) {
      if (const auto limit = parse_cgroup_limit(slurp(dir / limit_file)))
        facts.cgroups.push_back({*limit, cgroup_used(dir, v1)});
      if (dir == mount || !dir.has_parent_path() || dir.parent_path() == dir) break;
      dir = dir.parent_path();
    }
    if (!facts.cgroups.empty()) return;
  }
}

}  // namespace

std::string MemoryLimit::describe() const {
  return fmt::format("{} allows about {:.1f} GB", source, bytes / 1e9);
}

std::string memory_shortfall(double needed, const MemoryLimit& limit) {
  return fmt::format("would need about {:.1f} GB of memory and {}", needed / 1e9, limit.describe());
}

MemoryLimit least_memory_limit(const MemoryFacts& facts) {
  MemoryLimit best;
  auto consider = [&best](double bytes, const char* source) {
    bytes = std::max(0.0, bytes);
    if (!best.known || bytes < best.bytes) best = {true, bytes, source};
  };
  if (facts.physical) consider(*facts.physical, "physical memory");
  if (facts.address_limit)
    consider(*facts.address_limit - facts.mapped, "the process limit (ulimit -v)");
  if (facts.data_limit)
    consider(*facts.data_limit - facts.data, "the process data limit (ulimit -d)");
  for (const MemoryFacts::Cgroup& c : facts.cgroups)
    consider(c.limit - c.used, "the cgroup memory limit");
  return best;
}

MemoryLimit available_memory() {
  MemoryFacts facts;
  const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGE_SIZE);
  if (pages > 0 && page > 0)
    facts.physical = static_cast<double>(pages) * static_cast<double>(page);
  facts.address_limit = rlimit_bytes(RLIMIT_AS);
  facts.data_limit = rlimit_bytes(RLIMIT_DATA);
  if (page > 0)
    parse_statm(slurp("/proc/self/statm"), static_cast<double>(page), facts.mapped, facts.data);
  read_cgroups(facts);
  return least_memory_limit(facts);
}

std::optional<double> parse_cgroup_limit(std::string_view text) {
  if (trim(text) == "max") return std::nullopt;
  const auto v = parse_unsigned(text);
  if (!v || *v >= kUnlimited) return std::nullopt;
  return v;
}

std::optional<double> parse_byte_count(std::string_view text) { return parse_unsigned(text); }

std::optional<double> parse_memory_stat(std::string_view text, std::string_view key) {
  while (!text.empty()) {
    const size_t eol = text.find('\n');
    const std::string_view line = text.substr(0, eol);
    text = eol == std::string_view::npos ? std::string_view() : text.substr(eol + 1);
    const size_t space = line.find(' ');
    if (space != std::string_view::npos && line.substr(0, space) == key)
      return parse_unsigned(line.substr(space + 1));
  }
  return std::nullopt;
}

bool parse_statm(std::string_view text, double page_bytes, double& mapped, double& data) {
  std::istringstream in{std::string(text)};
  unsigned long long size = 0, resident = 0, shared = 0, code = 0, lib = 0, dat = 0;
  if (!(in >> size >> resident >> shared >> code >> lib >> dat)) return false;
  mapped = static_cast<double>(size) * page_bytes;
  data = static_cast<double>(dat) * page_bytes;
  return true;
}

std::optional<std::string> parse_cgroup_path(std::string_view text, bool v1) {
  // Lines "hierarchy-id:controller,list:path"; v2 has id 0 and an empty list.
  while (!text.empty()) {
    const size_t eol = text.find('\n');
    const std::string_view line = text.substr(0, eol);
    text = eol == std::string_view::npos ? std::string_view() : text.substr(eol + 1);
    const size_t a = line.find(':');
    const size_t b = a == std::string_view::npos ? a : line.find(':', a + 1);
    if (b == std::string_view::npos) continue;
    const std::string_view id = line.substr(0, a), controllers = line.substr(a + 1, b - a - 1);
    const std::string path(line.substr(b + 1));
    if (!v1) {
      if (id == "0" && controllers.empty()) return path;
      continue;
    }
    std::string_view rest = controllers;
    while (!rest.empty()) {
      const size_t comma = rest.find(',');
      if (rest.substr(0, comma) == "memory") return path;
      rest = comma == std::string_view::npos ? std::string_view() : rest.substr(comma + 1);
    }
  }
  return std::nullopt;
}

}  // namespace zeroset
