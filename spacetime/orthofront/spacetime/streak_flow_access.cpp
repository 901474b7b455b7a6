#include "orthofront/spacetime/streak_flow_access.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "orthofront/error.h"
#include "orthofront/field/field_spec.h"

namespace orthofront::spacetime {

namespace {
std::string number(double value) { return format_parameter(value); }
}  // namespace

void check_streak_options(const StreakOptions& o, const UnsteadyField& flow,
                          const std::string& field_name) {
  const auto bad = [](const std::string& what) { throw InvalidArgument(what); };
  if (!(std::isfinite(o.edge) && o.edge > 0)) bad("edge length must be finite and > 0, got " + number(o.edge));
  if (!(o.split > 1)) bad("split factor must be > 1, got " + number(o.split));
  if (!(std::isfinite(o.release_begin) && std::isfinite(o.release_end) &&
        o.release_end > o.release_begin))
    bad("release interval " + number(o.release_begin) + ":" + number(o.release_end) +
        " must be finite with its end after its begin");
  if (o.frames.empty()) bad("no observation times (frames) were given");
  for (std::size_t i = 0; i < o.frames.size(); ++i) {
    const double f = o.frames[i];
    if (!std::isfinite(f)) bad("observation time " + std::to_string(i) + " is not finite");
    if (!(f > o.release_begin))
      bad("observation time " + number(f) + " is not after the release begin " +
          number(o.release_begin));
    if (i > 0 && !(f > o.frames[i - 1]))
      bad("observation times must increase: " + number(f) + " after " + number(o.frames[i - 1]));
  }
  const TimeRange range = flow.time_range();
  const auto outside = [&](double t) { return !range.contains(t); };
  if (outside(o.release_begin) || outside(o.release_end) || outside(o.frames.back()))
    bad("the release interval " + number(o.release_begin) + ":" + number(o.release_end) +
        " and the observation times up to " + number(o.frames.back()) +
        " must lie in the time range of " + field_name + ", [" + number(range.begin) + ", " +
        number(range.end) + "]");
  if (!(o.release_step >= 0 && std::isfinite(o.release_step)))
    bad("release step must be finite and >= 0, got " + number(o.release_step));
  if (o.seed_count < 0 || o.seed_count == 1)
    bad("seed count must be at least 2 (or 0 for automatic), got " + std::to_string(o.seed_count));
}

std::string advect_from_release(const StreakFlowAccess& access, const FlowMap& map,
                                std::span<Vec3> x, std::span<const double> from, double t,
                                std::span<ParticleStatus> status, std::size_t& evaluations) {
  if (!access.prepare) {
    evaluations += map.advect_all(x, from, t, status);
    return {};
  }
  std::vector<std::size_t> order(x.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return from[a] < from[b]; });
  std::fill(status.begin(), status.end(), ParticleStatus::moving);
  double c = order.empty() ? t : from[order.front()];
  std::vector<double> stops;
  for (const double b : access.step_times)
    if (b > c && b < t) stops.push_back(b);
  stops.push_back(t);
  std::size_t started = 0;  // particles of `order` already moving
  std::vector<Vec3> bx;
  std::vector<double> bfrom;
  std::vector<ParticleStatus> bst;
  std::vector<std::size_t> which;
  for (const double b : stops) {
    if (std::string error = access.prepare(c, b); !error.empty()) return error;
    while (started < order.size() && from[order[started]] < b) ++started;
    bx.clear(), bfrom.clear(), bst.clear(), which.clear();
    for (std::size_t k = 0; k < started; ++k) {
      const std::size_t i = order[k];
      if (status[i] != ParticleStatus::moving) continue;
      which.push_back(i);
      bx.push_back(x[i]);
      bfrom.push_back(std::max(from[i], c));
    }
    bst.resize(bx.size());
    evaluations += map.advect_all(bx, bfrom, b, bst);
    for (std::size_t k = 0; k < which.size(); ++k) {
      x[which[k]] = bx[k];
      status[which[k]] = bst[k];
    }
    c = b;
  }
  return access.prepare(t, t);
}

}  // namespace orthofront::spacetime
