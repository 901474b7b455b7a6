#pragma once
// For tests that a reader refuses a tiny file whose header claims a huge size before allocating
// what the header claims: how long the read took and how much it raised the process's peak
// resident memory (VmHWM, reset first through /proc/self/clear_refs).
#include <chrono>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>

namespace test_support {

/// This process's peak resident memory in KiB (VmHWM), 0 where /proc is absent.
inline long peak_rss_kib() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind("VmHWM:", 0) == 0) {
      std::istringstream in(line.substr(6));
      long kib = 0;
      in >> kib;
      return kib;
    }
  }
  return 0;
}

struct Footprint {
  double seconds = 0.0;
  long peak_growth_kib = 0;  ///< how far the call raised the peak resident memory
};

/// Runs `read` after resetting the peak resident memory to the current one ("5" into
/// /proc/self/clear_refs; where that is refused the growth is measured from the old peak, which
/// can only understate it).
inline Footprint footprint(const std::function<void()>& read) {
  { std::ofstream("/proc/self/clear_refs") << "5"; }
  const long before = peak_rss_kib();
  const auto start = std::chrono::steady_clock::now();
  read();
  Footprint f;
  f.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  f.peak_growth_kib = peak_rss_kib() - before;
  return f;
}

/// A hostile file must be refused within this time and peak growth: a few MB, where the header
/// claims gigabytes.
constexpr double kHostileSeconds = 5.0;
constexpr long kHostileGrowthKib = 8 * 1024;

}  // namespace test_support
