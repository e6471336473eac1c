#include "meshless/solvers/available_memory.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <fstream>
#include <sstream>
#include <vector>

namespace meshless {

namespace {

std::optional<std::string> read_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) return std::nullopt;
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) return std::nullopt;
  return text.str();
}

std::optional<double> parse_bytes(const std::string& text) {
  std::istringstream in(text);
  double value = 0.0;
  if (!(in >> value) || value < 0.0) return std::nullopt;
  return value;
}

double physical_bytes() {
  const long pages = sysconf(_SC_PHYS_PAGES), page_size = sysconf(_SC_PAGE_SIZE);
  return pages > 0 && page_size > 0 ? static_cast<double>(pages) * static_cast<double>(page_size) : 0.0;
}

/// The cgroup path of this process for a v1 controller ("memory") or for v2 (controller empty), from
/// /proc/self/cgroup lines "id:controllers:path".
std::optional<std::string> cgroup_path(const std::string& proc_self_cgroup, const std::string& controller) {
  std::istringstream in(proc_self_cgroup);
  for (std::string line; std::getline(in, line);) {
    const auto first = line.find(':'), second = line.find(':', first + 1);
    if (first == std::string::npos || second == std::string::npos) continue;
    const std::string controllers = line.substr(first + 1, second - first - 1);
    const std::string path = line.substr(second + 1);
    if (controller.empty() ? controllers.empty() && line.compare(0, first, "0") == 0
                           : ("," + controllers + ",").find("," + controller + ",") != std::string::npos)
      return path;
  }
  return std::nullopt;
}

/// The directory of the group and of each ancestor under `mount` (a limit may sit on any of them), the
/// mount itself last: inside a cgroup namespace the process's own group is the mount's root.
std::vector<std::string> group_and_ancestors(const std::string& mount, std::string path) {
  std::vector<std::string> dirs;
  while (!path.empty() && path != "/") {
    dirs.push_back(mount + path);
    path = path.substr(0, path.rfind('/'));
  }
  dirs.push_back(mount);
  return dirs;
}

}  // namespace

std::optional<double> parse_mem_available(const std::string& meminfo) {
  std::istringstream in(meminfo);
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("MemAvailable:", 0) != 0) continue;
    std::istringstream fields(line.substr(13));
    double kib = 0.0;
    std::string unit;
    if (!(fields >> kib >> unit) || unit != "kB" || kib < 0.0) return std::nullopt;
    return kib * 1024.0;
  }
  return std::nullopt;
}

std::optional<double> cgroup_headroom(const std::string& limit, const std::string& usage, double physical) {
  if (limit.rfind("max", 0) == 0) return std::nullopt;  // v2: no limit
  const std::optional<double> l = parse_bytes(limit), u = parse_bytes(usage);
  if (!l || !u) return std::nullopt;
  if (physical > 0.0 && *l >= physical) return std::nullopt;  // v1 spells "no limit" as ~2^63
  return std::max(0.0, *l - *u);
}

AvailableMemory available_memory() {
  const double physical = physical_bytes();
  std::optional<double> headroom;
  std::string headroom_source;
  const std::optional<std::string> self = read_file("/proc/self/cgroup");
  if (self) {
    struct Layout {
      const char* version;
      std::string controller, mount;
      const char *limit_file, *usage_file;
    };
    const Layout layouts[] = {
        {"v2", "", "/sys/fs/cgroup", "memory.max", "memory.current"},
        {"v2", "", "/sys/fs/cgroup/unified", "memory.max", "memory.current"},
        {"v1", "memory", "/sys/fs/cgroup/memory", "memory.limit_in_bytes", "memory.usage_in_bytes"},
    };
    for (const Layout& layout : layouts) {
      const std::optional<std::string> path = cgroup_path(*self, layout.controller);
      if (!path) continue;
      for (const std::string& dir : group_and_ancestors(layout.mount, *path)) {
        const std::string limit_path = dir + "/" + layout.limit_file;
        const std::optional<std::string> limit = read_file(limit_path);
        const std::optional<std::string> usage = read_file(dir + "/" + layout.usage_file);
        if (!limit || !usage) continue;
        const std::optional<double> h = cgroup_headroom(*limit, *usage, physical);
        if (h && (!headroom || *h < *headroom)) {
          headroom = h;
          headroom_source = fmt::format("cgroup {} {}", layout.version, limit_path);
        }
      }
    }
  }
  std::optional<double> mem_available;
  if (const std::optional<std::string> meminfo = read_file("/proc/meminfo")) mem_available = parse_mem_available(*meminfo);

  // A cgroup limit binds only when it is tighter than what the whole machine has left.
  if (headroom && (!mem_available || *headroom < *mem_available)) return {*headroom, headroom_source};
  if (mem_available) return {*mem_available, "MemAvailable (/proc/meminfo)"};
  return {physical, "physical memory (sysconf)"};
}

}  // namespace meshless
