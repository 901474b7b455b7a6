#pragma once
/// When a streak surface's rows leave the seed, and where its particles stop (breaks): at every
/// releases_per_break-th release and the last, at every observation time and (streamed) at every
/// step of the series; the rows released between two breaks move from their release times to the
/// next break in one call. Observation times inside the release interval release a row too: the
/// surface then reaches the seed curve in every frame.
#include <cstddef>
#include <vector>

#include "orthofront/spacetime/streak_surface.h"

namespace orthofront::spacetime {

class StreakReleaseSchedule {
 public:
  /// `median_speed`: the seed's median speed at release_begin (<= 0: none inside), which sets
  /// the release step where options.release_step is 0 (ℓ over it; without it, a hundredth of the
  /// release interval). `step_times`: a streamed series' times (empty in memory). Takes the
  /// options as check_streak_options accepts them.
  StreakReleaseSchedule(const StreakOptions& options, double median_speed,
                        const std::vector<double>& step_times);

  /// The time between regular releases: the release interval in whole steps.
  double release_step() const { return step_; }
  /// Release times, increasing: the regular ones and the frames inside the release interval.
  const std::vector<double>& releases() const { return releases_; }
  /// Times the particles stop at, increasing, up to the last frame.
  const std::vector<double>& breaks() const { return breaks_; }

  /// The releases not taken yet before time t, taken (increasing).
  std::vector<double> take_before(double t);
  /// Whether the next release not taken is at time t; if so, it is taken.
  bool take_at(double t);
  /// Whether every release is taken.
  bool done() const { return next_ == releases_.size(); }

 private:
  double step_ = 0;
  std::vector<double> releases_, breaks_;
  std::size_t next_ = 0;  // releases before it are taken
};

}  // namespace orthofront::spacetime
