#pragma once
/// Stage timings for reports: the seconds since a start, and a scope that adds its seconds to a
/// counter.
#include <chrono>

namespace orthofront {

inline double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

/// Adds the elapsed time of a scope to one counter.
class StageTimer {
 public:
  explicit StageTimer(double& sink) : sink_(sink), start_(std::chrono::steady_clock::now()) {}
  ~StageTimer() { sink_ += seconds_since(start_); }
  StageTimer(const StageTimer&) = delete;
  StageTimer& operator=(const StageTimer&) = delete;

 private:
  double& sink_;
  std::chrono::steady_clock::time_point start_;
};

}  // namespace orthofront
