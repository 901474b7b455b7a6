#include "orthofront/spacetime/streamed_field.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "orthofront/error.h"
#include "orthofront/field/multilinear.h"

namespace orthofront::spacetime {

bool locate_time(const std::vector<double>& times, double t, std::size_t& k, double& w) {
  const std::size_t n = times.size();
  if (n < 2 || !(t >= times.front() && t <= times.back())) return false;
  // Called for every field evaluation: most series are evenly spaced, so the interval is guessed
  // from the mean spacing and found by a short walk (a binary search where the walk is long).
  // Either way k is the last interval start <= t, as upper_bound gives it.
  const double span = times.back() - times.front();
  const double guess = span > 0 ? (t - times.front()) / span * static_cast<double>(n - 1) : 0.0;
  k = std::min(static_cast<std::size_t>(guess), n - 2);
  for (int walk = 0;; ++walk) {
    if (walk == 4) {
      const auto it = std::upper_bound(times.begin(), times.end(), t);
      k = std::min(static_cast<std::size_t>(std::max<std::ptrdiff_t>(it - times.begin() - 1, 0)), n - 2);
      break;
    }
    if (k > 0 && times[k] > t)
      --k;
    else if (k + 2 < n && times[k + 1] <= t)
      ++k;
    else
      break;
  }
  w = (t - times[k]) / (times[k + 1] - times[k]);
  return true;
}

StreamedField::StreamedField(BrickCache& cache)
    : cache_(cache), grid_(cache.series().geometry()), layout_(cache.layout()) {
  const io::TimeSeries& s = cache.series();
  const GridGeometry& g = grid_;
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
  components_ = s.components();
  zero_is_no_data_ = s.zero_is_no_data();
  kind_ = 4 * (dimension_ == 3) + 2 * (components_ == 3) + (g.rectilinear() ? 1 : 0);
  box_ = g.bounds();
  if (dimension_ == 2) {
    box_.lo[2] = -1;
    box_.hi[2] = 1;
  }
  for (std::size_t a = 0; a < 3; ++a) {
    cells_[a] = static_cast<int>(a) < dimension_ ? g.size[a] - 1 : 0;
    if (g.rectilinear()) {
      inverse_width_[a].resize(g.axes[a].size() > 1 ? g.axes[a].size() - 1 : 0);
      for (std::size_t i = 0; i + 1 < g.axes[a].size(); ++i)
        inverse_width_[a][i] = 1.0 / (g.axes[a][i + 1] - g.axes[a][i]);
    } else {
      inverse_spacing_[a] = 1.0 / g.spacing[static_cast<int>(a)];
    }
  }
  const auto c = static_cast<std::size_t>(components_);
  stride_ = {c, c * static_cast<std::size_t>(layout_.size[0]),
             c * static_cast<std::size_t>(layout_.size[0] * layout_.size[1])};
  const std::size_t units = s.step_count() * layout_.bricks();
  table_ = std::make_unique<std::atomic<const float*>[]>(units);
  for (std::size_t i = 0; i < units; ++i) table_[i].store(nullptr, std::memory_order_relaxed);
  stamp_.assign(units, 0);
}

TimeRange StreamedField::time_range() const {
  return TimeRange{cache_.times().front(), cache_.times().back()};
}

double StreamedField::next_kink(const Vec3& x, double t, const Vec3& w, double w_t,
                                double after, double before) const {
  double first = grid_.next_cell_face(x, w, after);
  if (w_t != 0) {
    // The first interior time step beyond t + after w_t in the direction of w_t.
    const double step = next_interior_coordinate(cache_.times(), t + after * w_t, w_t > 0);
    const double tau = (step - t) / w_t;
    if (tau > after && tau < first) first = tau;
  }
  return first < before ? first : std::numeric_limits<double>::infinity();
}

std::string StreamedField::describe() const { return "time series " + cache_.series().describe(); }

std::string StreamedField::error() const {
  std::lock_guard lock(error_mutex_);
  return error_;
}

const float* StreamedField::unit(std::size_t step, std::size_t brick, bool resident_only,
                                 std::vector<BrickCache::Handle>& local) const {
  const std::size_t index = step * layout_.bricks() + brick;
  if (const float* p = table_[index].load(std::memory_order_acquire)) return p;
  if (resident_only || failed_.load(std::memory_order_relaxed)) return nullptr;
  slow_.fetch_add(1, std::memory_order_relaxed);
  try {
    BrickCache::Handle h =
        cache_.acquire(BrickKey{static_cast<std::uint32_t>(step), static_cast<std::uint32_t>(brick)});
    const float* p = h.data();
    std::lock_guard lock(extra_mutex_);
    if ((extra_pins_.size() + 1) * cache_.unit_bytes() * 4 > cache_.budget()) {
      local.push_back(std::move(h));
      return p;
    }
    table_[index].store(p, std::memory_order_release);
    extra_pins_.push_back(std::move(h));
    return p;
  } catch (const std::exception& e) {
    std::lock_guard lock(error_mutex_);
    if (error_.empty()) error_ = e.what();
    failed_.store(true, std::memory_order_relaxed);
    return nullptr;
  }
}

template <int Axes, int Components, bool WithJacobian>
FieldStatus StreamedField::evaluate(const Vec3& x, double t, Vec3& v, Mat3* J, Vec3* dvdt,
                                    bool resident_only) const {
  const std::vector<double>& times = cache_.times();
  std::size_t k = 0;
  double w = 0;
  if (!locate_time(times, t, k, w)) return FieldStatus::outside;
  multilinear::AxisCell at[3];
  for (int a = 0; a < Axes; ++a) {
    const auto ua = static_cast<std::size_t>(a);
    if (!(x[a] >= box_.lo[a] && x[a] <= box_.hi[a])) return FieldStatus::outside;
    if (grid_.rectilinear())
      at[a] = multilinear::locate_rectilinear(x[a], grid_.axes[ua], inverse_width_[ua].data(),
                                              cells_[ua]);
    else
      at[a] = multilinear::locate_uniform(x[a], grid_.origin[a], inverse_spacing_[ua], cells_[ua]);
  }
  // The cell's corners lie in one unit unless the cell straddles a brick border.
  std::int64_t brick[3] = {0, 0, 0}, local[3] = {0, 0, 0};
  bool straddles = false;
  for (int a = 0; a < Axes; ++a) {
    const auto ua = static_cast<std::size_t>(a);
    brick[a] = at[a].i / layout_.size[ua];
    local[a] = at[a].i - brick[a] * layout_.size[ua];
    straddles = straddles || local[a] == layout_.size[ua] - 1;
  }
  const std::size_t sy = stride_[1], sz = stride_[2];
  Vec3 values[2];
  Mat3 jacobians[2];
  std::vector<BrickCache::Handle> held;  // slow-path pins of this evaluation only (rarely used)
  for (int s = 0; s < 2; ++s) {
    const std::size_t step = k + static_cast<std::size_t>(s);
    FieldStatus status = FieldStatus::inside;
    const auto interpolate = [&](const auto& corner) {
      // Non-finite corners show in the value; zero vectors are looked for where they mean no data.
      if (zero_is_no_data_ && multilinear::cell_has_zero_vector<Axes, Components>(corner)) {
        status = FieldStatus::no_data;
        return;
      }
      multilinear::interpolate<Axes, Components, WithJacobian>(corner, at, values[s],
                                                               WithJacobian ? &jacobians[s]
                                                                            : nullptr);
      if (!multilinear::value_is_finite<Components>(values[s])) status = FieldStatus::no_data;
    };
    if (!straddles) {
      const float* data =
          unit(step, layout_.brick_index(brick[0], brick[1], brick[2]), resident_only, held);
      if (data == nullptr) return FieldStatus::no_data;
      const float* p = data + static_cast<std::size_t>(local[0]) * Components +
                       static_cast<std::size_t>(local[1]) * sy +
                       static_cast<std::size_t>(local[2]) * sz;
      interpolate([p, sy, sz](int bx, int by, int bz) {
        return p + static_cast<std::size_t>(bx) * Components + static_cast<std::size_t>(by) * sy +
               static_cast<std::size_t>(bz) * sz;
      });
    } else {
      // Gather the corners from the units that hold them.
      const float* corners[8] = {};
      for (int corner = 0; corner < (Axes == 3 ? 8 : 4); ++corner) {
        std::int64_t b[3] = {0, 0, 0}, l[3] = {0, 0, 0};
        for (int a = 0; a < Axes; ++a) {
          const auto ua = static_cast<std::size_t>(a);
          const std::int64_t i = at[a].i + ((corner >> a) & 1);
          b[a] = i / layout_.size[ua];
          l[a] = i - b[a] * layout_.size[ua];
        }
        const float* data =
            unit(step, layout_.brick_index(b[0], b[1], b[2]), resident_only, held);
        if (data == nullptr) return FieldStatus::no_data;
        corners[corner] = data + static_cast<std::size_t>(l[0]) * Components +
                          static_cast<std::size_t>(l[1]) * sy + static_cast<std::size_t>(l[2]) * sz;
      }
      interpolate([&corners](int bx, int by, int bz) { return corners[bx | by << 1 | bz << 2]; });
    }
    if (status != FieldStatus::inside) return status;
  }
  v = (1 - w) * values[0] + w * values[1];
  if constexpr (WithJacobian) {
    *J = (1 - w) * jacobians[0] + w * jacobians[1];
    *dvdt = (values[1] - values[0]) / (times[k + 1] - times[k]);
  }
  return FieldStatus::inside;
}

FieldStatus StreamedField::dispatch(const Vec3& x, double t, Vec3& v, Mat3* J, Vec3* dvdt,
                                    bool resident_only) const {
  // Rectilinear or uniform is decided inside (one branch per axis); the rest is compiled apart.
  const bool with_jacobian = J != nullptr;
  switch (kind_ >> 1) {
    case 0:
      return with_jacobian ? evaluate<2, 2, true>(x, t, v, J, dvdt, resident_only)
                           : evaluate<2, 2, false>(x, t, v, J, dvdt, resident_only);
    case 1:
      return with_jacobian ? evaluate<2, 3, true>(x, t, v, J, dvdt, resident_only)
                           : evaluate<2, 3, false>(x, t, v, J, dvdt, resident_only);
    case 2:
      return with_jacobian ? evaluate<3, 2, true>(x, t, v, J, dvdt, resident_only)
                           : evaluate<3, 2, false>(x, t, v, J, dvdt, resident_only);
    default:
      return with_jacobian ? evaluate<3, 3, true>(x, t, v, J, dvdt, resident_only)
                           : evaluate<3, 3, false>(x, t, v, J, dvdt, resident_only);
  }
}

FieldStatus StreamedField::velocity(const Vec3& x, double t, Vec3& v) const {
  return dispatch(x, t, v, nullptr, nullptr, false);
}

FieldStatus StreamedField::velocity_jacobian(const Vec3& x, double t, Vec3& v, Mat3& J,
                                             Vec3& dvdt) const {
  return dispatch(x, t, v, &J, &dvdt, false);
}

bool StreamedField::resident_velocity(const Vec3& x, double t, Vec3& v) const {
  return dispatch(x, t, v, nullptr, nullptr, true) == FieldStatus::inside;
}

void StreamedField::publish(std::vector<BrickCache::Handle>&& pins) {
  const std::size_t units = layout_.bricks();
  const auto index = [units](const BrickCache::Handle& h) {
    return static_cast<std::size_t>(h.key().step) * units + h.key().brick;
  };
  // No evaluation runs now (the engine calls back between steps).
  for (const auto& h : pins_) table_[index(h)].store(nullptr, std::memory_order_relaxed);
  for (const auto& h : extra_pins_) table_[index(h)].store(nullptr, std::memory_order_relaxed);
  for (const auto& h : pins) table_[index(h)].store(h.data(), std::memory_order_release);
  pins_ = std::move(pins);  // the old pins go only now: shared units never leave the cache
  extra_pins_.clear();
}

void StreamedField::release_except(std::span<const BrickKey> keep) {
  const std::size_t units = layout_.bricks();
  const auto less = [](const BrickKey& a, const BrickKey& b) {
    return a.step != b.step ? a.step < b.step : a.brick < b.brick;
  };
  std::vector<BrickCache::Handle> kept;
  for (BrickCache::Handle& h : pins_) {
    if (std::binary_search(keep.begin(), keep.end(), h.key(), less)) {
      kept.push_back(std::move(h));
    } else {
      table_[static_cast<std::size_t>(h.key().step) * units + h.key().brick].store(
          nullptr, std::memory_order_relaxed);
    }
  }
  pins_ = std::move(kept);  // the others are released here, before the new band loads
  for (const auto& h : extra_pins_)
    table_[static_cast<std::size_t>(h.key().step) * units + h.key().brick].store(
        nullptr, std::memory_order_relaxed);
  extra_pins_.clear();
}

void StreamedField::update_band(double t_lo, double t_hi) {
  const std::vector<double>& times = cache_.times();
  t_lo = std::clamp(t_lo, times.front(), times.back());
  t_hi = std::clamp(std::max(t_hi, t_lo), times.front(), times.back());
  std::size_t first = 0, last = 0;
  double w = 0;
  locate_time(times, t_lo, first, w);
  locate_time(times, t_hi, last, w);
  last = std::min(last + 1, times.size() - 1);
  const std::vector<BrickKey> keys = cache_.step_keys(first, last + 1);
  cache_.require_fits(keys.size(), "the band of time steps " + std::to_string(first) + ".." +
                                       std::to_string(last) + " (times " +
                                       std::to_string(times[first]) + " to " +
                                       std::to_string(times[last]) + ")");
  cache_.new_epoch(first);
  release_except(keys);
  publish(cache_.acquire_all(keys));
}

std::int64_t StreamedField::point_below(int axis, double x) const {
  const auto a = static_cast<std::size_t>(axis);
  const std::int64_t n = grid_.size[a];
  if (grid_.rectilinear()) {
    const auto& c = grid_.axes[a];
    return std::clamp<std::int64_t>(std::upper_bound(c.begin(), c.end(), x) - c.begin() - 1, 0,
                                    n - 1);
  }
  const double u = std::floor((x - grid_.origin[axis]) * inverse_spacing_[a]);
  return static_cast<std::int64_t>(std::clamp(u, 0.0, static_cast<double>(n - 1)));
}

void StreamedField::collect(const std::array<std::int64_t, 3>& lo,
                            const std::array<std::int64_t, 3>& hi, std::size_t k0, std::size_t k1,
                            std::vector<BrickKey>& out) {
  std::int64_t b0[3], b1[3];
  for (std::size_t a = 0; a < 3; ++a) {
    b0[a] = lo[a] / layout_.size[a];
    b1[a] = hi[a] / layout_.size[a];
  }
  const std::size_t units = layout_.bricks();
  auto& stamp = stamp_;
  for (std::size_t k = k0; k <= k1; ++k)
    for (std::int64_t bk = b0[2]; bk <= b1[2]; ++bk)
      for (std::int64_t bj = b0[1]; bj <= b1[1]; ++bj)
        for (std::int64_t bi = b0[0]; bi <= b1[0]; ++bi) {
          const std::size_t brick = layout_.brick_index(bi, bj, bk);
          const std::size_t index = k * units + brick;
          if (stamp[index] == stamp_epoch_) continue;
          stamp[index] = stamp_epoch_;
          out.push_back({static_cast<std::uint32_t>(k), static_cast<std::uint32_t>(brick)});
        }
}

BandUpdate StreamedField::update_front(std::span<const FrontSample> front,
                                       const BandPrediction& p) {
  const std::vector<double>& times = cache_.times();
  const std::size_t last_step = times.size() - 1;
  const auto step_of = [&](double t) {
    std::size_t k = 0;
    double w = 0;
    if (!locate_time(times, std::clamp(t, times.front(), times.back()), k, w)) k = 0;
    return k;
  };
  // Units a vertex samples within h front steps: a step moves it at most about ℓ in (x, c t),
  // along (v, c) / |(v, c)|; the margin covers the integrator's stages, the front's neighbours
  // and the deviation of the step length from ℓ.
  const auto gather = [&](int horizon, std::vector<BrickKey>& out) {
    ++stamp_epoch_;
    for (const FrontSample& f : front) {
      if (!f.x.allFinite() || !std::isfinite(f.t)) continue;
      const double c = f.time_scale > 0 ? f.time_scale : p.time_scale;
      const double lifted_speed = std::hypot(f.v.norm(), c);
      // Pinned units must cover the next steps for sure; prefetched ones are a guess, and a
      // guess too far ahead reads bricks the front never samples.
      const double reach = (horizon <= p.pinned_steps ? 1.5 : 1.0) * p.edge * horizon;
      const Vec3 ahead = f.x + f.v * (reach / lifted_speed);
      const double t_ahead = f.t + reach / lifted_speed;
      const double margin = 1.5 * p.edge;
      std::array<std::int64_t, 3> lo{0, 0, 0}, hi{0, 0, 0};
      for (int a = 0; a < dimension_; ++a) {
        const double x0 = std::min(f.x[a], ahead[a]) - margin,
                     x1 = std::max(f.x[a], ahead[a]) + margin;
        lo[static_cast<std::size_t>(a)] = point_below(a, x0);
        hi[static_cast<std::size_t>(a)] =
            std::min(point_below(a, x1) + 1, grid_.size[static_cast<std::size_t>(a)] - 1);
      }
      const std::size_t k0 = step_of(f.t - p.back_time);
      const std::size_t k1 = std::min(step_of(t_ahead + margin / c) + 1, last_step);
      collect(lo, hi, k0, k1, out);
    }
  };
  std::vector<BrickKey> pinned;
  gather(p.pinned_steps, pinned);
  BandUpdate u;
  u.pinned = pinned.size();
  u.first_step = last_step;
  for (const BrickKey& k : pinned) {
    u.first_step = std::min<std::size_t>(u.first_step, k.step);
    u.last_step = std::max<std::size_t>(u.last_step, k.step);
  }
  if (pinned.empty()) u.first_step = 0;
  cache_.require_fits(pinned.size(), "the front's band (" + std::to_string(pinned.size()) +
                                         (layout_.bricks() == 1 ? " time steps, " : " bricks over ") +
                                         "time steps " +
                                         std::to_string(u.first_step) + ".." +
                                         std::to_string(u.last_step) + ")");
  cache_.new_epoch(u.first_step);
  std::sort(pinned.begin(), pinned.end(), [](const BrickKey& a, const BrickKey& b) {
    return a.step != b.step ? a.step < b.step : a.brick < b.brick;
  });
  release_except(pinned);
  publish(cache_.acquire_all(pinned));
  if (p.prefetch_steps > p.pinned_steps) {
    std::vector<BrickKey> ahead;
    gather(p.prefetch_steps, ahead);
    // Most urgent first (earlier steps); within a step in file order (bricks are stored in
    // index order), so the reads sweep the file instead of seeking back and forth.
    std::sort(ahead.begin(), ahead.end(), [](const BrickKey& a, const BrickKey& b) {
      return a.step != b.step ? a.step < b.step : a.brick < b.brick;
    });
    u.prefetched = ahead.size();
    cache_.prefetch(ahead);
  }
  return u;
}

}  // namespace orthofront::spacetime
