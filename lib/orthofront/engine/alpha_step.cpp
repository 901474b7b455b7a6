#include "orthofront/engine/alpha_step.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <span>
#include <string>

#include "orthofront/engine/for_range.h"

namespace orthofront {

namespace {

/// `v` rotated left by `shift` (std::rotate(v.begin(), v.begin() + shift, v.end())) into
/// `out`, as two block copies.
template <class T>
void rotated_copy(const std::vector<T>& v, std::size_t shift, std::vector<T>& out) {
  const auto middle = v.begin() + static_cast<std::ptrdiff_t>(shift);
  out.resize(v.size());
  std::copy(v.begin(), middle, std::copy(middle, v.end(), out.begin()));
}

/// `v` rotated in place through `scratch`, which then trades places with v: std::rotate swaps
/// element by element, several times slower on a front's vertices, and a closed front is
/// rotated every step.
template <class T>
void rotate_by_copy(std::vector<T>& v, std::size_t shift, std::vector<T>& scratch) {
  rotated_copy(v, shift, scratch);
  v.swap(scratch);
}

}  // namespace

void solve_alpha_system(const std::vector<double>& p, const std::vector<double>& q,
                        const std::vector<double>& r, const std::vector<double>& speed,
                        std::size_t n, bool closed, bool damping, double speed_limit,
                        AlphaSolver& solver, AlphaSolution& out) {
  out.log_product = 0;
  out.negative = false;
  out.shift = 0;
  out.ok = false;
  out.damped = false;
  const std::vector<double>*rp = &p, *rq = &q, *rr = &r, *rs = &speed;
  if (closed) {
    for (std::size_t i = 0; i < n; ++i) {
      const double ratio = -p[i] / q[i];
      out.negative = out.negative != (ratio < 0);
      out.log_product += std::log(std::abs(ratio));
    }
    std::size_t drop = 0;
    for (std::size_t i = 1; i < n; ++i)
      if (std::abs(r[i]) < std::abs(r[drop])) drop = i;
    // Rotated so that the dropped equation joins the last and the first vertex.
    out.shift = (drop + 1) % n;
    rotated_copy(p, out.shift, out.p);
    rotated_copy(q, out.shift, out.q);
    rotated_copy(r, out.shift, out.r);
    rotated_copy(speed, out.shift, out.speed);
    rp = &out.p, rq = &out.q, rr = &out.r, rs = &out.speed;
  }
  const std::size_t m = n - 1;
  out.aln.resize(n);
  out.kernel.resize(n);
  out.ok = solver
               .solve(std::span<const double>(rp->data(), m), std::span<const double>(rq->data(), m),
                      std::span<const double>(rr->data(), m), out.aln, out.kernel)
               .ok;
  if (!out.ok || !damping) return;
  out.damped = true;
  out.choice =
      choose_damping_mu(out.aln, out.kernel, std::span<const double>(rs->data(), n), speed_limit);
}

template <int N>
AlphaStep<N>::AlphaStep(const Field<N>& field, const StreamSurfaceOptions& options, Mesh& mesh,
                        SurfaceReport& report, StepRecord& record)
    : field_(field), opt_(options), mesh_(mesh), report_(report), record_(record) {
  h_star_ = damping_step(opt_.damping);
}

template <int N>
void AlphaStep<N>::begin_step() {
  ortho_sum_ = 0;
  ortho_count_ = 0;
}

template <int N>
double AlphaStep<N>::orthogonality_mean() const {
  return ortho_count_ ? ortho_sum_ / static_cast<double>(ortho_count_) : 0.0;
}

template <int N>
typename AlphaStep<N>::Outcome AlphaStep<N>::solve(Front<N>& f, std::vector<Vec<N>>& vel,
                                                  std::vector<double>& speed,
                                                  std::vector<double>& alpha,
                                                  std::vector<char>& cut, SegmentTerms<N>* terms,
                                                  AlphaSolution* solution) {
  damping_infeasible_ = false;
  const std::size_t n = f.v.size();
  const std::size_t segments = f.closed ? n : n - 1;
  if (terms) {
    std::swap(terms_, *terms);
  } else {
    terms_.resize(segments);
    const auto at = [&f](std::size_t i) -> const Vec<N>& { return f.v[i].x; };
    segment_loop_.run(segments, opt_.parallel_threshold, [&](std::size_t b, std::size_t e) {
      segment_terms(field_, at, n, vel, b, e, terms_);
    });
  }
  const std::vector<double>& err = terms_.err;
  report_.field_evaluations += segments;
  // One pass: the orthogonality sums count only when every segment had flow.
  bool any_bad = false;
  double sum = ortho_sum_, largest = record_.orthogonality_max;
  for (std::size_t i = 0; i < segments; ++i) {
    if (!terms_.ok[i]) {
      cut[i] = 1;
      any_bad = true;
      continue;
    }
    sum += err[i];
    largest = std::max(largest, err[i]);
  }
  if (any_bad) return Outcome::cut;
  ortho_sum_ = sum;
  ortho_count_ += segments;
  record_.orthogonality_max = largest;
  for (std::size_t i = 0; i < n; ++i)
    if (f.v[i].x == f.v[i].anchor && f.v[i].mesh >= 0) {
      // Vertex error: mean |cos| of the adjacent segments.
      const std::size_t a = f.closed ? previous_index(i, n) : (i == 0 ? 0 : i - 1);
      const std::size_t b = f.closed ? i : std::min(i, segments - 1);
      mesh_.error[static_cast<std::size_t>(f.v[i].mesh)] = 0.5 * (err[a] + err[b]);
    }

  if (solution) {
    std::swap(solution_, *solution);
  } else {
    solve_alpha_system(terms_.p, terms_.q, terms_.r, speed, n, f.closed,
                       opt_.mu_mode == MuMode::damping, opt_.edge / h_star_, solver_, solution_);
  }
  const AlphaSolution& sol = solution_;
  if (f.closed) {
    if (std::abs(sol.log_product) > std::abs(report_.closed_log_product))
      report_.closed_log_product = sol.log_product;
    rotate_by_copy(f.v, sol.shift, front_scratch_);
    rotate_by_copy(vel, sol.shift, vel_scratch_);
    rotate_by_copy(speed, sol.shift, value_scratch_);
    if (sol.negative || std::abs(sol.log_product) > opt_.closed_log_product_limit) {
      // No closed orthogonal front exists here (e.g. a spiral): open the front at the
      // dropped segment instead of folding the mesh.
      f.closed = false;
      report_.closed_front_opened = true;
      report_.message = "closed front opened: ln|prod(-p/q)| = " +
                        std::to_string(sol.log_product) +
                        (sol.negative ? " (negative product)" : "") +
                        "; no closed flow-orthogonal front exists for this seed";
    }
  }
  if (!sol.ok) {
    // Singular system (e.g. a segment of zero length): fall back to uniform advance.
    std::fill(alpha.begin(), alpha.end(), 1.0);
    return Outcome::solved;
  }
  double mu = opt_.mu;
  if (sol.damped) {
    damping_infeasible_ = !sol.choice.feasible;
    if (!sol.choice.feasible) ++report_.infeasible_damping_steps;
    // An unbounded μ means the kernel vanishes on every moving vertex: advance along α^L.
    mu = std::isfinite(sol.choice.mu) ? sol.choice.mu : 0.0;
  }
  for (std::size_t i = 0; i < n; ++i) alpha[i] = sol.aln[i] + mu * sol.kernel[i];
  return Outcome::solved;
}

template <int N>
void AlphaStep<N>::measure_orthogonality(const Front<N>& f, const std::vector<Vec<N>>& vel) {
  const std::size_t n = f.v.size();
  const std::size_t segments = f.closed ? n : n - 1;
  for (std::size_t i = 0; i < segments; ++i) {
    const std::size_t j = next_index(i, n);
    const Vec<N> d = f.v[j].x - f.v[i].x;
    const Vec<N> vm = 0.5 * (vel[i] + vel[j]);
    const double denom = d.norm() * vm.norm();
    const double err = denom > 0 ? std::abs(d.dot(vm)) / denom : 0.0;
    ortho_sum_ += err;
    ++ortho_count_;
    record_.orthogonality_max = std::max(record_.orthogonality_max, err);
  }
}

template <int N>
void AlphaStep<N>::clamp_negative(const Front<N>& f, std::vector<double>& alpha,
                                  const std::vector<double>& speed) {
  const std::size_t n = f.v.size();
  double slow = -1;  // the slow-flow threshold, computed at the first clamp
  for (std::size_t i = 0; i < n; ++i) {
    if (!(alpha[i] < 0)) continue;
    ++report_.negative_alpha;
    if (opt_.negative_alpha != NegativeAlpha::clamp) continue;
    alpha[i] = 0;
    ++report_.clamped_alpha;
    if (slow < 0) slow = opt_.rip_speed_fraction * median_of(speed);
    if (speed[i] < slow)
      ++report_.clamped_slow_flow;
    else if (!f.closed && (i == 0 || i + 1 == n))
      ++report_.clamped_front_end;
    else if (damping_infeasible_)
      ++report_.clamped_infeasible_step;
    else
      ++report_.clamped_ahead;
  }
}

template <int N>
void AlphaStep<N>::raise_lagging(const Front<N>& f, std::vector<double>& alpha) {
  const std::size_t n = f.v.size();
  double lead = -std::numeric_limits<double>::infinity();
  double alpha_max = 0;
  for (std::size_t i = 0; i < n; ++i) {
    lead = std::max(lead, f.v[i].x[opt_.lag_axis]);
    alpha_max = std::max(alpha_max, alpha[i]);
  }
  const double ramp = std::clamp(opt_.lag_ramp, 0.0, 1.0) * opt_.max_lag;
  const double start = opt_.max_lag - ramp;
  for (std::size_t i = 0; i < n; ++i) {
    const double lag = lead - f.v[i].x[opt_.lag_axis];
    if (lag <= start || alpha[i] >= alpha_max) continue;
    double w = 1.0;
    if (ramp > 0 && lag < opt_.max_lag) {
      const double u = (lag - start) / ramp;
      w = u * u * (3 - 2 * u);  // smoothstep: no kink where the ramp begins or ends
    }
    alpha[i] += w * (alpha_max - alpha[i]);
    ++report_.lag_raised_alpha;
  }
}

template class AlphaStep<3>;
template class AlphaStep<4>;

}  // namespace orthofront
