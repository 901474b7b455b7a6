#include "cli/process_memory.h"

#include <algorithm>
#include <fstream>
#include <string>

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

std::size_t available_memory_bytes() { return proc_kib("/proc/meminfo", "MemAvailable:"); }

std::size_t default_vertex_budget() {
  constexpr std::size_t kCap = 50'000'000, kBytesPerVertex = 300;
  const std::size_t available = available_memory_bytes();
  if (available == 0) return kCap;
  return std::clamp<std::size_t>(available / 2 / kBytesPerVertex, 100'000, kCap);
}

}  // namespace orthofront::cli
