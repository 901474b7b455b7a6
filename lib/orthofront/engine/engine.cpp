#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <numeric>
#include <optional>
#include <string>

#include "orthofront/engine/fold_guard.h"
#include "orthofront/engine/surface_builder.h"
#include "orthofront/error.h"
#include "orthofront/field/field_spec.h"
#include "orthofront/integrate/runge_kutta.h"
#include "orthofront/solve/alpha_solver.h"

namespace orthofront {

const char* to_string(StopReason reason) {
  switch (reason) {
    case StopReason::none:
      return "none";
    case StopReason::steps:
      return "steps";
    case StopReason::vertex_budget:
      return "vertex_budget";
    case StopReason::time_budget:
      return "time_budget";
    case StopReason::fronts_exhausted:
      return "fronts_exhausted";
    case StopReason::left_domain:
      return "left_domain";
    case StopReason::cancelled:
      return "cancelled";
  }
  return "?";
}

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

/// Adds the elapsed time of a scope to one stage counter.
class StageTimer {
 public:
  explicit StageTimer(double& sink) : sink_(sink), start_(Clock::now()) {}
  ~StageTimer() { sink_ += seconds_since(start_); }
  StageTimer(const StageTimer&) = delete;
  StageTimer& operator=(const StageTimer&) = delete;

 private:
  double& sink_;
  Clock::time_point start_;
};

/// Runs body(begin, end) over [0, n): one functor for the serial and the parallel path. `grain`:
/// the smallest chunk worth a task (64 cheap vertex updates; 1 for costly items).
template <typename Body>
void for_range(std::size_t n, std::size_t threshold, const Body& body, std::size_t grain = 64) {
  if (n < threshold) {
    body(std::size_t{0}, n);
    return;
  }
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, grain),
                    [&](const tbb::blocked_range<std::size_t>& r) { body(r.begin(), r.end()); });
}

enum class VertexState : unsigned char { ok, outside, no_data, zero_speed, interrupted };

}  // namespace

template <int N>
class Engine {
 public:
  Engine(const Field<N>& field, const Seed<N>& seed, const StreamSurfaceOptions& options)
      : field_(field), seed_(seed), opt_(options) {
    validate();
    report_.options = opt_;
    tol_.absolute = opt_.tolerance * opt_.edge;
    tol_.relative = opt_.tolerance;
    h_star_ = -std::log(1.0 - opt_.damping);
    integration_stop_ = [this] { return stop_requested(); };
  }

  void set_stop_request(StopRequest request) { stop_request_ = std::move(request); }

  /// Lays the seed as the first front.
  void begin() {
    t_start_ = Clock::now();
    fronts_ = initial_fronts();
  }

  /// Continues from a saved state.
  void restore(EngineState<N> state) {
    t_start_ = Clock::now();
    fronts_ = std::move(state.fronts);
    step_ = state.step;
    died_outside_ = state.died_outside;
    next_front_id_ = state.next_front_id;
    elapsed_before_ = state.elapsed_seconds;
    mesh_ = std::move(state.mesh);
    if (fold_guard_on()) fold_guard_.rebuild(mesh_);
    report_ = std::move(state.report);
    report_.options = opt_;
  }

  EngineState<N> state() const {
    EngineState<N> s;
    s.fronts = fronts_;
    s.step = step_;
    s.died_outside = died_outside_;
    s.next_front_id = next_front_id_;
    s.elapsed_seconds = elapsed();
    s.mesh = mesh_;
    s.report = report_;
    return s;
  }

  double elapsed() const { return elapsed_before_ + seconds_since(t_start_); }

  bool next() {
    if (reason_ != StopReason::none) return false;
    if (fronts_.empty())
      reason_ = died_outside_ ? StopReason::left_domain : StopReason::fronts_exhausted;
    else if (step_ >= opt_.max_steps)
      reason_ = StopReason::steps;
    else if (mesh_.vertex_count() >= opt_.max_vertices)
      reason_ = StopReason::vertex_budget;
    else if (elapsed() > opt_.time_budget_seconds)
      reason_ = StopReason::time_budget;
    return reason_ == StopReason::none;
  }

  void cancel() {
    reason_ = StopReason::cancelled;
    report_.complete = false;
  }

  FrontSnapshot front() {
    front_positions_.clear();
    for (const auto& f : fronts_)
      for (const auto& fv : f.v)
        for (int i = 0; i < N; ++i) front_positions_.push_back(fv.x[i]);
    return FrontSnapshot{step_ + 1, N, front_positions_};
  }

  Progress progress() const {
    Progress p{step_, opt_.max_steps, mesh_.vertex_count(), fronts_.size(), 0, elapsed()};
    for (const auto& f : fronts_) p.front_vertices += f.v.size();
    return p;
  }

  int steps_done() const { return step_; }

  void step() {
    ++step_;
    step_record_ = StepRecord{};
    step_record_.step = step_;
    step_record_.h_min = std::numeric_limits<double>::infinity();
    ortho_sum_ = 0;
    ortho_count_ = 0;
    exits_this_step_ = 0;
    std::vector<Front<N>> next;
    std::vector<Front<N>> queue = std::move(fronts_);
    fronts_.clear();
    while (!queue.empty()) {
      Front<N> f = std::move(queue.back());
      queue.pop_back();
      advance_front(std::move(f), step_, queue, next);
    }
    fronts_ = std::move(next);
    died_outside_ = fronts_.empty() && exits_this_step_ > 0;
    if (stopping_) {
      // Integrations stopped part-way: the fronts end where they got to (a valid mesh).
      reason_ = stopped_by_budget_ ? StopReason::time_budget : StopReason::cancelled;
      if (reason_ == StopReason::cancelled) report_.complete = false;
    }
    step_record_.fronts = fronts_.size();
    for (const auto& f : fronts_) step_record_.front_vertices += f.v.size();
    step_record_.orthogonality_mean = ortho_count_ ? ortho_sum_ / ortho_count_ : 0.0;
    if (!std::isfinite(step_record_.h_min)) step_record_.h_min = 0;
    report_.per_step.push_back(step_record_);
  }

  SurfaceResult finish() {
    // (Decided by the report, which a saved state keeps: a resumed run ends with the same mesh.)
    if (report_.fold_rips > 0) mesh_.remove_unused_vertices();
    report_.stop_reason = reason_;
    report_.steps = step_;
    report_.vertices = mesh_.vertex_count();
    report_.faces = mesh_.face_count();
    report_.quads = static_cast<std::size_t>(std::count_if(
        mesh_.faces.begin(), mesh_.faces.end(), [](const Face& f) { return f.is_quad(); }));
    report_.triangles = report_.faces - report_.quads;
    if (opt_.measure_quality) {
      StageTimer timer(report_.times.quality);
      report_.quality = measure_quality(mesh_);
    }
    report_.times.total = elapsed();
    return SurfaceResult{std::move(mesh_), std::move(report_)};
  }

 private:
  void validate() const {
    auto positive = [](double v) { return std::isfinite(v) && v > 0; };
    if (!positive(opt_.edge))
      throw InvalidArgument("edge length must be positive and finite, got " +
                            std::to_string(opt_.edge));
    if (opt_.max_steps < 0)
      throw InvalidArgument("step count must not be negative, got " +
                            std::to_string(opt_.max_steps));
    if (!(opt_.damping > 0 && opt_.damping < 1))
      throw InvalidArgument("damping must lie in (0, 1), got " + std::to_string(opt_.damping));
    if (!std::isfinite(opt_.mu) || opt_.mu < 0)
      throw InvalidArgument("mu must be finite and >= 0, got " + std::to_string(opt_.mu));
    if (!(opt_.split_factor > 1.0) || !(opt_.merge_factor > 0) ||
        opt_.merge_factor >= 2 * opt_.split_factor)
      throw InvalidArgument("split/merge factors must satisfy split > 1, 0 < merge < 2 split");
    if (!positive(opt_.tolerance)) throw InvalidArgument("tolerance must be positive");
    if (!seed_.point) throw InvalidArgument("seed curve has no point function");
    if (seed_.parameters.size() < 2)
      throw InvalidArgument("a seed needs at least 2 vertices, got " +
                            std::to_string(seed_.parameters.size()));
    if (seed_.parameters.size() > opt_.max_vertices)
      throw InvalidArgument("a seed of " + std::to_string(seed_.parameters.size()) +
                            " vertices exceeds the vertex budget of " +
                            std::to_string(opt_.max_vertices) + " (--max-vertices)");
    // The first front step refines the seed to edges of about ℓ: a seed far longer than the
    // vertex budget allows would exhaust memory inside that one step.
    double length = 0;
    for (std::size_t i = 1; i < seed_.parameters.size(); ++i)
      length += (seed_.point(seed_.parameters[i]) - seed_.point(seed_.parameters[i - 1])).norm();
    if (length / opt_.edge > static_cast<double>(opt_.max_vertices))
      throw InvalidArgument("edge length " + format_parameter(opt_.edge) + " would put about " +
                            format_parameter(length / opt_.edge) + " vertices on the seed curve (length " +
                            format_parameter(length) + "), more than the vertex budget of " +
                            std::to_string(opt_.max_vertices) +
                            " (--max-vertices); raise --edge");
  }

  std::int32_t emit(const FrontVertex<N>& fv, double alpha, std::int32_t front, int step) {
    const Vec3 p = fv.x.template head<3>();
    // Closed seeds wrap s into [0, 1); on open seeds s = 1 is the end of the curve.
    const double s = seed_.closed ? fv.s - std::floor(fv.s) : fv.s;
    return mesh_.add_vertex(p, fv.t, alpha, s, 0.0, front, step);
  }

  std::vector<Front<N>> initial_fronts() {
    Front<N> f;
    f.closed = seed_.closed;
    f.id = next_front_id_++;
    report_.closed_seed = seed_.closed;
    for (double s : seed_.parameters) {
      FrontVertex<N> fv;
      fv.s = s;
      fv.x = seed_.point(s);
      fv.anchor = fv.x;
      f.v.push_back(fv);
    }
    // Vertices outside the domain or in no-data cells cut the seed into several fronts.
    std::vector<char> keep(f.v.size(), 1);
    std::size_t inside = 0;
    for (std::size_t i = 0; i < f.v.size(); ++i) {
      Vec<N> v;
      keep[i] = field_.velocity(f.v[i].x, v) == FieldStatus::inside;
      inside += keep[i] ? 1 : 0;
    }
    if (inside < 2)
      throw InvalidArgument("seed curve has " + std::to_string(inside) +
                            " vertices inside the field's domain; at least 2 are needed");
    std::vector<Front<N>> out;
    std::vector<char> cut(f.v.size(), 0);
    for (auto& part : split(std::move(f), keep, cut)) {
      for (auto& fv : part.v) fv.mesh = emit(fv, 0.0, part.id, 0);
      for (auto& piece : adapt_and_link(std::move(part), nullptr, 0))
        if (piece.v.size() >= 2) out.push_back(std::move(piece));
    }
    if (opt_.method == Method::timeline) {
      report_.timeline_step = opt_.timeline_step;
      if (!(report_.timeline_step > 0)) {
        std::vector<double> speeds;
        for (const auto& fr : out)
          for (const auto& fv : fr.v) {
            Vec<N> v;
            if (field_.velocity(fv.x, v) == FieldStatus::inside) speeds.push_back(v.norm());
          }
        std::nth_element(speeds.begin(), speeds.begin() + static_cast<long>(speeds.size() / 2),
                         speeds.end());
        const double median = speeds.empty() ? 0.0 : speeds[speeds.size() / 2];
        if (!(median > 0))
          throw InvalidArgument("velocity is zero along the seed; the timeline step is undefined");
        report_.timeline_step = opt_.edge / median;
      }
    }
    return out;
  }

  /// Splits a front at vertices with keep[i] == 0 (removed) and after segments with
  /// cut[i] != 0 (segment i joins i and i+1). Parts with fewer than two vertices are dropped.
  std::vector<Front<N>> split(Front<N>&& f, const std::vector<char>& keep,
                              const std::vector<char>& cut) {
    const std::size_t n = f.v.size();
    bool any = false;
    for (std::size_t i = 0; i < n; ++i) any = any || !keep[i] || cut[i];
    std::vector<Front<N>> parts;
    if (!any) {
      parts.push_back(std::move(f));
      return parts;
    }
    // For a closed front start right after a break, so every part is a contiguous run.
    std::size_t start = 0;
    if (f.closed) {
      for (std::size_t i = 0; i < n; ++i) {
        if (!keep[i]) {
          start = i;
          break;
        }
        if (cut[i]) {
          start = (i + 1) % n;
          break;
        }
      }
    }
    Front<N> current;
    // The first part keeps the front's id; further parts are new fronts.
    auto flush = [&]() {
      if (current.v.size() >= 2) {
        if (parts.empty()) {
          current.id = f.id;
        } else {
          current.id = next_front_id_++;
          ++report_.fronts_created;
        }
        parts.push_back(std::move(current));
      }
      current = Front<N>{};
    };
    for (std::size_t k = 0; k < n; ++k) {
      const std::size_t i = (start + k) % n;
      if (!keep[i]) {
        flush();
        continue;
      }
      current.v.push_back(f.v[i]);
      if (cut[i] && (f.closed || i + 1 < n)) flush();
    }
    flush();
    return parts;
  }

  static double median_of(std::vector<double> values) {
    if (values.empty()) return 0;
    const auto mid = values.begin() + static_cast<long>(values.size() / 2);
    std::nth_element(values.begin(), mid, values.end());
    return *mid;
  }

  /// One front step for one front. Fronts that must be cut first go back to `queue`.
  void advance_front(Front<N>&& f, int step, std::vector<Front<N>>& queue,
                     std::vector<Front<N>>& next) {
    const std::size_t n = f.v.size();
    if (n < 2) return;
    if (cut_stalled(f, step, queue)) return;
    vel_.resize(n);
    speed_.resize(n);
    alpha_.assign(n, 1.0);
    state_.assign(n, VertexState::ok);
    double h = 0;
    {
      StageTimer timer(report_.times.alpha);
      for_range(n, opt_.parallel_threshold, [&](std::size_t b, std::size_t e) {
        for (std::size_t i = b; i < e; ++i) {
          const FieldStatus st = field_.velocity(f.v[i].x, vel_[i]);
          state_[i] = st == FieldStatus::inside    ? VertexState::ok
                      : st == FieldStatus::outside ? VertexState::outside
                                                   : VertexState::no_data;
          speed_[i] = st == FieldStatus::inside ? vel_[i].norm() : 0.0;
        }
      });
      report_.field_evaluations += n;
      // Cut where a vertex has no usable flow: outside, no data, or vanishing speed.
      const double median = median_of(speed_);
      std::vector<char> keep(n, 1), cut(n, 0);
      bool broken = false;
      for (std::size_t i = 0; i < n; ++i) {
        if (state_[i] == VertexState::ok && !(speed_[i] > opt_.zero_speed_fraction * median)) {
          state_[i] = VertexState::zero_speed;
          ++report_.zero_velocity_cuts;
        }
        if (state_[i] != VertexState::ok) {
          keep[i] = 0;
          broken = true;
          if (state_[i] == VertexState::outside) ++report_.domain_exits, ++exits_this_step_;
          if (state_[i] == VertexState::no_data) ++report_.no_data_hits;
        }
      }
      if (broken) {
        for (auto& part : split(std::move(f), keep, cut)) queue.push_back(std::move(part));
        return;
      }
      if (opt_.method == Method::orthogonal) {
        const AlphaOutcome outcome = solve_alpha(f, cut);
        if (outcome == AlphaOutcome::cut) {
          for (auto& part : split(std::move(f), keep, cut)) queue.push_back(std::move(part));
          return;
        }
      } else {
        measure_orthogonality(f);
      }
    }
    if (opt_.method == Method::orthogonal && opt_.rip) {
      StageTimer timer(report_.times.rip);
      std::vector<char> keep(n, 1), cut(n, 0);
      if (find_rips(f, keep)) {
        for (auto& part : split(std::move(f), keep, cut)) queue.push_back(std::move(part));
        return;
      }
    }
    // Front step h (α-time); negative α handling.
    if (opt_.method == Method::orthogonal) {
      double max_speed = 0;
      double slow = -1;  // the slow-flow threshold, computed at the first clamp
      for (std::size_t i = 0; i < n; ++i) {
        if (alpha_[i] < 0) {
          ++report_.negative_alpha;
          if (opt_.negative_alpha == NegativeAlpha::clamp) {
            alpha_[i] = 0;
            ++report_.clamped_alpha;
            if (slow < 0) slow = opt_.rip_speed_fraction * median_of(speed_);
            if (speed_[i] < slow)
              ++report_.clamped_slow_flow;
            else if (!f.closed && (i == 0 || i + 1 == n))
              ++report_.clamped_front_end;
            else if (damping_infeasible_)
              ++report_.clamped_infeasible_step;
            else
              ++report_.clamped_ahead;
          }
        }
      }
      if (opt_.lag_axis >= 0 && opt_.lag_axis < N && opt_.max_lag > 0) raise_lagging(f);
      for (std::size_t i = 0; i < n; ++i)
        max_speed = std::max(max_speed, std::abs(alpha_[i]) * speed_[i]);
      if (!(max_speed > 0)) {
        ++report_.fronts_stalled;  // α vanished everywhere: this front cannot advance
        return;
      }
      h = opt_.edge / max_speed;
      h = std::min(h, opt_.mu_mode == MuMode::damping ? h_star_ : opt_.paper_max_step);
    } else {
      h = report_.timeline_step;
    }
    step_record_.h_min = std::min(step_record_.h_min, h);
    step_record_.h_max = std::max(step_record_.h_max, h);
    for (std::size_t i = 0; i < n; ++i)
      if (f.v[i].mesh >= 0 && f.v[i].x == f.v[i].anchor)
        mesh_.alpha[static_cast<std::size_t>(f.v[i].mesh)] = alpha_[i];

    // Advance every vertex along its stream line by τ_i = α_i h.
    Front<N> nf;
    nf.closed = f.closed;
    nf.id = f.id;
    nf.v.resize(n);
    std::vector<char> keep(n, 1), cut(n, 0);
    {
      StageTimer timer(report_.times.advance);
      std::vector<int> evaluations(n, 0);
      for_range(n, opt_.parallel_threshold, [&](std::size_t b, std::size_t e) {
        for (std::size_t i = b; i < e; ++i) {
          const double tau = alpha_[i] * h;
          FrontVertex<N> fv = f.v[i];
          fv.origin = static_cast<std::int32_t>(i);
          if (stopping_.load(std::memory_order_relaxed)) {
            keep[i] = 0;  // the run stops: this stream line ends at its last mesh vertex
            state_[i] = VertexState::interrupted;
          } else if (tau != 0) {
            const IntegrationResult<N> r = integrate(fv.x, tau);
            evaluations[i] = r.evaluations;
            fv.x = r.x;
            fv.t += r.reached;
            if (r.status != FieldStatus::inside) keep[i] = 0;
            state_[i] = r.interrupted                     ? VertexState::interrupted
                        : r.status == FieldStatus::outside ? VertexState::outside
                        : r.status == FieldStatus::inside  ? VertexState::ok
                                                           : VertexState::no_data;
          }
          nf.v[i] = fv;
        }
      });
      report_.vertex_steps += n;
      for (std::size_t i = 0; i < n; ++i) {
        report_.field_evaluations += static_cast<std::size_t>(evaluations[i]);
        if (state_[i] == VertexState::outside) ++report_.domain_exits, ++exits_this_step_;
        if (state_[i] == VertexState::no_data) ++report_.no_data_hits;
      }
    }
    // Vertices that left the domain end their stream lines at the last valid point: keep that
    // point in the mesh, but not in the front.
    for (auto& part : split(std::move(nf), keep, cut)) {
      for (auto& piece : adapt_and_link(std::move(part), &f, step)) {
        if (piece.v.size() < 2 || too_short(piece)) {
          ++report_.fronts_dropped_short;
          continue;
        }
        next.push_back(std::move(piece));
      }
    }
  }

  /// Takes the vertices that stopped advancing (StreamSurfaceOptions::stall_steps) out of the
  /// front; the parts left go back to `queue`. Returns whether any was.
  bool cut_stalled(Front<N>& f, int step, std::vector<Front<N>>& queue) {
    if (opt_.stall_steps <= 0 || opt_.method != Method::orthogonal || step <= opt_.stall_steps)
      return false;
    const std::size_t n = f.v.size();
    std::vector<char> keep(n, 1), cut(n, 0);
    bool any = false;
    for (std::size_t i = 0; i < n; ++i) {
      const std::int32_t m = f.v[i].mesh;
      if (m < 0 || step - mesh_.step[static_cast<std::size_t>(m)] <= opt_.stall_steps) continue;
      keep[i] = 0;
      any = true;
      ++report_.stall_cuts;
    }
    if (!any) return false;
    for (auto& part : split(std::move(f), keep, cut)) queue.push_back(std::move(part));
    return true;
  }

  /// The lag bound: vertices behind the lead along lag_axis have their α raised towards the
  /// front's largest α, smoothly from lag (1 - lag_ramp)·max_lag to all of it at max_lag, so they
  /// keep pace instead of falling further behind while neighbours' α differ little (a step in α
  /// between neighbours tilts the front and folds it; see StreamSurfaceOptions::max_lag).
  void raise_lagging(const Front<N>& f) {
    const std::size_t n = f.v.size();
    double lead = -std::numeric_limits<double>::infinity();
    double alpha_max = 0;
    for (std::size_t i = 0; i < n; ++i) {
      lead = std::max(lead, f.v[i].x[opt_.lag_axis]);
      alpha_max = std::max(alpha_max, alpha_[i]);
    }
    const double ramp = std::clamp(opt_.lag_ramp, 0.0, 1.0) * opt_.max_lag;
    const double start = opt_.max_lag - ramp;
    for (std::size_t i = 0; i < n; ++i) {
      const double lag = lead - f.v[i].x[opt_.lag_axis];
      if (lag <= start || alpha_[i] >= alpha_max) continue;
      double w = 1.0;
      if (ramp > 0 && lag < opt_.max_lag) {
        const double u = (lag - start) / ramp;
        w = u * u * (3 - 2 * u);  // smoothstep: no kink where the ramp begins or ends
      }
      alpha_[i] += w * (alpha_max - alpha_[i]);
      ++report_.lag_raised_alpha;
    }
  }

  enum class AlphaOutcome { solved, cut };

  /// Builds p, q, r, solves for α (into alpha_), chooses μ. Closed fronts drop the equation
  /// with the smallest |r| (rotating the front so it becomes the closing segment).
  AlphaOutcome solve_alpha(Front<N>& f, std::vector<char>& cut) {
    damping_infeasible_ = false;
    const std::size_t n = f.v.size();
    const std::size_t segments = f.closed ? n : n - 1;
    p_.resize(segments);
    q_.resize(segments);
    r_.resize(segments);
    seg_ok_.assign(segments, 1);
    seg_err_.resize(segments);
    for_range(segments, opt_.parallel_threshold, [&](std::size_t b, std::size_t e) {
      Vec<N> vm;
      Mat<N> jm;
      for (std::size_t i = b; i < e; ++i) {
        const std::size_t j = (i + 1) % n;
        const Vec<N> d = f.v[j].x - f.v[i].x;
        const Vec<N> mid = 0.5 * (f.v[i].x + f.v[j].x);
        if (field_.velocity_jacobian(mid, vm, jm) != FieldStatus::inside) {
          seg_ok_[i] = 0;
          continue;
        }
        p_[i] = 0.5 * d.dot(jm * vel_[i]) - vel_[i].dot(vm);
        q_[i] = 0.5 * d.dot(jm * vel_[j]) + vel_[j].dot(vm);
        r_[i] = d.dot(vm);
        const double denom = d.norm() * vm.norm();
        seg_err_[i] = denom > 0 ? std::abs(r_[i]) / denom : 0.0;
      }
    });
    report_.field_evaluations += segments;
    bool any_bad = false;
    for (std::size_t i = 0; i < segments; ++i)
      if (!seg_ok_[i]) {
        cut[i] = 1;
        any_bad = true;
      }
    if (any_bad) return AlphaOutcome::cut;
    for (std::size_t i = 0; i < segments; ++i) {
      ortho_sum_ += seg_err_[i];
      ++ortho_count_;
      step_record_.orthogonality_max = std::max(step_record_.orthogonality_max, seg_err_[i]);
    }
    for (std::size_t i = 0; i < n; ++i)
      if (f.v[i].x == f.v[i].anchor && f.v[i].mesh >= 0) {
        // Vertex error: mean |cos| of the adjacent segments.
        const std::size_t a = f.closed ? (i + n - 1) % n : (i == 0 ? 0 : i - 1);
        const std::size_t b = f.closed ? i : std::min(i, segments - 1);
        mesh_.error[static_cast<std::size_t>(f.v[i].mesh)] = 0.5 * (seg_err_[a] + seg_err_[b]);
      }

    if (f.closed) {
      double log_product = 0;
      bool negative = false;
      for (std::size_t i = 0; i < n; ++i) {
        const double ratio = -p_[i] / q_[i];
        negative = negative != (ratio < 0);
        log_product += std::log(std::abs(ratio));
      }
      if (std::abs(log_product) > std::abs(report_.closed_log_product))
        report_.closed_log_product = log_product;
      std::size_t drop = 0;
      for (std::size_t i = 1; i < n; ++i)
        if (std::abs(r_[i]) < std::abs(r_[drop])) drop = i;
      // Rotate so the dropped equation joins the last and the first vertex.
      const auto shift = static_cast<long>((drop + 1) % n);
      std::rotate(f.v.begin(), f.v.begin() + shift, f.v.end());
      std::rotate(vel_.begin(), vel_.begin() + shift, vel_.end());
      std::rotate(speed_.begin(), speed_.begin() + shift, speed_.end());
      std::rotate(p_.begin(), p_.begin() + shift, p_.end());
      std::rotate(q_.begin(), q_.begin() + shift, q_.end());
      std::rotate(r_.begin(), r_.begin() + shift, r_.end());
      if (negative || std::abs(log_product) > opt_.closed_log_product_limit) {
        // No closed orthogonal front exists here (e.g. a spiral): open the front at the
        // dropped segment instead of folding the mesh.
        f.closed = false;
        report_.closed_front_opened = true;
        report_.message = "closed front opened: ln|prod(-p/q)| = " + std::to_string(log_product) +
                          (negative ? " (negative product)" : "") +
                          "; no closed flow-orthogonal front exists for this seed";
      }
    }
    const std::size_t m = n - 1;
    aln_.resize(n);
    kernel_.resize(n);
    const AlphaSolver::Result res =
        solver_.solve(std::span<const double>(p_.data(), m), std::span<const double>(q_.data(), m),
                      std::span<const double>(r_.data(), m), aln_, kernel_);
    if (!res.ok) {
      // Singular system (e.g. a segment of zero length): fall back to uniform advance.
      std::fill(alpha_.begin(), alpha_.end(), 1.0);
      return AlphaOutcome::solved;
    }
    double mu = opt_.mu;
    if (opt_.mu_mode == MuMode::damping) {
      const DampingChoice choice = choose_damping_mu(
          aln_, kernel_, std::span<const double>(speed_.data(), n), opt_.edge / h_star_);
      damping_infeasible_ = !choice.feasible;
      if (!choice.feasible) ++report_.infeasible_damping_steps;
      // An unbounded μ means the kernel vanishes on every moving vertex: advance along α^L.
      mu = std::isfinite(choice.mu) ? choice.mu : 0.0;
    }
    for (std::size_t i = 0; i < n; ++i) alpha_[i] = aln_[i] + mu * kernel_[i];
    return AlphaOutcome::solved;
  }

  void measure_orthogonality(const Front<N>& f) {
    const std::size_t n = f.v.size();
    const std::size_t segments = f.closed ? n : n - 1;
    for (std::size_t i = 0; i < segments; ++i) {
      const std::size_t j = (i + 1) % n;
      const Vec<N> d = f.v[j].x - f.v[i].x;
      const Vec<N> vm = 0.5 * (vel_[i] + vel_[j]);
      const double denom = d.norm() * vm.norm();
      const double err = denom > 0 ? std::abs(d.dot(vm)) / denom : 0.0;
      ortho_sum_ += err;
      ++ortho_count_;
      step_record_.orthogonality_max = std::max(step_record_.orthogonality_max, err);
    }
  }

  /// Sharp, slow peaks of α mark separating stream lines: their vertices are removed.
  bool find_rips(const Front<N>& f, std::vector<char>& keep) {
    const std::size_t n = f.v.size();
    if (n < 3) return false;
    const double median = median_of(speed_);
    bool any = false;
    const std::size_t first = f.closed ? 0 : 1;
    const std::size_t last = f.closed ? n : n - 1;
    for (std::size_t i = first; i < last; ++i) {
      const double a = alpha_[i];
      const double am = alpha_[(i + n - 1) % n];
      const double ap = alpha_[(i + 1) % n];
      if (!(a > 0 && a > am && a > ap)) continue;
      const double sharpness = 1.0 - (am + ap) / (2.0 * a);
      if (sharpness > opt_.rip_sharpness && speed_[i] < opt_.rip_speed_fraction * median) {
        keep[i] = 0;
        any = true;
        ++report_.rips;
      }
    }
    return any;
  }

  IntegrationResult<N> integrate(const Vec<N>& x, double tau) const {
    if (opt_.integrator == IntegratorKind::rk4)
      return integrate_rk4(field_, x, tau, opt_.rk4_substeps);
    return integrate_dopri5(field_, x, tau, tol_, 0, &integration_stop_);
  }

  /// Whether the caller's stop request or the time budget ends the run inside a step: asked by
  /// long integrations (runge_kutta.h) from worker threads; once true, stays true.
  bool stop_requested() const {
    if (stopping_.load(std::memory_order_relaxed)) return true;
    const bool budget = elapsed() > opt_.time_budget_seconds;
    if (!budget && !(stop_request_ && stop_request_())) return false;
    if (budget) stopped_by_budget_ = true;
    stopping_ = true;
    return true;
  }

  bool too_short(const Front<N>& f) const {
    double length = 0;
    for (std::size_t i = 0; i + 1 < f.v.size(); ++i) length += (f.v[i + 1].x - f.v[i].x).norm();
    if (f.closed && f.v.size() > 1) length += (f.v.front().x - f.v.back().x).norm();
    return length < opt_.edge;
  }

  /// Point at fraction λ of segment i → i+1 of front f (positions only), Catmull-Rom on the
  /// front with reflected end points.
  Vec<N> cubic_point(const Front<N>& f, std::size_t i, double lambda) const {
    const std::size_t n = f.v.size();
    const std::size_t j = (i + 1) % n;
    const Vec<N>& p1 = f.v[i].x;
    const Vec<N>& p2 = f.v[j].x;
    Vec<N> p0, p3;
    if (f.closed || i > 0)
      p0 = f.v[(i + n - 1) % n].x;
    else
      p0 = 2 * p1 - p2;
    if (f.closed || j + 1 < n)
      p3 = f.v[(j + 1) % n].x;
    else
      p3 = 2 * p2 - p1;
    const double t = lambda, t2 = t * t, t3 = t2 * t;
    return 0.5 * ((2 * p1) + (-p0 + p2) * t + (2 * p0 - 5 * p1 + 4 * p2 - p3) * t2 +
                  (-p0 + 3 * p1 - 3 * p2 + p3) * t3);
  }

  /// Merge short segments, split long ones, decide which vertices get new mesh vertices, and
  /// stitch faces between the previous front `old` (nullptr for the seed) and `f`. Returns the
  /// parts of `f`: more than one where split_long cut it at segments no stream line can fill.
  std::vector<Front<N>> adapt_and_link(Front<N>&& f, const Front<N>* old, int step) {
    std::vector<Front<N>> parts;
    const std::size_t first_inserted = mesh_.vertex_count();
    {
      StageTimer timer(report_.times.adapt);
      merge_short(f);
      std::vector<char> cut;
      if (split_long(f, old, step, cut)) {
        parts = split(std::move(f), std::vector<char>(cut.size(), 1), cut);
      } else {
        parts.push_back(std::move(f));
      }
    }
    StageTimer timer(report_.times.stitch);
    if (!old) return parts;
    if (!fold_guard_on()) {
      for (auto& part : parts) {
        emit_moved(part, *old, step);
        stitch(*old, part);
      }
      return parts;
    }
    std::vector<Front<N>> linked;
    for (auto& part : parts) link_guarded(std::move(part), *old, step, first_inserted, linked);
    return linked;
  }

  bool fold_guard_on() const { return opt_.fold_guard && opt_.method == Method::orthogonal; }

  /// Emits and stitches one part; where a face of the strip folds over a neighbour (fold_guard.h)
  /// the strip is undone, the vertices standing on the fold leave the front (a local rip: their
  /// stream lines end at their previous mesh vertices) and the rest is stitched again, up to
  /// three times. Folds left after that stay in the mesh, counted in the report. Vertices
  /// inserted this step (mesh vertices from first_inserted on) may stand on a fold too; one taken
  /// out leaves a mesh vertex no face uses, which finish() removes when the guard ripped.
  void link_guarded(Front<N>&& part, const Front<N>& old, int step, std::size_t first_inserted,
                    std::vector<Front<N>>& out) {
    constexpr int kRounds = 3;
    std::vector<Front<N>> pieces;
    pieces.push_back(std::move(part));
    for (int round = 0;; ++round) {
      const std::size_t vertices = mesh_.vertex_count(), faces = mesh_.face_count();
      const std::size_t skipped = report_.skipped_vertex_steps;
      std::vector<std::int32_t> folded;
      for (auto& piece : pieces) {
        const std::size_t first_face = mesh_.face_count();
        emit_moved(piece, old, step);
        stitch(old, piece);
        const auto found = fold_guard_.folded_vertices(mesh_, first_face, first_inserted);
        folded.insert(folded.end(), found.begin(), found.end());
      }
      if (folded.empty() || round + 1 == kRounds) {
        if (!folded.empty()) report_.folds_left += folded.size();
        fold_guard_.accept(mesh_, faces);
        for (auto& piece : pieces) out.push_back(std::move(piece));
        return;
      }
      // Undo the round and take the folded vertices out of their pieces.
      mesh_.truncate(vertices, faces);
      report_.skipped_vertex_steps = skipped;
      std::sort(folded.begin(), folded.end());
      std::vector<Front<N>> next;
      for (std::size_t p = 0; p < pieces.size(); ++p) {
        Front<N>& linked = pieces[p];
        std::vector<char> keep(linked.v.size(), 1), cut(linked.v.size(), 0);
        for (std::size_t i = 0; i < linked.v.size(); ++i) {
          FrontVertex<N>& fv = linked.v[i];
          if (std::binary_search(folded.begin(), folded.end(), fv.mesh)) {
            keep[i] = 0;
            ++report_.fold_rips;
          }
          // A mesh vertex emit_moved gave it this round is gone: it stands for its origin's again
          // (it was a copy of that vertex before; inserted vertices are older than `vertices`).
          if (fv.origin >= 0 && fv.mesh >= 0 && static_cast<std::size_t>(fv.mesh) >= vertices) {
            const FrontVertex<N>& from = old.v[static_cast<std::size_t>(fv.origin)];
            fv.mesh = from.mesh;
            fv.anchor = from.anchor;
          }
        }
        for (auto& piece : split(std::move(pieces[p]), keep, cut)) next.push_back(std::move(piece));
      }
      pieces = std::move(next);
    }
  }

  void merge_short(Front<N>& f) {
    const std::size_t n = f.v.size();
    if (n < 3) return;
    const double limit = opt_.merge_factor * opt_.edge;
    std::vector<FrontVertex<N>> out;
    out.reserve(n);
    out.push_back(f.v[0]);
    // A vertex that keeps its mesh vertex between two others that keep theirs is not merged:
    // the three old mesh vertices would close a flat triangle on the previous front.
    const double still = opt_.row_skip == RowSkip::off ? 0.0 : opt_.skip_fraction * opt_.edge;
    const auto waiting = [still](const FrontVertex<N>& fv) {
      return fv.origin >= 0 && (fv.x - fv.anchor).norm() <= still;
    };
    // Nor is one between two that did not move at all (α clamped to 0): neither can be given a
    // new mesh vertex (see renew_across_merges), so every face across the merge would be made of
    // old mesh vertices only.
    const auto stuck = [this](const FrontVertex<N>& a, const FrontVertex<N>& b) {
      return !has_moved(a) && !has_moved(b);
    };
    for (std::size_t i = 1; i + 1 < n; ++i) {
      const double joined = (f.v[i].x - out.back().x).norm() + (f.v[i + 1].x - f.v[i].x).norm();
      // A closed front keeps three vertices at least: with two, both of its segments join the
      // same two vertices, and the faces stitched to them share both edges (non-manifold).
      const bool loop_kept = !f.closed || out.size() + (n - 1 - i) >= 3;
      if (joined < limit && loop_kept &&
          !(waiting(out.back()) && waiting(f.v[i]) && waiting(f.v[i + 1])) &&
          !stuck(out.back(), f.v[i + 1])) {
        ++report_.merges;
        continue;
      }
      out.push_back(f.v[i]);
    }
    out.push_back(f.v[n - 1]);
    if (f.closed && out.size() > 3 && !stuck(out[out.size() - 2], out.front())) {
      // The closing pair: drop the last vertex when it and its closing segment are short.
      const double joined =
          (out.back().x - out[out.size() - 2].x).norm() + (out.front().x - out.back().x).norm();
      if (joined < limit) {
        out.pop_back();
        ++report_.merges;
      }
    }
    f.v = std::move(out);
  }

  /// A vertex to insert at fraction λ of segment i, and where it went.
  struct InsertionJob {
    std::size_t segment = 0;
    double lambda = 0, s = 0, t = 0;
    Vec<N> x = Vec<N>::Zero();
    int evaluations = 0;
    enum class Outcome : unsigned char {
      seed,
      streamline,
      previous_row,
      fallback,
      interpolated
    } outcome{};
    bool left_domain = false;  ///< a fallback whose stream line left the domain or met no data
  };

  /// Splits segments longer than split_factor·ℓ with vertices on the stream lines of seed
  /// parameters between those of their ends. Where the seed parameter cannot tell those stream
  /// lines apart any more (some of them would start from the seed point of an end or of another
  /// insertion on the segment), the segment is cut instead: cut[k] != 0 after vertex k of the
  /// returned front (split's convention); returns whether any segment was cut.
  ///
  /// Near a separating stream line, neighbouring stream lines diverge exponentially and
  /// insertions halve the seed interval between front vertices every step or so, until it is
  /// below the resolution of a double (abc: about 23 steps). Vertices inserted after that share
  /// the seed parameter and so the stream line of an end: the front runs along that one stream
  /// line, and every vertex inserted there stays on it, moving only along it. The front then
  /// grows a fold of zero width that stitch fills with zero-area faces (with α < 0 kept it settles
  /// into a cycle that emits new mesh vertices exactly on the previous step's), and with a mesh
  /// vertex every few 1e-6 along the stream line (T-junctions). No surface lies between such
  /// ends: the surface tears there, as at a rip.
  bool split_long(Front<N>& f, const Front<N>* old, int step, std::vector<char>& cut) {
    const std::size_t n = f.v.size();
    const double limit = opt_.split_factor * opt_.edge;
    const std::size_t segments = f.closed ? n : n - 1;
    jobs_.clear();
    std::vector<char> unresolved(n, 0);
    bool any_cut = false;
    const auto seed_point = [this](double s) {
      return seed_.point(seed_.closed ? s - std::floor(s) : s);
    };
    for (std::size_t i = 0; i < segments; ++i) {
      const std::size_t j = (i + 1) % n;
      const double length = (f.v[j].x - f.v[i].x).norm();
      if (!(length > limit)) continue;
      const int pieces = static_cast<int>(std::ceil(length / opt_.edge));
      double s_next = f.v[j].s;
      if (f.closed && j == 0) s_next += 1.0;  // wrap the seed parameter on the closing segment
      const std::size_t first = jobs_.size();
      Vec<N> previous = seed_point(f.v[i].s);
      const Vec<N> last = seed_point(s_next);
      bool resolved = true;
      for (int k = 1; k < pieces && resolved; ++k) {
        InsertionJob job;
        job.segment = i;
        job.lambda = static_cast<double>(k) / pieces;
        job.s = f.v[i].s + job.lambda * (s_next - f.v[i].s);
        job.t = f.v[i].t + job.lambda * (f.v[j].t - f.v[i].t);
        const Vec<N> p = seed_point(job.s);
        resolved = p != previous && p != last;
        previous = p;
        jobs_.push_back(job);
      }
      if (!resolved) {
        jobs_.resize(first);
        unresolved[i] = 1;
        any_cut = true;
      }
    }
    cut.clear();
    if (jobs_.empty()) {
      if (any_cut) cut = std::move(unresolved);
      return any_cut;
    }
    // Each insertion integrates a stream line from the seed: independent and costly, so they run
    // in parallel; the mesh vertices are then emitted in front order, as a serial run would.
    for_range(
        jobs_.size(), 2,
        [&](std::size_t b, std::size_t e) {
          for (std::size_t k = b; k < e; ++k) insertion_point(f, old, jobs_[k]);
        },
        1);
    std::vector<FrontVertex<N>> out;
    out.reserve(n + jobs_.size());
    if (any_cut) cut.reserve(n + jobs_.size());
    std::size_t next_job = 0;
    for (std::size_t i = 0; i < n; ++i) {
      out.push_back(f.v[i]);
      if (any_cut) cut.push_back(unresolved[i]);
      const std::size_t j = (i + 1) % n;
      for (; next_job < jobs_.size() && jobs_[next_job].segment == i; ++next_job) {
        const InsertionJob& job = jobs_[next_job];
        report_.field_evaluations += static_cast<std::size_t>(job.evaluations);
        if (job.outcome == InsertionJob::Outcome::streamline) ++report_.streamline_insertions;
        if (job.outcome == InsertionJob::Outcome::previous_row) ++report_.previous_row_insertions;
        if (job.outcome == InsertionJob::Outcome::fallback) {
          ++report_.insertion_fallbacks;
          ++(job.left_domain ? report_.fallback_left_domain : report_.fallback_far_from_front);
        }
        FrontVertex<N> nv;
        nv.s = job.s;
        nv.t = job.t;
        nv.x = job.x;
        nv.anchor = nv.x;
        nv.origin = -1;
        const double a =
            mesh_.alpha.empty() ? 0.0 : 0.5 * (alpha_or_zero(f.v[i]) + alpha_or_zero(f.v[j]));
        nv.mesh = emit(nv, a, f.id, step);
        out.push_back(nv);
        if (any_cut) cut.push_back(0);
        ++report_.splits;
      }
    }
    f.v = std::move(out);
    return any_cut;
  }

  double alpha_or_zero(const FrontVertex<N>& fv) const {
    return fv.mesh >= 0 ? mesh_.alpha[static_cast<std::size_t>(fv.mesh)] : 0.0;
  }

  /// Follows the stream line from `start` for `duration`, then moves it along itself onto the
  /// front: the plane through the cubic guess normal to the flow. On success (inside, within a
  /// quarter segment of the guess) sets job.x and job.t; `status` tells why it failed otherwise.
  bool shoot(const Front<N>& f, std::size_t i, std::size_t j, const Vec<N>& guess,
             const Vec<N>& start, double duration, InsertionJob& job, FieldStatus& status) const {
    const double seg = (f.v[j].x - f.v[i].x).norm();
    IntegrationResult<N> r = integrate_dopri5(field_, start, duration, tol_, 0, &integration_stop_);
    job.evaluations += r.evaluations;
    double time = job.t;
    for (int iteration = 0; iteration < 4 && r.status == FieldStatus::inside; ++iteration) {
      Vec<N> w;
      if (field_.velocity(r.x, w) != FieldStatus::inside) break;
      const double ww = w.squaredNorm();
      if (!(ww > 0)) break;
      const double delta = (guess - r.x).dot(w) / ww;
      if (std::abs(delta) * std::sqrt(ww) < 1e-6 * seg) break;
      // A Newton step longer than the segment means the stream line runs nearly parallel to
      // the front here (or the flow is slow): give up instead of integrating for ages.
      if (std::abs(delta) * std::sqrt(ww) > seg) break;
      r = integrate_dopri5(field_, r.x, delta, tol_, 0, &integration_stop_);
      job.evaluations += r.evaluations + 1;
      time += delta;
    }
    status = r.status;
    if (r.status != FieldStatus::inside || !((r.x - guess).norm() < 0.25 * seg)) return false;
    job.t = time;
    job.x = r.x;
    return true;
  }

  /// Fills job.x (and job.t when the point is put on its true stream line). Thread-safe.
  void insertion_point(const Front<N>& f, const Front<N>* old, InsertionJob& job) const {
    using Outcome = typename InsertionJob::Outcome;
    const std::size_t i = job.segment;
    const std::size_t j = (i + 1) % f.v.size();
    const double s = job.s;
    if (job.t == 0) {
      job.x = seed_.point(s - std::floor(s));
      job.outcome = Outcome::seed;
      return;
    }
    const Vec<N> guess = cubic_point(f, i, job.lambda);
    if (opt_.insertion == Insertion::streamline || opt_.insertion == Insertion::previous_row) {
      // The previous front's point between the ends' origins (on their stream lines to within
      // the interpolation) and the time left to this front, where the ends came from neighbours.
      std::optional<std::pair<Vec<N>, double>> row_start;
      if (old && f.v[i].origin >= 0 && f.v[j].origin >= 0) {
        const auto oi = static_cast<std::size_t>(f.v[i].origin);
        const auto oj = static_cast<std::size_t>(f.v[j].origin);
        const std::size_t n_old = old->v.size();
        if (oj == oi + 1 || (old->closed && oj == (oi + 1) % n_old))
          row_start.emplace(cubic_point(*old, oi, job.lambda),
                            job.t - (old->v[oi].t + job.lambda * (old->v[oj].t - old->v[oi].t)));
      }
      FieldStatus status = FieldStatus::inside;
      // streamline: from the seed (exact), then from the previous row where that fails;
      // previous-row: from the previous row (one step's integration), else from the seed.
      const bool row_first = opt_.insertion == Insertion::previous_row && row_start;
      for (int attempt = 0; attempt < 2; ++attempt) {
        const bool from_row = (attempt == 0) == row_first;
        if (from_row && !row_start) break;
        const Vec<N> start = from_row ? row_start->first : seed_.point(s - std::floor(s));
        if (shoot(f, i, j, guess, start, from_row ? row_start->second : job.t, job, status)) {
          job.outcome = from_row ? Outcome::previous_row : Outcome::streamline;
          return;
        }
      }
      job.outcome = Outcome::fallback;
      job.left_domain = status != FieldStatus::inside;
      job.x = guess;
      return;
    }
    job.outcome = Outcome::interpolated;
    job.x = opt_.insertion == Insertion::cubic
                ? guess
                : Vec<N>(f.v[i].x + job.lambda * (f.v[j].x - f.v[i].x));
  }

  /// Row skipping leaves one triangle wherever a waiting vertex neighbours a moving one. Grow
  /// moving regions into neighbours that went at least half the way, and let short waiting
  /// or moving runs join their surroundings, so rows start and end in few places.
  void smooth_rows(const Front<N>& f, std::vector<char>& fresh) const {
    const std::size_t n = f.v.size();
    const double full = opt_.skip_fraction * opt_.edge;
    const double low = 0.5 * full;
    const double high = 0.9 * opt_.edge;
    auto moved = [&](std::size_t i) { return (f.v[i].x - f.v[i].anchor).norm(); };
    auto movable = [&](std::size_t i) { return f.v[i].origin >= 0 && moved(i) >= low; };
    // Inserted vertices count as moving (they are new mesh vertices).
    auto moving = [&](std::size_t i) { return f.v[i].origin < 0 || fresh[i]; };
    for (std::size_t i = 1; i < n; ++i)
      if (!fresh[i] && moving(i - 1) && movable(i)) fresh[i] = 1;
    for (std::size_t i = n - 1; i-- > 0;)
      if (!fresh[i] && moving(i + 1) && movable(i)) fresh[i] = 1;
    // A short moving run inside waiting vertices waits too, unless it has gone nearly ℓ.
    for (std::size_t i = 0; i < n;) {
      if (!(f.v[i].origin >= 0 && fresh[i])) {
        ++i;
        continue;
      }
      std::size_t j = i;
      bool early = true;
      for (; j < n && f.v[j].origin >= 0 && fresh[j]; ++j) early = early && moved(j) < high;
      if (early && j - i <= 2 && i > 0 && j < n && !moving(i - 1) && !moving(j))
        for (std::size_t k = i; k < j; ++k) fresh[k] = 0;
      i = j;
    }
  }

  /// Whether a vertex of the front moved away from its mesh vertex (one whose α was clamped to
  /// 0 did not: a copy of its mesh vertex would make zero-area faces). Inserted ones are new.
  bool has_moved(const FrontVertex<N>& fv) const {
    return fv.origin < 0 || (fv.x - fv.anchor).norm() > 1e-12 * opt_.edge;
  }

  /// Gives moved vertices new mesh vertices (all of them without row skipping).
  void emit_moved(Front<N>& f, const Front<N>& old, int step) {
    const std::size_t n = f.v.size();
    std::vector<char> fresh(n, 0);
    const double min_move = opt_.skip_fraction * opt_.edge;
    for (std::size_t i = 0; i < n; ++i) {
      if (f.v[i].origin < 0) continue;  // inserted: already a mesh vertex
      const double distance = (f.v[i].x - f.v[i].anchor).norm();
      // Without row skipping every vertex that moved at all gets a new mesh vertex; one whose α
      // was clamped to 0 did not move and keeps its own (a copy would make a zero-area face).
      const bool every_row = opt_.row_skip == RowSkip::off || opt_.method == Method::timeline;
      fresh[i] = every_row ? has_moved(f.v[i]) : distance >= min_move;
    }
    if (opt_.row_skip == RowSkip::run && opt_.method == Method::orthogonal) smooth_rows(f, fresh);
    for (std::size_t i = 0; i < n; ++i)
      if (fresh[i] && f.v[i].origin >= 0 && lands_on_mesh_vertex(f, old, fresh, i)) fresh[i] = 0;
    renew_across_merges(f, old, fresh);
    for (std::size_t i = 0; i < n; ++i) {
      if (f.v[i].origin < 0) continue;
      if (fresh[i]) {
        f.v[i].mesh = emit(f.v[i], 0.0, f.id, step);
        f.v[i].anchor = f.v[i].x;
      } else {
        ++report_.skipped_vertex_steps;
      }
    }
  }

  /// Whether moved vertex i of the front, if it got a new mesh vertex, would lie on (within
  /// 1e-8 ℓ of) a mesh vertex of the faces stitched to it: its own old one, those of its origin's
  /// neighbours on the previous front, or those its neighbours on the front will have. A stalled
  /// front folded onto one stream line (abc) settles into a cycle in which a vertex returns to
  /// where a neighbour's kept mesh vertex was made steps earlier; a copy there gives a face two
  /// coincident corners (zero area). And a vertex that moved less than that from its own (a front
  /// near a stagnation point, e.g. the timeline baseline on `stalling`) made a new row of copies
  /// every step. Such a vertex keeps its old mesh vertex instead, as a waiting vertex does
  /// (renew_across_merges may still renew it where that is needed for a manifold).
  bool lands_on_mesh_vertex(const Front<N>& f, const Front<N>& old, const std::vector<char>& fresh,
                            std::size_t i) const {
    const double tolerance = 1e-8 * opt_.edge;
    const auto near = [&](const Vec3& p) {
      return (p - f.v[i].x.template head<3>()).norm() <= tolerance;
    };
    const auto near_mesh = [&](std::int32_t m) {
      return m >= 0 && near(mesh_.positions[static_cast<std::size_t>(m)]);
    };
    const std::size_t n = f.v.size(), n_old = old.v.size();
    for (const bool next : {false, true}) {
      if (!f.closed && (next ? i + 1 >= n : i == 0)) continue;
      const std::size_t k = next ? (i + 1) % n : (i + n - 1) % n;
      // A neighbour that gets a new mesh vertex gets it at its position; the others keep theirs.
      if (k != i && (fresh[k] ? near(f.v[k].x.template head<3>()) : near_mesh(f.v[k].mesh)))
        return true;
    }
    const auto o = static_cast<std::size_t>(f.v[i].origin);
    if (near_mesh(old.v[o].mesh)) return true;
    if ((old.closed || o > 0) && near_mesh(old.v[(o + n_old - 1) % n_old].mesh)) return true;
    if ((old.closed || o + 1 < n_old) && near_mesh(old.v[(o + 1) % n_old].mesh)) return true;
    return false;
  }

  /// Two vertices of the front that both keep their old mesh vertices, with nothing inserted
  /// between them but vertices merged away (merge_short), would make stitch join an old chain of
  /// three or more mesh vertices to a new "chain" of those two old ones: every face between lies
  /// on the previous front, made of its mesh vertices only. Where that front turned back on
  /// itself (the tip of a fan, whose two front edges belong to one triangle) such a face is a
  /// copy of one already behind it, with the opposite orientation: non-manifold edges. So the
  /// one of the two that moved further gets a new mesh vertex (merge_short merges between no two
  /// that did not move at all). Where only one end of a chain is old, zipper avoids such faces.
  void renew_across_merges(const Front<N>& f, const Front<N>& old,
                           std::vector<char>& fresh) const {
    const std::size_t n = f.v.size(), n_old = old.v.size();
    const std::size_t segments = f.closed ? n : (n > 0 ? n - 1 : 0);
    for (std::size_t i = 0; i < segments; ++i) {
      const std::size_t j = (i + 1) % n;
      const FrontVertex<N>& a = f.v[i];
      const FrontVertex<N>& b = f.v[j];
      if (a.origin < 0 || b.origin < 0 || fresh[i] || fresh[j]) continue;
      // Old vertices from a.origin to b.origin, as stitch walks them (forward, wrapping on a
      // closed previous front; a single vertex on a closed front goes all the way round).
      const auto oa = static_cast<std::size_t>(a.origin), ob = static_cast<std::size_t>(b.origin);
      if (ob < oa && !old.closed) continue;
      const std::size_t span = ob > oa ? ob - oa : ob + n_old - oa;
      if (span < 2) continue;  // adjacent on the previous front too: one quad, no merge
      const double da = (a.x - a.anchor).norm(), db = (b.x - b.anchor).norm();
      const std::size_t k = da >= db ? i : j;
      if (has_moved(f.v[k])) fresh[k] = 1;
    }
  }

  void add_face(std::array<std::int32_t, 4> ids, int count) {
    // Drop repeated corners (a vertex that kept its mesh vertex collapses a quad to a triangle).
    std::array<std::int32_t, 4> u{};
    int m = 0;
    for (int k = 0; k < count; ++k) {
      bool seen = false;
      for (int l = 0; l < m; ++l)
        seen = seen || u[static_cast<std::size_t>(l)] == ids[static_cast<std::size_t>(k)];
      if (!seen) u[static_cast<std::size_t>(m++)] = ids[static_cast<std::size_t>(k)];
    }
    if (m == 4)
      mesh_.add_quad(u[0], u[1], u[2], u[3]);
    else if (m == 3)
      mesh_.add_triangle(u[0], u[1], u[2]);
  }

  /// Whether the face add_face would write for these corners has (near) zero area: below
  /// 1e-9 ℓ², far above rounding and far below any face worth keeping (quality counts a face
  /// degenerate below 1e-12 of the mean squared edge). Corners that collapse to fewer than three
  /// write no face, which is not degenerate.
  bool flat_face(std::array<std::int32_t, 4> ids, int count) const {
    std::array<Vec3, 4> p;
    int m = 0;
    for (int k = 0; k < count; ++k) {
      const std::int32_t id = ids[static_cast<std::size_t>(k)];
      bool seen = false;
      for (int l = 0; l < k; ++l) seen = seen || ids[static_cast<std::size_t>(l)] == id;
      if (!seen) p[static_cast<std::size_t>(m++)] = mesh_.positions[static_cast<std::size_t>(id)];
    }
    if (m < 3) return false;
    const Vec3 area = m == 4 ? Vec3((p[2] - p[0]).cross(p[3] - p[1]))
                             : Vec3((p[1] - p[0]).cross(p[2] - p[0]));
    return 0.5 * area.norm() < 1e-9 * opt_.edge * opt_.edge;
  }

  double distance(std::int32_t a, std::int32_t b) const {
    return (mesh_.positions[static_cast<std::size_t>(a)] -
            mesh_.positions[static_cast<std::size_t>(b)])
        .norm();
  }

  /// Whether zipper's choice at (i, j) between a triangle (on A's segment when `on_a`, else on
  /// B's) and the quad that advances both would write a flat face while the other would not.
  /// Vertices inserted on a straight segment from a vertex that kept its mesh vertex (α clamped
  /// to 0) lie on one line with it (linear insertion, or the cubic fallback at an open front's
  /// end): a fan from that kept vertex across them is a row of collinear triangles. Where the quad
  /// leaves one side without segments, the fan that must follow counts as part of it.
  bool flat_choice(const std::vector<std::int32_t>& a, const std::vector<std::int32_t>& b,
                   std::size_t i, std::size_t j, bool triangle, bool on_a) const {
    const std::size_t ma = a.size() - 1, mb = b.size() - 1;
    const bool triangle_flat =
        on_a ? flat_face({a[i], a[i + 1], b[j], -1}, 3) : flat_face({a[i], b[j + 1], b[j], -1}, 3);
    bool quad_flat = flat_face({a[i], a[i + 1], b[j + 1], b[j]}, 4);
    if (on_a && mb - j == 1)
      for (std::size_t k = i + 1; k < ma && !quad_flat; ++k)
        quad_flat = flat_face({a[k], a[k + 1], b[mb], -1}, 3);
    if (!on_a && ma - i == 1)
      for (std::size_t k = j + 1; k < mb && !quad_flat; ++k)
        quad_flat = flat_face({a[ma], b[k + 1], b[k], -1}, 3);
    return triangle ? triangle_flat && !quad_flat : quad_flat && !triangle_flat;
  }

  /// Faces between an old chain A and a new chain B with common ends in correspondence:
  /// quads while both advance together, triangles where one side has more segments, placed
  /// where they create the shorter connecting edge.
  void zipper(const std::vector<std::int32_t>& a, const std::vector<std::int32_t>& b) {
    std::size_t i = 0, j = 0;
    const std::size_t ma = a.size() - 1, mb = b.size() - 1;
    while (i < ma || j < mb) {
      const std::size_t ra = ma - i, rb = mb - j;
      if (ra == rb) {
        add_face({a[i], a[i + 1], b[j + 1], b[j]}, 4);
        ++i, ++j;
      } else if (ra > rb) {
        // An end of B that kept its old mesh vertex (a waiting vertex next to a merge) is an old
        // vertex: a triangle from it to a segment of A that does not contain it lies on the
        // previous front, made of old mesh vertices only (see renew_across_merges). Step past it
        // on B first, and keep the last segment of B for the end when B ends on an old vertex.
        const bool b_old = (j == 0 && b[0] == a[0]) || (j == mb && b[mb] == a[ma]);
        const bool next_old = j + 1 == mb && b[mb] == a[ma];
        bool triangle = rb == 0 || distance(a[i + 1], b[j]) <= distance(a[i + 1], b[j + 1]);
        // The other choice where this one would be flat (flat_choice); the rules for old ends
        // of B, which keep the surface manifold, still come first.
        if (rb > 0 && flat_choice(a, b, i, j, triangle, true)) triangle = !triangle;
        if (b_old && b[j] != a[i] && b[j] != a[i + 1] && rb > 0 && !next_old) triangle = false;
        if (next_old && !b_old) triangle = true;
        if (triangle) {
          add_face({a[i], a[i + 1], b[j], -1}, 3);
          ++i;
        } else {
          add_face({a[i], a[i + 1], b[j + 1], b[j]}, 4);
          ++i, ++j;
        }
      } else {
        bool triangle = ra == 0 || distance(a[i], b[j + 1]) <= distance(a[i + 1], b[j + 1]);
        if (ra > 0 && flat_choice(a, b, i, j, triangle, false)) triangle = !triangle;
        if (triangle) {
          add_face({a[i], b[j + 1], b[j], -1}, 3);
          ++j;
        } else {
          add_face({a[i], a[i + 1], b[j + 1], b[j]}, 4);
          ++i, ++j;
        }
      }
    }
  }

  void stitch(const Front<N>& old, const Front<N>& f) {
    const std::size_t n = f.v.size();
    const std::size_t n_old = old.v.size();
    std::vector<std::size_t> anchors;
    for (std::size_t i = 0; i < n; ++i)
      if (f.v[i].origin >= 0) anchors.push_back(i);
    if (anchors.size() < 2 && !(f.closed && anchors.size() == 1)) return;
    std::vector<std::int32_t> chain_a, chain_b;
    const std::size_t pairs = f.closed ? anchors.size() : anchors.size() - 1;
    for (std::size_t k = 0; k < pairs; ++k) {
      const std::size_t ja = anchors[k];
      const std::size_t jb = anchors[(k + 1) % anchors.size()];
      const auto oa = static_cast<std::size_t>(f.v[ja].origin);
      const auto ob = static_cast<std::size_t>(f.v[jb].origin);
      chain_a.clear();
      chain_b.clear();
      // Old chain: forward from oa to ob (wrapping on closed old fronts).
      std::size_t steps_old = ob >= oa ? ob - oa : ob + n_old - oa;
      if (ob < oa && !old.closed) continue;   // no old segment joins them
      if (steps_old == 0) steps_old = n_old;  // a closed front with a single anchor
      for (std::size_t s = 0; s <= steps_old; ++s) chain_a.push_back(old.v[(oa + s) % n_old].mesh);
      std::size_t steps_new = jb >= ja ? jb - ja : jb + n - ja;
      if (steps_new == 0) steps_new = n;
      for (std::size_t s = 0; s <= steps_new; ++s) chain_b.push_back(f.v[(ja + s) % n].mesh);
      zipper(chain_a, chain_b);
    }
  }

  const Field<N>& field_;
  const Seed<N>& seed_;
  StreamSurfaceOptions opt_;
  std::vector<double> front_positions_;
  // Between steps (EngineState).
  std::vector<Front<N>> fronts_;
  int step_ = 0;
  bool died_outside_ = false;
  double elapsed_before_ = 0;
  Clock::time_point t_start_ = Clock::now();
  StopReason reason_ = StopReason::none;
  Tolerance tol_;
  double h_star_ = 0;
  bool damping_infeasible_ = false;  ///< the last α solve's damping target could not be met
  FoldGuard fold_guard_;
  Mesh mesh_;
  SurfaceReport report_;
  AlphaSolver solver_;
  std::int32_t next_front_id_ = 0;
  StepRecord step_record_;
  double ortho_sum_ = 0;
  std::size_t ortho_count_ = 0;
  std::size_t exits_this_step_ = 0;
  StopRequest stop_request_;
  StopRequest integration_stop_;  ///< stop_requested(), as the integrators take it
  mutable std::atomic<bool> stopping_{false};
  mutable std::atomic<bool> stopped_by_budget_{false};
  // Per-front scratch, reused between fronts and steps.
  std::vector<Vec<N>> vel_;
  std::vector<double> speed_, alpha_, p_, q_, r_, aln_, kernel_, seg_err_;
  std::vector<char> seg_ok_;
  std::vector<InsertionJob> jobs_;
  std::vector<VertexState> state_;
};

template <int N>
SurfaceBuilder<N>::SurfaceBuilder(const Field<N>& field, const Seed<N>& seed,
                                  const StreamSurfaceOptions& options)
    : engine_(std::make_unique<Engine<N>>(field, seed, options)) {
  engine_->begin();
}

template <int N>
SurfaceBuilder<N>::SurfaceBuilder(const Field<N>& field, const Seed<N>& seed,
                                  const StreamSurfaceOptions& options, EngineState<N> state)
    : engine_(std::make_unique<Engine<N>>(field, seed, options)) {
  engine_->restore(std::move(state));
}

template <int N>
SurfaceBuilder<N>::~SurfaceBuilder() = default;
template <int N>
SurfaceBuilder<N>::SurfaceBuilder(SurfaceBuilder&&) noexcept = default;
template <int N>
SurfaceBuilder<N>& SurfaceBuilder<N>::operator=(SurfaceBuilder&&) noexcept = default;

template <int N>
bool SurfaceBuilder<N>::next() {
  return engine_->next();
}
template <int N>
void SurfaceBuilder<N>::step() {
  engine_->step();
}
template <int N>
void SurfaceBuilder<N>::cancel() {
  engine_->cancel();
}
template <int N>
void SurfaceBuilder<N>::set_stop_request(StopRequest request) {
  engine_->set_stop_request(std::move(request));
}
template <int N>
FrontSnapshot SurfaceBuilder<N>::front() {
  return engine_->front();
}
template <int N>
Progress SurfaceBuilder<N>::progress() const {
  return engine_->progress();
}
template <int N>
int SurfaceBuilder<N>::steps_done() const {
  return engine_->steps_done();
}
template <int N>
EngineState<N> SurfaceBuilder<N>::state() const {
  return engine_->state();
}
template <int N>
SurfaceResult SurfaceBuilder<N>::finish() {
  return engine_->finish();
}

template class SurfaceBuilder<3>;
template class SurfaceBuilder<4>;

template <int N>
SurfaceResult build_stream_surface(const Field<N>& field, const Seed<N>& seed,
                                   const StreamSurfaceOptions& options,
                                   const ProgressCallback& progress,
                                   const FrontHook& before_step, const StopRequest& stop) {
  SurfaceBuilder<N> builder(field, seed, options);
  builder.set_stop_request(stop);
  while (builder.next()) {
    if (before_step && !before_step(builder.front())) {
      builder.cancel();
      break;
    }
    if (progress && !progress(builder.progress())) {
      builder.cancel();
      break;
    }
    builder.step();
  }
  return builder.finish();
}

template SurfaceResult build_stream_surface<3>(const Field<3>&, const Seed<3>&,
                                               const StreamSurfaceOptions&,
                                               const ProgressCallback&, const FrontHook&,
                                               const StopRequest&);
template SurfaceResult build_stream_surface<4>(const Field<4>&, const Seed<4>&,
                                               const StreamSurfaceOptions&,
                                               const ProgressCallback&, const FrontHook&,
                                               const StopRequest&);

}  // namespace orthofront
