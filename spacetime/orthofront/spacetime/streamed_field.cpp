#include "orthofront/spacetime/streamed_field.h"

#include <algorithm>

#include "orthofront/error.h"

namespace orthofront::spacetime {
namespace {
FieldStatus to_field_status(SlabStatus s) {
  return s == SlabStatus::inside    ? FieldStatus::inside
         : s == SlabStatus::outside ? FieldStatus::outside
                                    : FieldStatus::no_data;
}
}  // namespace

StreamedField::StreamedField(TimeStepCache& cache) : cache_(cache) {
  const io::TimeSeries& s = cache.series();
  const GridGeometry& g = s.geometry();
  if (s.step_count() < 2)
    throw InvalidArgument("time series " + s.describe() + " has " +
                          std::to_string(s.step_count()) + " step(s); a path surface needs 2");
  if ((g.dimension != 2 && g.dimension != 3) || (s.components() != 2 && s.components() != 3))
    throw InvalidArgument("time series " + s.describe() + ": grid dimension " +
                          std::to_string(g.dimension) + " with " +
                          std::to_string(s.components()) +
                          " components is not supported (2D or 3D, 2 or 3 components)");
  for (int a = 0; a < g.dimension; ++a)
    if (g.size[static_cast<std::size_t>(a)] < 2)
      throw InvalidArgument("time series " + s.describe() + ": axis " + std::to_string(a) +
                            " has fewer than two samples");
  dimension_ = g.dimension;
  box_ = g.bounds();
  if (dimension_ == 2) {
    box_.lo[2] = -1;
    box_.hi[2] = 1;
  }
}

TimeRange StreamedField::time_range() const {
  return TimeRange{cache_.times().front(), cache_.times().back()};
}

std::string StreamedField::describe() const { return "time series " + cache_.series().describe(); }

std::string StreamedField::error() const {
  std::lock_guard lock(error_mutex_);
  return error_;
}

void StreamedField::update_band(double t_lo, double t_hi) {
  const std::vector<double>& times = cache_.times();
  const std::size_t n = times.size();
  t_lo = std::clamp(t_lo, times.front(), times.back());
  t_hi = std::clamp(std::max(t_hi, t_lo), times.front(), times.back());
  std::size_t first = 0, last = 0;
  double w = 0;
  locate_time(times, t_lo, first, w);
  locate_time(times, t_hi, last, w);
  last = std::min(last + 1, n - 1);  // the interval containing t_hi ends at last + 1
  cache_.require_fits(last - first + 1, "the band of time steps " + std::to_string(first) +
                                            ".." + std::to_string(last) + " (times " +
                                            std::to_string(times[first]) + " to " +
                                            std::to_string(times[last]) + ")");
  std::vector<TimeStepCache::Handle> pins = cache_.acquire_range(first, last);
  cache_.set_band(first, last);
  auto view = std::make_shared<SlabView>();
  view->grid = &cache_.series().geometry();
  view->components = cache_.series().components();
  view->times = &cache_.times();
  view->first = first;
  for (const auto& h : pins) view->steps.push_back(h.data());
  // No evaluation runs now (the engine calls back between steps), so the old view and pins
  // can go once the new ones are in place.
  current_.store(view.get(), std::memory_order_release);
  view_ = std::move(view);
  pins_ = std::move(pins);
  band_first_ = first;
  band_last_ = last;
}

FieldStatus StreamedField::evaluate(const Vec3& x, double t, Vec3& v, Mat3* J,
                                    Vec3* dvdt) const {
  const SlabView* view = current_.load(std::memory_order_acquire);
  if (view == nullptr) return slow_path(x, t, v, J, dvdt);
  const SlabStatus s = sample_slab(*view, x, t, v, J, dvdt);
  if (s == SlabStatus::missing) return slow_path(x, t, v, J, dvdt);
  return to_field_status(s);
}

FieldStatus StreamedField::slow_path(const Vec3& x, double t, Vec3& v, Mat3* J,
                                     Vec3* dvdt) const {
  slow_.fetch_add(1, std::memory_order_relaxed);
  std::size_t k = 0;
  double w = 0;
  if (!locate_time(cache_.times(), t, k, w)) return FieldStatus::outside;
  try {
    TimeStepCache::Handle a = cache_.acquire(k);
    TimeStepCache::Handle b = cache_.acquire(k + 1);
    SlabView view;
    view.grid = &cache_.series().geometry();
    view.components = cache_.series().components();
    view.times = &cache_.times();
    view.first = k;
    view.steps = {a.data(), b.data()};
    return to_field_status(sample_slab(view, x, t, v, J, dvdt));
  } catch (const std::exception& e) {
    std::lock_guard lock(error_mutex_);
    if (error_.empty()) error_ = e.what();
    return FieldStatus::no_data;
  }
}

FieldStatus StreamedField::velocity(const Vec3& x, double t, Vec3& v) const {
  return evaluate(x, t, v, nullptr, nullptr);
}

FieldStatus StreamedField::velocity_jacobian(const Vec3& x, double t, Vec3& v, Mat3& J,
                                             Vec3& dvdt) const {
  return evaluate(x, t, v, &J, &dvdt);
}

}  // namespace orthofront::spacetime
