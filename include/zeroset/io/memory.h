#pragma once
/// How much memory this process may still take: the least of physical memory, the process
/// limits (`ulimit -v`, RLIMIT_DATA) and the cgroup's limit (docs/architecture.md, "Errors").
/// Work that plans a large allocation (grids, images, point sets) checks its estimate against
/// it first, so that it is refused with the limit named instead of failing half way.
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace zeroset {

/// The memory still available under the tightest limit, and what imposes that limit.
struct MemoryLimit {
  bool known = false;  ///< false when no limit could be read (then `bytes` is 0)
  double bytes = 0;    ///< bytes still available under the limit
  std::string source;  ///< "physical memory", "the process limit (ulimit -v)", ...

  /// The share of `bytes` a single plan may take: the rest is left for the program itself,
  /// its threads' stacks and the allocator's slack.
  double budget() const { return 0.75 * bytes; }
  /// "the process limit (ulimit -v) allows about 2.9 GB" (for messages).
  std::string describe() const;
};

/// What the limits are computed from, as read from the system; empty optionals are unknown or
/// unlimited. Kept apart from the reading so that the rules can be tested on given text.
struct MemoryFacts {
  std::optional<double> physical;       ///< bytes of RAM
  std::optional<double> address_limit;  ///< RLIMIT_AS (ulimit -v), bytes
  std::optional<double> data_limit;     ///< RLIMIT_DATA (ulimit -d), bytes
  double mapped = 0;                    ///< address space mapped now (/proc/self/statm: size)
  double data = 0;                      ///< data and stack mapped now (/proc/self/statm: data)
  struct Cgroup {
    double limit = 0;  ///< memory.max (v2) or memory.limit_in_bytes (v1)
    double used = 0;   ///< usage without the reclaimable page cache
  };
  std::vector<Cgroup> cgroups;  ///< the process's cgroup and its ancestors that have a limit
};

/// The tightest of the limits in `facts` (never negative).
MemoryLimit least_memory_limit(const MemoryFacts& facts);

/// The message of a plan that does not fit: "would need about 5.2 GB of memory and the process
/// limit (ulimit -v) allows about 2.9 GB" (`needed` in bytes).
std::string memory_shortfall(double needed, const MemoryLimit& limit);

/// Reads the facts of this process (sysconf, getrlimit, /proc/self/statm, /proc/self/cgroup
/// and the cgroup files, v2 or v1) and returns the tightest limit. Cost: a few small file
/// reads; call it once per plan, not in a loop.
MemoryLimit available_memory();

// The parsers of the files available_memory reads, for tests.

/// A cgroup limit file ("max\n", or a byte count); nullopt when unlimited, unreadable, or so
/// large that it means unlimited (cgroup v1 writes 2⁶³ rounded to a page).
std::optional<double> parse_cgroup_limit(std::string_view text);
/// A byte count file (memory.current, memory.usage_in_bytes); nullopt when unreadable.
std::optional<double> parse_byte_count(std::string_view text);
/// The value of `key` in a memory.stat file ("key value" lines); nullopt when absent.
std::optional<double> parse_memory_stat(std::string_view text, std::string_view key);
/// /proc/self/statm ("size resident shared text lib data dt", in pages): sets mapped and data
/// in bytes; false when the text does not have that form.
bool parse_statm(std::string_view text, double page_bytes, double& mapped, double& data);
/// The cgroup path of the memory controller in /proc/self/cgroup: the v1 line naming
/// "memory" when `v1`, else the v2 line "0::path". nullopt when there is none.
std::optional<std::string> parse_cgroup_path(std::string_view text, bool v1);

}  // namespace zeroset
