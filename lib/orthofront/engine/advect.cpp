#include "orthofront/engine/advect.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace orthofront {

template <int N>
FrontAdvect<N>::FrontAdvect(const Field<N>& field, const StreamSurfaceOptions& options,
                            const Tolerance& tolerance, const StopRequest& stop,
                            const std::atomic<bool>& stopping, SurfaceReport& report)
    : field_(field), opt_(options), tol_(tolerance), stop_(stop), stopping_(stopping),
      report_(report) {}

template <int N>
bool FrontAdvect<N>::sample(const Front<N>& f, std::vector<char>& keep, std::size_t& exits,
                           VertexSamples<N>* ahead) {
  const std::size_t n = f.v.size();
  if (ahead) {
    std::swap(samples_, *ahead);
  } else {
    samples_.resize(n);
    const auto at = [&f](std::size_t i) -> const Vec<N>& { return f.v[i].x; };
    velocity_loop_.run(n, opt_.parallel_threshold, [&](std::size_t b, std::size_t e) {
      sample_vertices(field_, at, b, e, samples_);
    });
  }
  const std::vector<double>& speed = samples_.speed;
  state_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const FieldStatus st = samples_.status[i];
    state_[i] = st == FieldStatus::inside    ? VertexState::ok
                : st == FieldStatus::outside ? VertexState::outside
                                             : VertexState::no_data;
  }
  report_.field_evaluations += n;
  // No speed is below the zero-speed share of the median where none is below that share of the
  // largest (the median is no larger; a share >= 0 keeps the order): the median, a copy and a
  // selection, only then.
  double slowest = std::numeric_limits<double>::infinity(), fastest = 0;
  bool comparable = true;  // no NaN (which the median's test marks as no flow)
  for (std::size_t i = 0; i < n; ++i) {
    comparable = comparable && !std::isnan(speed[i]);
    fastest = std::max(fastest, speed[i]);
    if (state_[i] == VertexState::ok) slowest = std::min(slowest, speed[i]);
  }
  const bool all_fast = comparable && std::isfinite(fastest) && opt_.zero_speed_fraction >= 0 &&
                        slowest > opt_.zero_speed_fraction * fastest;
  const double median = all_fast ? 0.0 : median_of(speed);
  bool usable = true;
  for (std::size_t i = 0; i < n; ++i) {
    if (state_[i] == VertexState::ok && !all_fast &&
        !(speed[i] > opt_.zero_speed_fraction * median)) {
      state_[i] = VertexState::zero_speed;
      ++report_.zero_velocity_cuts;
    }
    if (state_[i] != VertexState::ok) {
      keep[i] = 0;
      usable = false;
      if (state_[i] == VertexState::outside) ++report_.domain_exits, ++exits;
      if (state_[i] == VertexState::no_data) ++report_.no_data_hits;
    }
  }
  return usable;
}

template <int N>
IntegrationResult<N> FrontAdvect<N>::integrate(const Vec<N>& x, double tau) const {
  if (opt_.integrator == IntegratorKind::rk4)
    return integrate_rk4(field_, x, tau, opt_.rk4_substeps);
  return integrate_dopri5(field_, x, tau, tol_, 0, &stop_);
}

template <int N>
Front<N> FrontAdvect<N>::advance(const Front<N>& f, const std::vector<double>& alpha, double h,
                                 std::vector<char>& keep, std::size_t& exits,
                                 std::vector<FrontVertex<N>>&& room) {
  const std::size_t n = f.v.size();
  Front<N> nf;
  nf.closed = f.closed;
  nf.id = f.id;
  // Every vertex is written below: room kept from an old front saves a pass of zeros over it.
  nf.v = std::move(room);
  nf.v.resize(n);
  state_.assign(n, VertexState::ok);
  evaluations_.assign(n, 0);
  const auto apply = [&](std::size_t i, FrontVertex<N>& fv, const IntegrationResult<N>& r) {
    evaluations_[i] = r.evaluations;
    fv.x = r.x;
    fv.t += r.reached;
    if (r.status != FieldStatus::inside) keep[i] = 0;
    state_[i] = r.interrupted                      ? VertexState::interrupted
                : r.status == FieldStatus::outside ? VertexState::outside
                : r.status == FieldStatus::inside  ? VertexState::ok
                                                   : VertexState::no_data;
  };
  bool bulk = false;
  if (front_integrator_ && !stopping_.load(std::memory_order_relaxed) &&
      n >= front_integrator_->min_vertices()) {
    // The whole front in one call of the bulk backend.
    batch_x_.resize(n);
    batch_tau_.resize(n);
    batch_out_.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      batch_x_[i] = f.v[i].x;
      batch_tau_[i] = alpha[i] * h;
    }
    bulk = front_integrator_->integrate(batch_x_, batch_tau_, batch_out_);
  }
  if (bulk) {
    for (std::size_t i = 0; i < n; ++i) {
      FrontVertex<N> fv = f.v[i];
      fv.origin = static_cast<std::int32_t>(i);
      if (batch_tau_[i] != 0) apply(i, fv, batch_out_[i]);
      nf.v[i] = fv;
    }
  } else {
    for_range(n, opt_.parallel_threshold, [&](std::size_t b, std::size_t e) {
      for (std::size_t i = b; i < e; ++i) {
        const double tau = alpha[i] * h;
        FrontVertex<N> fv = f.v[i];
        fv.origin = static_cast<std::int32_t>(i);
        if (stopping_.load(std::memory_order_relaxed)) {
          keep[i] = 0;  // the run stops: this stream line ends at its last mesh vertex
          state_[i] = VertexState::interrupted;
        } else if (tau != 0) {
          apply(i, fv, integrate(fv.x, tau));
        }
        nf.v[i] = fv;
      }
    });
  }
  report_.vertex_steps += n;
  for (std::size_t i = 0; i < n; ++i) {
    report_.field_evaluations += static_cast<std::size_t>(evaluations_[i]);
    if (state_[i] == VertexState::outside) ++report_.domain_exits, ++exits;
    if (state_[i] == VertexState::no_data) ++report_.no_data_hits;
  }
  return nf;
}

template class FrontAdvect<3>;
template class FrontAdvect<4>;

}  // namespace orthofront
