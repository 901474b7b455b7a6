#include "orthofront/spacetime/streak_release_schedule.h"

#include <algorithm>
#include <cmath>

namespace orthofront::spacetime {

StreakReleaseSchedule::StreakReleaseSchedule(const StreakOptions& o, double median_speed,
                                             const std::vector<double>& step_times) {
  const double span = o.release_end - o.release_begin;
  double step = o.release_step > 0 ? o.release_step : (median_speed > 0 ? o.edge / median_speed : span / 100);
  const double rows = std::clamp(std::round(span / step), 1.0, 1e7);
  step_ = span / rows;
  for (double j = 0; j <= rows; ++j)
    releases_.push_back(j == rows ? o.release_end : o.release_begin + step_ * j);
  for (const double f : o.frames)
    if (f < o.release_end) releases_.push_back(f);
  std::sort(releases_.begin(), releases_.end());
  releases_.erase(std::unique(releases_.begin(), releases_.end()), releases_.end());
  const double t_last = o.frames.back();
  const auto per_break = static_cast<std::size_t>(o.releases_per_break);
  for (std::size_t j = 0; j < releases_.size(); ++j)
    if (j % per_break == 0 || j + 1 == releases_.size()) breaks_.push_back(releases_[j]);
  breaks_.insert(breaks_.end(), o.frames.begin(), o.frames.end());
  for (const double t : step_times)
    if (t > o.release_begin && t < t_last) breaks_.push_back(t);
  std::erase_if(breaks_, [&](double t) { return t > t_last; });
  std::sort(breaks_.begin(), breaks_.end());
  breaks_.erase(std::unique(breaks_.begin(), breaks_.end()), breaks_.end());
}

std::vector<double> StreakReleaseSchedule::take_before(double t) {
  std::vector<double> taus;
  while (next_ < releases_.size() && releases_[next_] < t) taus.push_back(releases_[next_++]);
  return taus;
}

bool StreakReleaseSchedule::take_at(double t) {
  if (next_ >= releases_.size() || releases_[next_] != t) return false;
  ++next_;
  return true;
}

}  // namespace orthofront::spacetime
