#include "jobs/process_memory.h"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>

namespace orthofront::jobs {
namespace {
// The value of a "Key:   N kB" line of a /proc file, in bytes.
std::size_t proc_kib(const char* file, const std::string& key) {
  std::ifstream in(file);
  std::string line;
  while (std::getline(in, line))
    if (line.rfind(key, 0) == 0) return std::stoull(line.substr(key.size())) * 1024;
  return 0;
}
}  // namespace

std::size_t peak_rss_bytes() { return proc_kib("/proc/self/status", "VmHWM:"); }

std::size_t current_rss_bytes() {
  // statm is one short line of page counts (size resident shared ...): cheaper than parsing
  // /proc/self/status, which matters on a progress line redrawn ten times a second.
  std::FILE* f = std::fopen("/proc/self/statm", "r");
  if (f == nullptr) return 0;
  unsigned long long size = 0, resident = 0;
  const int read = std::fscanf(f, "%llu %llu", &size, &resident);
  std::fclose(f);
  const long page = sysconf(_SC_PAGESIZE);
  if (read != 2 || page <= 0) return 0;
  return static_cast<std::size_t>(resident) * static_cast<std::size_t>(page);
}

namespace {

// The first number in a one-line file ("max" and unreadable files: nullopt).
std::optional<std::size_t> number_in(const std::filesystem::path& file) {
  std::ifstream in(file);
  unsigned long long value = 0;
  if (!(in >> value)) return std::nullopt;
  return static_cast<std::size_t>(value);
}

// Bytes left under the memory limits of this process's cgroups: v2's memory.max less
// memory.current of its cgroup and each ancestor, v1's memory.limit_in_bytes less
// memory.usage_in_bytes. nullopt where no limit applies.
std::optional<std::size_t> cgroup_headroom() {
  std::ifstream in("/proc/self/cgroup");
  std::optional<std::size_t> least;
  const auto take = [&](std::optional<std::size_t> limit, std::optional<std::size_t> used) {
    // v1 writes "no limit" as a page-rounded 2^63.
    if (!limit || *limit >= (std::size_t{1} << 62)) return;
    const std::size_t left = *limit > used.value_or(0) ? *limit - used.value_or(0) : 0;
    least = std::min(least.value_or(left), left);
  };
  for (std::string line; std::getline(in, line);) {
    // "0::/path" (v2) or "N:memory:/path" (v1).
    const std::size_t a = line.find(':'), b = line.find(':', a + 1);
    if (a == std::string::npos || b == std::string::npos) continue;
    const std::string controllers = line.substr(a + 1, b - a - 1);
    std::filesystem::path group = line.substr(b + 1);
    const bool v2 = controllers.empty();
    if (!v2 && ("," + controllers + ",").find(",memory,") == std::string::npos) continue;
    for (;; group = group.parent_path()) {
      const std::filesystem::path dir =
          (v2 ? "/sys/fs/cgroup" : "/sys/fs/cgroup/memory") / group.relative_path();
      if (v2)
        take(number_in(dir / "memory.max"), number_in(dir / "memory.current"));
      else
        take(number_in(dir / "memory.limit_in_bytes"), number_in(dir / "memory.usage_in_bytes"));
      if (!group.has_relative_path()) break;
    }
  }
  return least;
}

// Bytes of address space left under RLIMIT_AS (ulimit -v); nullopt without a limit.
std::optional<std::size_t> address_space_headroom() {
  rlimit limit{};
  if (::getrlimit(RLIMIT_AS, &limit) != 0 || limit.rlim_cur == RLIM_INFINITY) return std::nullopt;
  const std::size_t used = proc_kib("/proc/self/status", "VmSize:");
  const auto cap = static_cast<std::size_t>(limit.rlim_cur);
  return cap > used ? cap - used : 0;
}

}  // namespace

std::size_t available_memory_bytes() {
  std::size_t least = proc_kib("/proc/meminfo", "MemAvailable:");
  for (const std::optional<std::size_t> left : {cgroup_headroom(), address_space_headroom()})
    if (left) least = least == 0 ? *left : std::min(least, *left);
  return least;
}

std::size_t vertex_budget_for(std::size_t memory_bytes) {
  if (memory_bytes == 0) return kMaxDefaultVertices;
  return std::clamp<std::size_t>(memory_bytes / 2 / kBytesPerVertex, 1, kMaxDefaultVertices);
}

std::size_t default_vertex_budget() {
  const std::size_t available = available_memory_bytes();
  if (available == 0) return kMaxDefaultVertices;
  return std::max<std::size_t>(vertex_budget_for(available), 100'000);
}

std::size_t cache_budget_for(std::size_t memory_bytes) {
  if (memory_bytes == 0) return std::size_t{512} << 20;
  return memory_bytes / 4;
}

std::string format_memory(std::size_t bytes) {
  char text[32];
  const double mib = static_cast<double>(bytes) / (1024.0 * 1024.0);
  if (mib >= 1024)
    std::snprintf(text, sizeof text, "%.1f GiB", mib / 1024);
  else
    std::snprintf(text, sizeof text, "%.0f MiB", mib);
  return text;
}

}  // namespace orthofront::jobs
