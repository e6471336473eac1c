#pragma once
// How much memory this process may still allocate: the budget of the automatic direct/iterative choice
// (meshless/solvers/efg_linear_solver.hpp). Half the physical RAM is wrong on a shared machine and in a container:
// the limit that applies is the cgroup's when there is one, and otherwise what the kernel reports as
// available (free memory plus reclaimable caches).
#include <optional>
#include <string>

namespace meshless {

struct AvailableMemory {
  double bytes = 0.0;  ///< what may still be allocated [bytes]
  /// Where the figure comes from: "cgroup v2 <file>", "cgroup v1 <file>" (limit minus usage, capped by
  /// MemAvailable) or "MemAvailable (/proc/meminfo)", or "physical memory (sysconf)" when neither is readable.
  std::string source;
};

/// Reads the cgroup (v2, then v1) of this process and /proc/meminfo afresh on every call (the figure changes
/// as other processes run). Never throws: an unreadable file falls back on the next source.
AvailableMemory available_memory();

/// MemAvailable of a /proc/meminfo text [bytes]; nullopt when absent or malformed.
std::optional<double> parse_mem_available(const std::string& meminfo);
/// limit - usage of a cgroup's memory files (v2 memory.max / memory.current, or v1 memory.limit_in_bytes /
/// memory.usage_in_bytes) [bytes]; nullopt when there is no limit ("max", or a limit above the physical
/// memory, which is how v1 spells "none") or the texts are malformed. Clamped at 0.
std::optional<double> cgroup_headroom(const std::string& limit, const std::string& usage, double physical_bytes);

}  // namespace meshless
