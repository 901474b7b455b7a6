#include "orthofront/spacetime/flow_map.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>

namespace orthofront::spacetime {

std::size_t FlowMap::advect_all(std::span<Vec3> x, std::span<const double> t0, double t1,
                                std::span<ParticleStatus> status) const {
  std::atomic<std::size_t> evaluations{0};
  tbb::parallel_for(std::size_t{0}, x.size(), [&](std::size_t i) {
    const Advected a = advect(x[i], t0[i], t1);
    x[i] = a.x;
    status[i] = a.status;
    evaluations.fetch_add(static_cast<std::size_t>(a.evaluations), std::memory_order_relaxed);
  });
  return evaluations.load();
}

namespace {

// dx/dt = v(x, t) as the steady field (v, 1) over (x, t), restricted to [t_lo, t_hi]. Times a
// few rounding errors past an end are taken as the end: the integrator's last step lands on t1
// by a sum of step sizes, which may overshoot by an ulp where the data's time range ends.
template <int N>
class TimeLifted final : public Field<N> {
  static constexpr int d = N - 1;

 public:
  TimeLifted(const UnsteadyField& flow, double t_lo, double t_hi)
      : flow_(flow), t_lo_(t_lo), t_hi_(t_hi),
        slack_(1e-12 * std::max({1.0, std::abs(t_lo), std::abs(t_hi)})) {}
  FieldStatus velocity(const Vec<N>& X, Vec<N>& V) const override {
    double t = X[d];
    if (t < t_lo_ - slack_ || t > t_hi_ + slack_) return FieldStatus::outside;
    t = std::clamp(t, t_lo_, t_hi_);
    Vec3 x = Vec3::Zero(), v;
    x.template head<d>() = X.template head<d>();
    const FieldStatus st = flow_.velocity(x, t, v);
    if (st != FieldStatus::inside) return st;
    V.template head<d>() = v.template head<d>();
    V[d] = 1.0;
    return st;
  }
  FieldStatus velocity_jacobian(const Vec<N>&, Vec<N>&, Mat<N>&) const override {
    return FieldStatus::no_data;  // not used by the integrator
  }
  Box<N> domain() const override {
    Box<N> b;
    const Box<3> box = flow_.domain();
    b.lo.template head<d>() = box.lo.template head<d>();
    b.hi.template head<d>() = box.hi.template head<d>();
    b.lo[d] = t_lo_;
    b.hi[d] = t_hi_;
    return b;
  }
  std::string describe() const override { return flow_.describe(); }
  double next_kink(const Vec<N>& X, const Vec<N>& W, double after, double before) const override {
    Vec3 x = Vec3::Zero(), w = Vec3::Zero();
    x.template head<d>() = X.template head<d>();
    w.template head<d>() = W.template head<d>();
    return flow_.next_kink(x, X[d], w, W[d], after, before);
  }

 private:
  const UnsteadyField& flow_;
  double t_lo_, t_hi_, slack_;
};

}  // namespace

IntegratedFlowMap::IntegratedFlowMap(const UnsteadyField& flow, Tolerance tolerance)
    : flow_(flow), tolerance_(tolerance) {}

Advected IntegratedFlowMap::advect(const Vec3& x, double t0, double t1) const {
  return flow_.dimension() == 2 ? advect_in<3>(x, t0, t1) : advect_in<4>(x, t0, t1);
}

template <int N>
Advected IntegratedFlowMap::advect_in(const Vec3& x, double t0, double t1) const {
  constexpr int d = N - 1;
  Advected out;
  out.x = x;
  out.t = t0;
  const TimeRange range = flow_.time_range();
  if (!range.contains(t0) || !range.contains(t1)) {
    out.status = ParticleStatus::time_bounds;
    return out;
  }
  if (t0 == t1) {
    Vec3 v;
    const FieldStatus st = flow_.velocity(x, t0, v);
    out.status = st == FieldStatus::inside ? ParticleStatus::moving
                 : st == FieldStatus::outside ? ParticleStatus::left_domain
                                              : ParticleStatus::no_data;
    out.evaluations = 1;
    return out;
  }
  const TimeLifted<N> field(flow_, std::min(t0, t1), std::max(t0, t1));
  Vec<N> X;
  X.template head<d>() = x.template head<d>();
  X[d] = t0;
  const IntegrationResult<N> r = integrate_dopri5(field, X, t1 - t0, tolerance_);
  out.x = Vec3::Zero();
  out.x.template head<d>() = r.x.template head<d>();
  out.evaluations = r.evaluations;
  out.t = r.status == FieldStatus::inside ? t1 : t0 + r.reached;
  out.status = r.status == FieldStatus::inside    ? ParticleStatus::moving
               : r.status == FieldStatus::outside ? ParticleStatus::left_domain
                                                  : ParticleStatus::no_data;
  return out;
}

}  // namespace orthofront::spacetime
