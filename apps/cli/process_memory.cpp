#include "cli/process_memory.h"

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <fstream>

namespace orthofront::cli {
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

std::size_t available_memory_bytes() { return proc_kib("/proc/meminfo", "MemAvailable:"); }

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

}  // namespace orthofront::cli
