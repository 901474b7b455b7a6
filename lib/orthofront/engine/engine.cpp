#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <string>

#include "orthofront/engine/adapt.h"
#include "orthofront/engine/advect.h"
#include "orthofront/engine/discretization.h"
#include "orthofront/engine/link.h"
#include "orthofront/engine/rip.h"
#include "orthofront/engine/samples_ahead.h"
#include "orthofront/engine/surface_builder.h"
#include "orthofront/error.h"
#include "orthofront/field/field_spec.h"
#include "orthofront/mesh/close_gaps.h"
#include "orthofront/seed/seed_check.h"
#include "orthofront/stage_timer.h"

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
    case StopReason::end_time:
      return "end_time";
  }
  return "?";
}

namespace {

using Clock = std::chrono::steady_clock;
}  // namespace

/// The driver (paper Figure 4): each step takes every front through the stall cut → velocity
/// (advect.h) → α (discretization.h: the orthogonal alpha_step.h or the timeline baseline) →
/// rips (rip.h) → advance (advect.h) → adapt (adapt.h) → link (link.h: stitch, checked by the
/// fold guard); the finished surface's gaps are closed (mesh/close_gaps.h).
template <int N>
class Engine {
 public:
  Engine(const Field<N>& field, const Seed<N>& seed, const StreamSurfaceOptions& options)
      : field_(field), seed_(seed), opt_(options) {
    validate();
    report_.options = opt_;
    tol_.absolute = opt_.tolerance * opt_.edge;
    tol_.relative = opt_.tolerance;
    integration_stop_ = [this] { return stop_requested(); };
  }

  void set_stop_request(StopRequest request) { stop_request_ = std::move(request); }
  void set_front_integrator(FrontIntegrator<N>* integrator) {
    advect_.set_front_integrator(integrator);
  }

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
    ids_.next = state.next_front_id;
    elapsed_before_ = state.elapsed_seconds;
    mesh_ = std::move(state.mesh);
    linker_.rebuild(mesh_);
    report_ = std::move(state.report);
    report_.options = opt_;
  }

  EngineState<N> state() const {
    EngineState<N> s;
    s.fronts = fronts_;
    s.step = step_;
    s.died_outside = died_outside_;
    s.next_front_id = ids_.next;
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

  /// One front step of every front. A front that must be cut first goes back to the queue as
  /// its parts, which then take the step themselves.
  void step() {
    ++step_;
    step_record_ = StepRecord{};
    step_record_.step = step_;
    step_record_.h_min = std::numeric_limits<double>::infinity();
    discretization_->begin_step();
    adapter_.begin_step();
    samples_ahead_.begin_step();
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
    step_record_.orthogonality_mean = discretization_->orthogonality_mean();
    if (!std::isfinite(step_record_.h_min)) step_record_.h_min = 0;
    report_.per_step.push_back(step_record_);
  }

  SurfaceResult finish() {
    adapter_.finish();
    // Only a surface that tore (its front was cut into parts) has gaps to close.
    if (opt_.close_gaps && discretization_->safeguarded() && report_.fronts_created > 0) {
      StageTimer timer(report_.times.gaps);
      // The fold guard kept the boundary as it stitched (the same edges on a manifold mesh): no
      // pass over every face.
      const double distance = opt_.gap_distance * opt_.edge;
      const std::size_t faces_before = mesh_.face_count();
      const GapReport gaps = linker_.guarded()
                                 ? close_gaps(mesh_, distance, 2 * opt_.edge, linker_.boundary())
                                 : close_gaps(mesh_, distance, 2 * opt_.edge);
      report_.gap_stretches = gaps.stretches;
      report_.gap_faces = gaps.faces;
      report_.gaps_refused = gaps.refused;
      report_.triangles_closing_gaps = static_cast<std::size_t>(
          std::count_if(mesh_.faces.begin() + static_cast<std::ptrdiff_t>(faces_before),
                        mesh_.faces.end(), [](const Face& f) { return !f.is_quad(); }));
    }
    // (Decided by the report, which a saved state keeps: a resumed run ends with the same mesh.)
    if (report_.fold_rips > 0) mesh_.remove_unused_vertices();
    report_.stop_reason = reason_;
    report_.steps = step_;
    report_.legs_started_ahead = adapter_.legs_started_ahead();
    report_.legs_used_ahead = adapter_.legs_used_ahead();
    report_.samples_started_ahead = samples_ahead_.started();
    report_.samples_used_ahead = samples_ahead_.used();
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
  /// One front step for one front (Figure 4's loop body).
  void advance_front(Front<N>&& f, int step, std::vector<Front<N>>& queue,
                     std::vector<Front<N>>& next) {
    const std::size_t n = f.v.size();
    if (n < 2) return;
    std::vector<char> keep(n, 1), cut(n, 0);
    const auto requeue = [&] {
      for (auto& part : split(std::move(f), keep, cut)) queue.push_back(std::move(part));
    };
    if (find_stalled(f, step, keep)) return requeue();
    {
      StageTimer timer(report_.times.alpha);
      auto* ahead = samples_ahead_.take(f);
      if (!advect_.sample(f, keep, exits_this_step_, ahead ? &ahead->vertices : nullptr))
        return requeue();
      alpha_.assign(n, 1.0);
      const bool system_ahead = ahead && ahead->has_segments;  // its terms and solution
      if (!discretization_->alpha(f, advect_.velocities(), advect_.speeds(), alpha_, cut,
                                  system_ahead ? &ahead->segments : nullptr,
                                  system_ahead ? &ahead->solution : nullptr))
        return requeue();
    }
    if (discretization_->safeguarded() && opt_.rip) {
      StageTimer timer(report_.times.rip);
      const std::size_t rips = find_rips(alpha_, advect_.speeds(), f.closed,
                                         {opt_.rip_sharpness, opt_.rip_speed_fraction}, keep);
      report_.rips += rips;
      if (rips > 0) return requeue();
    }
    const double h = front_step(f);
    if (h < 0) {
      ++report_.fronts_stalled;  // α vanished everywhere: this front cannot advance
      return;
    }
    Front<N> advanced = [&] {
      StageTimer timer(report_.times.advance);
      return advect_.advance(f, alpha_, h, keep, exits_this_step_, std::move(spare_vertices_));
    }();
    // Vertices that left the domain end their stream lines at the last valid point: keep that
    // point in the mesh, but not in the front.
    for (auto& part : split(std::move(advanced), keep, cut)) {
      for (auto& piece : adapt_and_link(std::move(part), &f, step)) {
        if (piece.v.size() < 2 || front_shorter_than(piece, opt_.edge)) {
          ++report_.fronts_dropped_short;
          continue;
        }
        if (step < opt_.max_steps) adapter_.start_likely_shots(piece, f);
        next.push_back(std::move(piece));
      }
    }
    spare_vertices_ = std::move(f.v);
  }

  /// Marks (keep[i] = 0) the vertices that stopped advancing: their mesh vertex is more than
  /// stall_steps steps old (StreamSurfaceOptions::stall_steps). Returns whether any was.
  bool find_stalled(const Front<N>& f, int step, std::vector<char>& keep) {
    if (opt_.stall_steps <= 0 || !discretization_->safeguarded() || step <= opt_.stall_steps)
      return false;
    bool any = false;
    for (std::size_t i = 0; i < f.v.size(); ++i) {
      const std::int32_t m = f.v[i].mesh;
      if (m < 0 || step - mesh_.step[static_cast<std::size_t>(m)] <= opt_.stall_steps) continue;
      keep[i] = 0;
      any = true;
      ++report_.stall_cuts;
    }
    return any;
  }

  /// The front step h in α-time (discretization.h); -1 when no vertex moves. Records α on the
  /// mesh vertices the front stands on.
  double front_step(const Front<N>& f) {
    const std::size_t n = f.v.size();
    const double h = discretization_->step(f, alpha_, advect_.speeds());
    if (h < 0) return h;
    step_record_.h_min = std::min(step_record_.h_min, h);
    step_record_.h_max = std::max(step_record_.h_max, h);
    for (std::size_t i = 0; i < n; ++i)
      if (f.v[i].mesh >= 0 && f.v[i].x == f.v[i].anchor)
        mesh_.alpha[static_cast<std::size_t>(f.v[i].mesh)] = alpha_[i];
    return h;
  }

  /// Merge short segments, split long ones, decide which vertices get new mesh vertices, and
  /// stitch faces between the previous front `old` (nullptr for the seed) and `f`. Returns the
  /// parts of `f`: more than one where split_long cut it at segments no stream line can fill.
  std::vector<Front<N>> adapt_and_link(Front<N>&& f, const Front<N>* old, int step) {
    std::vector<Front<N>> parts;
    const std::size_t first_inserted = mesh_.vertex_count();
    {
      StageTimer timer(report_.times.adapt);
      adapter_.merge_short(f);
      std::vector<char> cut;
      if (adapter_.split_long(f, old, step, cut)) {
        parts = split(std::move(f), std::vector<char>(cut.size(), 1), cut);
      } else {
        parts.push_back(std::move(f));
      }
    }
    // The next step samples these fronts first: an idle thread can do it while they are
    // stitched (only large ones: a task costs more than sampling a few dozen vertices).
    if (step < opt_.max_steps)
      for (const Front<N>& part : parts)
        if (part.v.size() >= opt_.parallel_threshold) samples_ahead_.start(part);
    StageTimer timer(report_.times.stitch);
    if (!old) return parts;
    return linker_.link(std::move(parts), *old, step, first_inserted);
  }

  void validate() const {
    auto positive = [](double v) { return std::isfinite(v) && v > 0; };
    if (!positive(opt_.edge))
      throw InvalidArgument("edge length must be positive and finite, got " +
                            std::to_string(opt_.edge));
    if (opt_.max_steps < 0)
      throw InvalidArgument("step count must not be negative, got " +
                            std::to_string(opt_.max_steps));
    if (opt_.shot_evaluations < 0)
      throw InvalidArgument("seed shot evaluations must not be negative, got " +
                            std::to_string(opt_.shot_evaluations));
    if (!(opt_.join_fraction >= 0 && opt_.join_fraction <= 1))
      throw InvalidArgument("join fraction must lie in [0, 1], got " +
                            std::to_string(opt_.join_fraction));
    if (!(opt_.damping > 0 && opt_.damping < 1))
      throw InvalidArgument("damping must lie in (0, 1), got " + std::to_string(opt_.damping));
    if (!std::isfinite(opt_.mu) || opt_.mu < 0)
      throw InvalidArgument("mu must be finite and >= 0, got " + std::to_string(opt_.mu));
    if (!(opt_.split_factor > 1.0) || !(opt_.merge_factor > 0) ||
        opt_.merge_factor >= 2 * opt_.split_factor)
      throw InvalidArgument("split/merge factors must satisfy split > 1, 0 < merge < 2 split");
    if (!positive(opt_.tolerance)) throw InvalidArgument("tolerance must be positive");
    if (!positive(opt_.paper_max_step))
      throw InvalidArgument("the paper mode's largest step must be positive, got " +
                            std::to_string(opt_.paper_max_step));
    if (!positive(opt_.gap_distance))
      throw InvalidArgument("gap distance must be positive, got " +
                            std::to_string(opt_.gap_distance));
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

  std::vector<Front<N>> initial_fronts() {
    Front<N> f;
    f.closed = seed_.closed;
    f.id = ids_.next++;
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
    SeedSurvey survey;
    for (std::size_t i = 0; i < f.v.size(); ++i) {
      Vec<N> v = Vec<N>::Zero();
      const FieldStatus status = field_.velocity(f.v[i].x, v);
      keep[i] = status == FieldStatus::inside;
      survey.add(f.v[i].x.template head<3>(), status, v.template head<3>());
    }
    SeedContext context;
    context.about = field_.describe();
    context.dimension = std::min(N, 3);
    require_seed_inside(survey, context, false);
    std::vector<Front<N>> out;
    std::vector<char> cut(f.v.size(), 0);
    for (auto& part : split(std::move(f), keep, cut)) {
      for (auto& fv : part.v) fv.mesh = emit_vertex(mesh_, fv, seed_.closed, 0.0, part.id, 0);
      for (auto& piece : adapt_and_link(std::move(part), nullptr, 0))
        if (piece.v.size() >= 2) out.push_back(std::move(piece));
    }
    discretization_->begin(out);
    return out;
  }

  std::vector<Front<N>> split(Front<N>&& f, const std::vector<char>& keep,
                              const std::vector<char>& cut) {
    FrontIds ids{ids_.next, 0};
    auto parts = split_front(std::move(f), keep, cut, ids);
    ids_.next = ids.next;
    report_.fronts_created += ids.created;
    return parts;
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

  const Field<N>& field_;
  const Seed<N>& seed_;
  StreamSurfaceOptions opt_;
  Tolerance tol_;
  StopRequest stop_request_;
  StopRequest integration_stop_;  ///< stop_requested(), as the integrators take it
  mutable std::atomic<bool> stopping_{false};
  mutable std::atomic<bool> stopped_by_budget_{false};
  std::vector<double> front_positions_;
  // Between steps (EngineState).
  std::vector<Front<N>> fronts_;
  int step_ = 0;
  bool died_outside_ = false;
  double elapsed_before_ = 0;
  Clock::time_point t_start_ = Clock::now();
  StopReason reason_ = StopReason::none;
  FrontIds ids_;
  Mesh mesh_;
  SurfaceReport report_;
  StepRecord step_record_;
  std::size_t exits_this_step_ = 0;
  // The stages (they keep references to the members above).
  std::unique_ptr<Discretization<N>> discretization_ =
      make_discretization(field_, opt_, mesh_, report_, step_record_);
  FrontAdvect<N> advect_{field_, opt_, tol_, integration_stop_, stopping_, report_};
  // The timeline baseline solves no α system: sampling ahead would save it little.
  SamplesAhead<N> samples_ahead_{field_, opt_, opt_.samples_ahead && discretization_->safeguarded()};
  FrontAdapter<N> adapter_{field_, seed_, opt_, tol_, integration_stop_, mesh_, report_};
  // The paper's baseline keeps every row (no row skipping) and has no fold guard.
  StripLinker<N> linker_{
      opt_,
      discretization_->safeguarded() ? opt_.row_skip : RowSkip::off,
      opt_.fold_guard && discretization_->safeguarded(),
      seed_.closed,
      mesh_,
      report_,
      [this](Front<N>&& f, const std::vector<char>& keep, const std::vector<char>& cut) {
        return split(std::move(f), keep, cut);
      }};
  // Per-front scratch, reused between fronts and steps.
  std::vector<FrontVertex<N>> spare_vertices_;  ///< a front's vertices once it has advanced
  std::vector<double> alpha_;
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
void SurfaceBuilder<N>::set_front_integrator(FrontIntegrator<N>* integrator) {
  engine_->set_front_integrator(integrator);
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
                                   const FrontHook& before_step, const StopRequest& stop,
                                   FrontIntegrator<N>* front_integrator) {
  SurfaceBuilder<N> builder(field, seed, options);
  builder.set_stop_request(stop);
  builder.set_front_integrator(front_integrator);
  while (builder.next()) {
    if (stop && stop()) {
      builder.cancel();
      break;
    }
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
                                               const StopRequest&, FrontIntegrator<3>*);
template SurfaceResult build_stream_surface<4>(const Field<4>&, const Seed<4>&,
                                               const StreamSurfaceOptions&,
                                               const ProgressCallback&, const FrontHook&,
                                               const StopRequest&, FrontIntegrator<4>*);

}  // namespace orthofront
