#include "orthofront/spacetime/streak_line_field.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

#include "orthofront/error.h"

namespace orthofront::spacetime {

namespace {

std::string number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", value);
  return text;
}

// The variational equations of dx/dt = v(x, t) as one autonomous field over
// Y = (x (d), ∇φ (d × d, column-major), t): Y' = (v, ∇v ∇φ, 1).
template <int d>
class Variational final : public Field<d + d * d + 1> {
 public:
  static constexpr int N = d + d * d + 1;
  explicit Variational(const UnsteadyField& flow) : flow_(flow) {}
  FieldStatus velocity(const Vec<N>& Y, Vec<N>& V) const override {
    Vec3 x = Vec3::Zero(), v, dvdt;
    Mat3 J;
    x.template head<d>() = Y.template head<d>();
    const FieldStatus st = flow_.velocity_jacobian(x, Y[N - 1], v, J, dvdt);
    if (st != FieldStatus::inside) return st;
    V.template head<d>() = v.template head<d>();
    const Eigen::Map<const Eigen::Matrix<double, d, d>> G(Y.data() + d);
    Eigen::Map<Eigen::Matrix<double, d, d>>(V.data() + d) = J.template topLeftCorner<d, d>() * G;
    V[N - 1] = 1.0;
    return st;
  }
  FieldStatus velocity_jacobian(const Vec<N>&, Vec<N>&, Mat<N>&) const override {
    return FieldStatus::no_data;  // not used by the integrator
  }
  Box<N> domain() const override {
    Box<N> b;
    b.lo.setConstant(-std::numeric_limits<double>::infinity());
    b.hi.setConstant(std::numeric_limits<double>::infinity());
    return b;
  }
  std::string describe() const override { return flow_.describe(); }
  /// The flow's kinks along the path's (x, t) part: where ∇v jumps (a cell face), Y' jumps.
  double next_kink(const Vec<N>& Y, const Vec<N>& W, double after, double before) const override {
    Vec3 x = Vec3::Zero(), w = Vec3::Zero();
    x.template head<d>() = Y.template head<d>();
    w.template head<d>() = W.template head<d>();
    return flow_.next_kink(x, Y[N - 1], w, W[N - 1], after, before);
  }

 private:
  const UnsteadyField& flow_;
};

template <int d>
FlowMapGradient flow_map_gradient_in(const UnsteadyField& flow, const Vec3& x, double t0, double t1,
                                     const Tolerance& tolerance) {
  constexpr int N = Variational<d>::N;
  Vec<N> Y;
  Y.template head<d>() = x.template head<d>();
  Eigen::Map<Eigen::Matrix<double, d, d>>(Y.data() + d).setIdentity();
  Y[N - 1] = t0;
  const Variational<d> system(flow);
  const IntegrationResult<N> r = integrate_dopri5<N>(system, Y, t1 - t0, tolerance);
  FlowMapGradient out;
  out.status = r.status;
  out.evaluations = r.evaluations;
  out.x.template head<d>() = r.x.template head<d>();
  out.gradient.setZero();
  out.gradient.template topLeftCorner<d, d>() =
      Eigen::Map<const Eigen::Matrix<double, d, d>>(r.x.data() + d);
  return out;
}

}  // namespace

FlowMapGradient flow_map_gradient(const UnsteadyField& flow, const Vec3& x, double t0, double t1,
                                  const Tolerance& tolerance) {
  return flow.dimension() == 2 ? flow_map_gradient_in<2>(flow, x, t0, t1, tolerance)
                               : flow_map_gradient_in<3>(flow, x, t0, t1, tolerance);
}

StreakLineField::StreakLineField(const UnsteadyField& flow, double observation_time, double max_age,
                                 Tolerance tolerance)
    : flow_(flow), t_(observation_time), max_age_(max_age), tolerance_(tolerance) {
  const TimeRange times = flow.time_range();
  if (!(max_age > 0 && std::isfinite(max_age) && std::isfinite(observation_time) &&
        times.contains(observation_time) && times.contains(observation_time - max_age)))
    throw InvalidArgument("streak-line field: ages [0, " + number(max_age) +
                          "] before t = " + number(observation_time) +
                          " must be a span > 0 inside the time range of " + flow.describe());
  const Box<3> box = flow.domain();
  const Vec3 extent = box.hi - box.lo;
  dx_ = 1e-6 * (flow.dimension() == 2 ? extent.head<2>().norm() : extent.norm());
  da_ = 1e-6 * max_age;
}

std::string StreakLineField::describe() const {
  return "streak-line field of " + flow_.describe() + " at t = " + number(t_);
}

FieldStatus StreakLineField::velocity(const Vec3& x, double age, Vec3& s) const {
  derived_.fetch_add(1, std::memory_order_relaxed);
  // A few rounding errors past either end of the age range count as the end (the integrator's
  // last step sums step sizes).
  const double slack = 1e-12 * std::max(1.0, max_age_);
  if (age < -slack || age > max_age_ + slack) return FieldStatus::outside;
  age = std::clamp(age, 0.0, max_age_);
  const int d = flow_.dimension();
  if (age == 0.0) {  // Ψ = x, ∇Ψ = I
    flow_evaluations_.fetch_add(1, std::memory_order_relaxed);
    const FieldStatus st = flow_.velocity(x, t_, s);
    if (d == 2) s.z() = 0;
    return st;
  }
  const FlowMapGradient back = flow_map_gradient(flow_, x, t_, t_ - age, tolerance_);
  flow_evaluations_.fetch_add(static_cast<std::size_t>(back.evaluations) + 1,
                              std::memory_order_relaxed);
  if (back.status != FieldStatus::inside) return back.status;
  Vec3 v;
  const FieldStatus st = flow_.velocity(back.x, t_ - age, v);
  if (st != FieldStatus::inside) return st;
  s.setZero();
  if (d == 2) {
    const Eigen::Matrix2d G = back.gradient.topLeftCorner<2, 2>();
    const double det = G.determinant();
    if (!(std::abs(det) > 0) || !std::isfinite(det)) return FieldStatus::no_data;
    s.head<2>() = G.inverse() * v.head<2>();
  } else {
    const Eigen::PartialPivLU<Mat3> lu(back.gradient);
    if (!(std::abs(lu.determinant()) > 0)) return FieldStatus::no_data;
    s = lu.solve(v);
  }
  return s.allFinite() ? FieldStatus::inside : FieldStatus::no_data;
}

FieldStatus StreakLineField::velocity_jacobian(const Vec3& x, double age, Vec3& s, Mat3& J,
                                               Vec3& dsda) const {
  FieldStatus st = velocity(x, age, s);
  if (st != FieldStatus::inside) return st;
  J.setZero();
  const int d = flow_.dimension();
  Vec3 plus, minus;
  for (int c = 0; c < d; ++c) {
    Vec3 e = Vec3::Zero();
    e[c] = dx_;
    if ((st = velocity(x + e, age, plus)) != FieldStatus::inside) return st;
    if ((st = velocity(x - e, age, minus)) != FieldStatus::inside) return st;
    J.col(c) = (plus - minus) / (2 * dx_);
  }
  // One-sided at the ends of the age range.
  const double lo = std::max(0.0, age - da_), hi = std::min(max_age_, age + da_);
  if ((st = velocity(x, hi, plus)) != FieldStatus::inside) return st;
  if ((st = velocity(x, lo, minus)) != FieldStatus::inside) return st;
  dsda = (plus - minus) / (hi - lo);
  return FieldStatus::inside;
}

StreakLineSurface build_streak_line_surface(const UnsteadyField& flow, const SeedCurve& seed,
                                            const StreakLineSurfaceOptions& o) {
  const auto started = std::chrono::steady_clock::now();
  if (flow.dimension() != 2)
    throw InvalidArgument("the streak-line route needs a 2D flow; '" + flow.describe() + "' is " +
                          std::to_string(flow.dimension()) + "D");
  const double t = o.observation_time;
  if (!(std::isfinite(o.release_begin) && std::isfinite(o.release_end) && std::isfinite(t) &&
        o.release_end > o.release_begin && t > o.release_begin))
    throw InvalidArgument("release " + number(o.release_begin) + ":" + number(o.release_end) +
                          " and observation time " + number(t) +
                          " must be finite, the release increasing and begun before t");
  const double max_age = t - o.release_begin;
  const double first_age = std::max(0.0, t - o.release_end);
  const StreakLineField field(flow, t, max_age, o.tolerance);

  // The seed row: the seed curve at age 0, or where the youngest particles (released at
  // release_end) are at t, as a polyline through eight times as many particles as the row gets
  // vertices (its chord error is what this row adds).
  const double edge = o.path.engine.edge;
  int count = o.seed_count;
  SeedCurve row = seed;
  if (first_age > 0) {
    const int n = 8 * std::max(2, count > 0 ? count : static_cast<int>(seed.length() / edge) + 1);
    std::vector<Vec3> points;
    for (const double s : seed.sample(n)) {
      const FlowMapGradient moved =
          flow_map_gradient(flow, seed.point(s), o.release_end, t, o.tolerance);
      if (moved.status != FieldStatus::inside)
        throw InvalidArgument("the particle released at s = " + number(s) +
                              " at t = " + number(o.release_end) + " leaves the domain of " +
                              flow.describe() + " before t = " + number(t));
      points.push_back(moved.x);
    }
    if (seed.closed()) points.push_back(points.front());
    row = SeedCurve::polyline(std::move(points), false);
  }
  if (count <= 0) count = static_cast<int>(row.length() / edge) + 1;
  count = std::max(count, 2);

  PathSurfaceOptions p = o.path;
  p.t0 = first_age;
  p.t1 = max_age;
  PathSurfaceResult r = build_path_surface(field, row, count, p);

  StreakLineSurface out;
  out.first_age = first_age;
  out.mesh = std::move(r.mesh);
  out.lifted = std::move(r.spacetime_positions);
  out.report = r.report;
  out.path = r.path;
  Mesh& m = out.mesh;
  const std::size_t n = m.vertex_count();
  m.release_time.resize(n);
  m.age.resize(n);
  m.speed.resize(n);
  m.particle_id.assign(n, -1);
  for (std::size_t i = 0; i < n; ++i) {
    m.age[i] = m.time[i];
    m.release_time[i] = t - m.time[i];
    Vec3 v;
    m.speed[i] =
        flow.velocity(m.positions[i], t, v) == FieldStatus::inside ? v.head<2>().norm() : 0.0;
  }
  out.derived_evaluations = field.derived_evaluations();
  out.flow_evaluations = field.flow_evaluations();
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  return out;
}

}  // namespace orthofront::spacetime
