#include "orthofront/spacetime/path_surface.h"

#include "orthofront/advect/steady_front_integrator.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <variant>

#include "orthofront/error.h"
#include "orthofront/seed/seed.h"
#include "orthofront/seed/seed_check.h"
#include "orthofront/engine/surface_builder.h"
#include "orthofront/spacetime/bulk_flow_map.h"
#include "orthofront/spacetime/bulk_front_integrator.h"
#include "orthofront/spacetime/lifted_field.h"
#include "orthofront/spacetime/streamed_field.h"

namespace orthofront::spacetime {
namespace {

using Clock = std::chrono::steady_clock;
constexpr double kInf = std::numeric_limits<double>::infinity();

/// Forwards to a flow and records the range of times it was evaluated at (lock-free: a relaxed
/// load first, a compare-exchange only when the range grows).
class TrackedFlow final : public UnsteadyField {
 public:
  explicit TrackedFlow(const UnsteadyField& flow) : flow_(flow) { reset(); }
  int dimension() const override { return flow_.dimension(); }
  FieldStatus velocity(const Vec3& x, double t, Vec3& v) const override {
    note(t);
    return flow_.velocity(x, t, v);
  }
  FieldStatus velocity_jacobian(const Vec3& x, double t, Vec3& v, Mat3& J,
                                Vec3& dvdt) const override {
    note(t);
    return flow_.velocity_jacobian(x, t, v, J, dvdt);
  }
  Box<3> domain() const override { return flow_.domain(); }
  TimeRange time_range() const override { return flow_.time_range(); }
  std::string describe() const override { return flow_.describe(); }
  double next_kink(const Vec3& x, double t, const Vec3& w, double w_t, double after,
                   double before) const override {
    return flow_.next_kink(x, t, w, w_t, after, before);
  }

  /// Widens the range by a time evaluated elsewhere (by a bulk front advance).
  void note(double t) const {
    double lo = lo_.load(std::memory_order_relaxed);
    while (t < lo && !lo_.compare_exchange_weak(lo, t, std::memory_order_relaxed)) {
    }
    double hi = hi_.load(std::memory_order_relaxed);
    while (t > hi && !hi_.compare_exchange_weak(hi, t, std::memory_order_relaxed)) {
    }
  }

  /// Range since the last reset (lo > hi when nothing was evaluated), then resets.
  std::pair<double, double> take() {
    const std::pair<double, double> r{lo_.load(), hi_.load()};
    reset();
    return r;
  }

 private:
  void reset() {
    lo_.store(kInf);
    hi_.store(-kInf);
  }
  const UnsteadyField& flow_;
  mutable std::atomic<double> lo_, hi_;
};

void check_options(const PathSurfaceOptions& o, const UnsteadyField& flow) {
  if (!(std::isfinite(o.t0) && std::isfinite(o.t1) && o.t1 > o.t0))
    throw InvalidArgument("path surface: need finite t0 < t1, got t0 = " + std::to_string(o.t0) +
                          ", t1 = " + std::to_string(o.t1));
  const TimeRange r = flow.time_range();
  if (!r.contains(o.t0))
    throw InvalidArgument("path surface: t0 = " + std::to_string(o.t0) +
                          " lies outside the time range [" + std::to_string(r.begin) + ", " +
                          std::to_string(r.end) + "] of " + flow.describe());
  if (!(std::isfinite(o.time_scale) && o.time_scale >= 0))
    throw InvalidArgument("path surface: time scale must be > 0 (or 0: derived), got " +
                          std::to_string(o.time_scale));
}

// c = median |v(x, t0)| over the seed vertices: one time unit then lifts a path line by the
// distance a typical particle travels in it, so the lifted stream lines lean about 45° and the
// front's orthogonality weighs time and space alike; one front step spans about ℓ/c in time,
// the time a particle needs to cross one edge. Where the seed sits in still flow, fall back to
// the domain's diagonal over the time range (the surface then crosses the domain once).
std::pair<double, std::string> choose_time_scale(const UnsteadyField& flow, const Seed<3>& seed,
                                                 const PathSurfaceOptions& o) {
  if (o.time_scale > 0) return {o.time_scale, "given"};
  std::vector<double> speeds;
  const int d = flow.dimension();
  for (double s : seed.parameters) {
    Vec3 v;
    if (flow.velocity(seed.point(s), o.t0, v) == FieldStatus::inside)
      speeds.push_back(d == 2 ? v.head<2>().norm() : v.norm());
  }
  if (!speeds.empty()) {
    std::nth_element(speeds.begin(), speeds.begin() + static_cast<std::ptrdiff_t>(speeds.size() / 2),
                     speeds.end());
    const double median = speeds[speeds.size() / 2];
    if (median > 0 && std::isfinite(median)) return {median, "median seed speed"};
  }
  const Box<3> box = flow.domain();
  const Vec3 extent = box.extent();
  const double diagonal = d == 2 ? extent.head<2>().norm() : extent.norm();
  return {diagonal / (o.t1 - o.t0), "domain / time range"};
}

// At least 2 seed vertices must lie inside the domain, with data, at t0 (the engine's own check
// knows neither the time nor the names).
void check_seed(const UnsteadyField& flow, const Seed<3>& seed, const PathSurfaceOptions& o) {
  const int d = flow.dimension();
  SeedSurvey survey;
  for (double s : seed.parameters) {
    Vec3 v = Vec3::Zero();
    const Vec3 x = seed.point(s);
    survey.add(x, flow.velocity(x, o.t0, v), v);
  }
  char t0[32];
  std::snprintf(t0, sizeof t0, "%g", o.t0);
  SeedContext context;
  context.seed = o.seed_name.empty() ? "the seed curve" : "seed '" + o.seed_name + "'";
  context.field = "field '" + (o.field_name.empty() ? flow.describe() : o.field_name) + "'";
  context.when = std::string(" at t0 = ") + t0;
  context.domain = describe_box(flow.domain(), d);
  const TimeRange times = flow.time_range();
  if (std::isfinite(times.begin) || std::isfinite(times.end)) {
    char range[80];
    std::snprintf(range, sizeof range, ", t in [%g, %g]", times.begin, times.end);
    context.domain += range;
  }
  context.about = o.field_name.empty() ? "" : flow.describe();
  context.dimension = d;
  require_seed_inside(survey, context, false);
}

struct Run {
  const UnsteadyField& flow;
  StreamedField* streamed = nullptr;
  BrickCache* cache = nullptr;
  bool shared_band = false;  ///< the driver holds one band for several surfaces
};

}  // namespace

/// One path surface through the lifted field R^N (N = d + 1), one front step at a time.
class PathSurfaceBuilder::Impl {
 public:
  virtual ~Impl() = default;
  virtual bool next() = 0;
  virtual void step() = 0;
  virtual void cancel() = 0;
  virtual double front_time() = 0;
  virtual double step_time() const = 0;
  virtual void front_samples(std::vector<FrontSample>& out) = 0;
  virtual BandPrediction prediction() const = 0;
  virtual int steps_done() const = 0;
  virtual PathState state() const = 0;
  virtual PathSurfaceResult finish() = 0;
};

namespace {

template <int N>
class PathRun final : public PathSurfaceBuilder::Impl {
 public:
  PathRun(const Run& run, const SeedCurve& curve, int seed_count, const PathSurfaceOptions& o,
          const PathState* resume)
      : run_(run), curve_(curve), o_(o), tracked_(run.flow), start_(Clock::now()) {
    if (seed_count < 2)
      throw InvalidArgument("a path surface needs at least 2 seed vertices, got " +
                            std::to_string(seed_count));
    if ((o.device || o.shared_bulk) && !run.cache)
      throw InvalidArgument("device: bulk advection moves the front through a gridded series "
                            "read through a cache; '" +
                            (o.field_name.empty() ? run.flow.describe() : o.field_name) +
                            "' is a field in memory (sample it onto a grid first)");
    PathReport& pr = result_.path;
    pr.t0 = o.t0;
    pr.t1 = o.t1;
    pr.dimension = N - 1;
    pr.streamed = run.streamed != nullptr;
    const Seed<3> seed3 = make_seed(curve, seed_count);
    if (resume) {
      // The seed was checked and c chosen when the surface began: the state carries c, so a
      // resumed surface needs no data at t0.
      pr.time_scale = resume->time_scale;
      pr.time_scale_source = resume->time_scale_source;
      pr.band = resume->band;
      pr.time_reached = resume->time_reached;
      observed_ = {resume->observed_begin, resume->observed_end};
    } else {
      if (run.streamed) {
        // The seed's own units, for the time scale and the engine's first evaluations.
        std::vector<FrontSample> seeds;
        for (double s : seed3.parameters) seeds.push_back({seed3.point(s), o.t0, Vec3::Zero()});
        BandPrediction around;
        around.edge = o.engine.edge;
        around.time_scale = 1e300;  // no reach in time: the steps around t0
        around.pinned_steps = 1;
        around.prefetch_steps = 0;
        run.streamed->update_front(seeds, around);
      }
      check_seed(run.flow, seed3, o);
      const std::pair<double, std::string> scale = choose_time_scale(run.flow, seed3, o);
      pr.time_scale = scale.first;
      pr.time_scale_source = scale.second;
      observed_ = {o.t0, o.t0};
    }
    c_ = pr.time_scale;
    lifted_ = std::make_unique<LiftedField<N>>(tracked_, c_, TimeRange{o.t0, o.t1}, o.t0);
    seed_.parameters = seed3.parameters;
    seed_.closed = seed3.closed;
    seed_.point = [curve = curve_, lifted = lifted_.get(), t0 = o.t0](double s) {
      return lifted->lift(curve.point(s), t0);
    };
    const double step_time = o.engine.edge / c_;  // the most a vertex moves in time per step
    const bool backwards = o.engine.negative_alpha == NegativeAlpha::keep;
    prediction_.edge = o.engine.edge;
    prediction_.time_scale = c_;
    prediction_.back_time = (backwards ? 1.0 : 0.25) * step_time;
    if (run.streamed) {
      before_ = run.cache->statistics();
      wait_before_ = before_.wait_seconds;
    }
    StreamSurfaceOptions engine = o.engine;
    // The stall cut and gap closing are the stream surface's: a path surface's front waits by
    // design (the lag bound holds its lead back), and its mesh lives in space-time.
    engine.stall_steps = 0;
    engine.close_gaps = false;
    // The flow notes the time band of every evaluation in the step that makes it: seed-shot
    // legs and front samples taken ahead, between steps, would land in another step's band.
    engine.shots_ahead = false;
    engine.samples_ahead = false;
    if (o.max_band > 0) {
      engine.lag_axis = N - 1;  // the lifted time coordinate τ = c t
      engine.max_lag = c_ * o.max_band;
    }
    if (resume) {
      const auto* state = std::get_if<EngineState<N>>(&resume->engine);
      if (!state)
        throw InvalidArgument("path surface: the saved state is of a " +
                              std::to_string(resume->engine.index() == 0 ? 2 : 3) +
                              "D flow, this series is " + std::to_string(N - 1) + "D");
      builder_ = std::make_unique<SurfaceBuilder<N>>(*lifted_, seed_, engine, *state);
    } else {
      builder_ = std::make_unique<SurfaceBuilder<N>>(*lifted_, seed_, engine);
    }
    if ((o.device || o.shared_bulk) && run.cache) attach_bulk_advance(*run.cache, engine);
  }

  bool next() override {
    if (!builder_->next()) return false;
    // The cache's own hook: before each front step, pin what the step samples around each
    // vertex and prefetch what the following steps will reach.
    if (run_.streamed && !run_.shared_band && !hold_band(builder_->front())) {
      builder_->cancel();
      return false;
    }
    if (!after_step(builder_->progress())) {
      builder_->cancel();
      return false;
    }
    return true;
  }

  void step() override {
    builder_->step();
    if (bulk_) {
      // The band records every time the step reached, the bulk advance's too.
      if (const auto [lo, hi] = bulk_->take_time_range(); lo <= hi) {
        tracked_.note(lo);
        tracked_.note(hi);
      }
    }
  }
  void cancel() override { builder_->cancel(); }
  int steps_done() const override { return builder_->steps_done(); }

  double front_time() override {
    const FrontSnapshot f = builder_->front();
    double t = kInf;
    for (std::size_t i = N - 1; i < f.positions.size(); i += N)
      t = std::min(t, lifted_->time_of(f.positions[i]));
    return t;
  }

  double step_time() const override { return o_.engine.edge / c_; }

  void front_samples(std::vector<FrontSample>& out) override {
    const FrontSnapshot f = builder_->front();
    for (std::size_t i = 0; i + N <= f.positions.size(); i += N) {
      FrontSample sample;
      for (int a = 0; a < N - 1; ++a) sample.x[a] = f.positions[i + static_cast<std::size_t>(a)];
      sample.t = lifted_->time_of(f.positions[i + N - 1]);
      sample.time_scale = c_;
      // Where the band of another surface replaced this one's, read the velocity (a slow-path
      // pin): a vertex taken for still would be given the reach of a whole front step in time.
      if (!run_.streamed->resident_velocity(sample.x, sample.t, sample.v) &&
          run_.streamed->velocity(sample.x, sample.t, sample.v) != FieldStatus::inside)
        sample.v.setZero();
      out.push_back(sample);
    }
  }

  BandPrediction prediction() const override { return prediction_; }

  PathState state() const override {
    PathState s;
    s.engine = builder_->state();
    s.time_scale = c_;
    s.time_scale_source = result_.path.time_scale_source;
    s.band = result_.path.band;
    s.time_reached = result_.path.time_reached;
    s.observed_begin = observed_.first;
    s.observed_end = observed_.second;
    return s;
  }

  PathSurfaceResult finish() override {
    PathReport& pr = result_.path;
    SurfaceResult sr = builder_->finish();
    // The last step has no progress call after it: record its band here.
    if (const auto [lo, hi] = tracked_.take(); lo <= hi && sr.report.steps > 0 &&
                                              pr.band.size() < static_cast<std::size_t>(sr.report.steps)) {
      BandRecord b;
      b.step = sr.report.steps;
      b.t_min = lo;
      b.t_max = hi;
      if (run_.streamed) b.first_step = band_.first_step, b.last_step = band_.last_step;
      if (run_.streamed) b.pinned_units = band_.pinned;
      pr.band.push_back(b);
    }
    if (run_.streamed && pr.complete) {
      if (const std::string e = run_.streamed->error(); !e.empty()) {
        pr.complete = false;
        pr.message = e;
      }
    }
    // Spatial mesh with physical time; space-time positions for 2D flows.
    result_.mesh = std::move(sr.mesh);
    Mesh& mesh = result_.mesh;
    for (std::size_t i = 0; i < mesh.vertex_count(); ++i) {
      if constexpr (N == 3) {
        const double t = lifted_->time_of(mesh.positions[i][2]);
        result_.spacetime_positions.emplace_back(mesh.positions[i][0], mesh.positions[i][1], t);
        mesh.positions[i][2] = 0;
        mesh.time[i] = t;
      } else {
        mesh.time[i] += o_.t0;
      }
      pr.time_reached = std::max(pr.time_reached, mesh.time[i]);
    }
    // Per step: the time range of the vertices it created.
    for (BandRecord& b : pr.band) {
      b.vertex_t_min = kInf;
      b.vertex_t_max = -kInf;
    }
    for (std::size_t i = 0; i < mesh.vertex_count(); ++i) {
      const auto k = static_cast<std::size_t>(mesh.step[i]);
      if (k >= 1 && k <= pr.band.size()) {
        BandRecord& b = pr.band[k - 1];
        b.vertex_t_min = std::min(b.vertex_t_min, mesh.time[i]);
        b.vertex_t_max = std::max(b.vertex_t_max, mesh.time[i]);
      }
    }
    for (BandRecord& b : pr.band)
      if (b.vertex_t_min > b.vertex_t_max) b.vertex_t_min = b.vertex_t_max = b.t_max;
    // A surface cut short by a budget before its path lines reached t1 did not do what was asked.
    const StopReason reason = sr.report.stop_reason;
    if (pr.complete && pr.time_reached < o_.t1 - 1e-6 * (o_.t1 - o_.t0) &&
        (reason == StopReason::steps || reason == StopReason::vertex_budget ||
         reason == StopReason::time_budget)) {
      pr.complete = false;
      const char* raise = reason == StopReason::steps           ? "--steps"
                          : reason == StopReason::vertex_budget ? "--max-vertices"
                                                                : "--time-budget";
      pr.message = "stopped at t = " + std::to_string(pr.time_reached) + " of t1 = " +
                   std::to_string(o_.t1) + ": " + to_string(reason) + " reached (raise " + raise +
                   ")";
    }
    // Short of t1 for any other reason, the surface is incomplete too, and says why; at t1 the
    // path lines leave the lifted domain through its end, which is no "left the domain".
    // The last front ends within about a front step (ℓ / c in time) of where it stops.
    const double close = std::max(1e-6 * (o_.t1 - o_.t0), 1.5 * o_.engine.edge / c_);
    const double data_end = run_.flow.time_range().end;
    if (pr.complete && pr.time_reached < o_.t1 - close) {
      if (data_end < o_.t1 - close && pr.time_reached >= data_end - close) {
        pr.complete = false;
        pr.message = "the data end at t = " + std::to_string(data_end) + ", before t1 = " +
                     std::to_string(o_.t1) + ": the surface stops there";
      } else if (reason == StopReason::fronts_exhausted) {
        pr.complete = false;
        pr.message = "stopped at t = " + std::to_string(pr.time_reached) + " of t1 = " +
                     std::to_string(o_.t1) + ": every front stalled or became shorter than two "
                     "edges (fronts_exhausted)";
      }
    }
    if (reason == StopReason::left_domain && pr.time_reached >= o_.t1 - close)
      sr.report.stop_reason = StopReason::end_time;
    result_.report = std::move(sr.report);
    if (!pr.complete) {
      result_.report.complete = false;
      if (!result_.report.message.empty()) result_.report.message += "; ";
      result_.report.message += pr.message;
    }
    pr.total_seconds = std::chrono::duration<double>(Clock::now() - start_).count();
    if (run_.streamed) {
      pr.cache = run_.cache->statistics();
      pr.slow_evaluations = run_.streamed->slow_evaluations();
      pr.wait_seconds = pr.cache.wait_seconds - wait_before_;
      // This surface's share (a cache may have served an earlier surface first).
      pr.io_seconds = pr.cache.read_seconds - before_.read_seconds;
      pr.decode_seconds = pr.cache.decode_seconds - before_.decode_seconds;
    }
    pr.compute_seconds = pr.total_seconds - pr.wait_seconds;
    if (bulk_) {
      pr.device = bulk_->backend_name();
      if (pr.device.empty())
        pr.device = "none (auto: no front reached " + std::to_string(bulk_min_vertices_) +
                    " vertices, or no CUDA device)";
      pr.device_min_vertices = bulk_min_vertices_;
      pr.device_calls = bulk_->calls();
      pr.device_statistics = bulk_->statistics();
    }
    return std::move(result_);
  }

 private:
  // The front advance through a BatchAdvector (PathSurfaceOptions::device). `auto` without a
  // CUDA device keeps the per-vertex advance.
  void attach_bulk_advance(BrickCache& cache, const StreamSurfaceOptions& engine) {
    const advect::Device device = o_.shared_bulk ? o_.shared_bulk->device() : *o_.device;
    std::size_t min_vertices = o_.device_min_vertices;
    const bool automatic = device == advect::Device::auto_select;
    if (automatic && min_vertices == 0) min_vertices = kCudaFrontBreakEven;
    BulkFrontOptions bo;
    bo.time_scale = c_;
    bo.time_origin = o_.t0;
    bo.times = {o_.t0, o_.t1};
    bo.min_vertices = min_vertices;
    bulk_min_vertices_ = min_vertices;
    // The engine's step spans at most ℓ / c in time.
    bo.method = advect::front_method(engine, c_);
    if (const std::shared_ptr<SharedBulkAdvance> shared = o_.shared_bulk) {
      bulk_ = std::make_unique<BulkFrontIntegrator<N>>(
          shared->steps(), [shared] { return shared->backend(); }, bo);
      builder_->set_front_integrator(bulk_.get());
      return;
    }
    steps_ = std::make_unique<CachedSteps>(cache);
    if (automatic) {
      // CUDA starts (and is looked for) only when a front reaches the break-even size.
      const std::size_t bytes = o_.device_bytes;
      bulk_ = std::make_unique<BulkFrontIntegrator<N>>(
          *steps_,
          [bytes]() -> std::shared_ptr<advect::BatchAdvector> {
            if (!advect::cuda_available()) return nullptr;
            return advect::make_advector(advect::Device::cuda, bytes);
          },
          bo);
    } else {
      // Asked for by name: a missing device is an error at the start.
      bulk_ = std::make_unique<BulkFrontIntegrator<N>>(
          *steps_, advect::make_advector(device, o_.device_bytes), bo);
    }
    builder_->set_front_integrator(bulk_.get());
  }

  bool hold_band(const FrontSnapshot& f) {
    PathReport& pr = result_.path;
    samples_.resize(f.positions.size() / N);
    for (std::size_t i = 0; i < samples_.size(); ++i) {
      FrontSample& sample = samples_[i];
      sample.x.setZero();
      for (int a = 0; a < N - 1; ++a) sample.x[a] = f.positions[i * N + static_cast<std::size_t>(a)];
      sample.t = lifted_->time_of(f.positions[i * N + N - 1]);
      if (!run_.streamed->resident_velocity(sample.x, sample.t, sample.v)) sample.v.setZero();
    }
    try {
      band_ = run_.streamed->update_front(samples_, prediction_);
    } catch (const std::exception& e) {
      pr.complete = false;
      pr.message = e.what();
      return false;
    }
    return true;
  }

  // After each front step (and before the first): the band it used, errors, the user's progress.
  bool after_step(const Progress& p) {
    PathReport& pr = result_.path;
    const auto [lo, hi] = tracked_.take();
    if (lo <= hi) observed_ = {lo, hi};
    if (p.step > 0 && pr.band.size() < static_cast<std::size_t>(p.step)) {
      BandRecord b;
      b.step = p.step;
      b.t_min = observed_.first;
      b.t_max = observed_.second;
      if (run_.streamed) b.first_step = band_.first_step, b.last_step = band_.last_step;
      if (run_.streamed) b.pinned_units = band_.pinned;
      pr.band.push_back(b);
    }
    pr.time_reached = std::max(pr.time_reached, observed_.second);
    if (run_.streamed) {
      if (const std::string e = run_.streamed->error(); !e.empty()) {
        pr.complete = false;
        pr.message = e;
        return false;
      }
    }
    if (o_.progress) {
      PathProgress pp;
      pp.engine = p;
      pp.t0 = o_.t0;
      pp.t1 = o_.t1;
      pp.time_reached = pr.time_reached;
      pp.band_begin = observed_.first;
      pp.band_end = observed_.second;
      pp.streamed = pr.streamed;
      if (run_.streamed) {
        pp.band_first = band_.first_step;
        pp.band_last = band_.last_step;
        pp.cache = run_.cache->statistics();
      }
      if (!o_.progress(pp)) {
        pr.complete = false;
        if (pr.message.empty()) pr.message = "cancelled";
        return false;
      }
    }
    return true;
  }

  Run run_;
  SeedCurve curve_;
  PathSurfaceOptions o_;
  TrackedFlow tracked_;
  Clock::time_point start_;
  PathSurfaceResult result_;
  double c_ = 1;
  std::unique_ptr<LiftedField<N>> lifted_;
  Seed<N> seed_;
  std::unique_ptr<SurfaceBuilder<N>> builder_;
  std::pair<double, double> observed_{0, 0};
  double wait_before_ = 0;
  BandUpdate band_;
  BandPrediction prediction_;
  std::vector<FrontSample> samples_;
  CacheStatistics before_;
  std::unique_ptr<CachedSteps> steps_;  // the bulk front advance (device set), else null
  std::size_t bulk_min_vertices_ = 0;
  std::unique_ptr<BulkFrontIntegrator<N>> bulk_;
};

std::unique_ptr<PathSurfaceBuilder::Impl> make_run(const Run& run, const SeedCurve& seed,
                                                   int seed_count, const PathSurfaceOptions& options,
                                                   const PathState* resume) {
  check_options(options, run.flow);
  if (run.flow.dimension() == 2)
    return std::make_unique<PathRun<3>>(run, seed, seed_count, options, resume);
  return std::make_unique<PathRun<4>>(run, seed, seed_count, options, resume);
}

PathSurfaceResult drive(PathSurfaceBuilder& builder) {
  while (builder.next()) builder.step();
  return builder.finish();
}

}  // namespace

PathSurfaceBuilder::PathSurfaceBuilder(const UnsteadyField& flow, const SeedCurve& seed,
                                       int seed_count, const PathSurfaceOptions& options,
                                       const PathState* resume)
    : impl_(make_run(Run{flow}, seed, seed_count, options, resume)) {}

PathSurfaceBuilder::PathSurfaceBuilder(BrickCache& cache, const SeedCurve& seed, int seed_count,
                                       const PathSurfaceOptions& options, const PathState* resume)
    : streamed_(std::make_unique<StreamedField>(cache)) {
  PathSurfaceOptions o = options;
  // Inserting on the true path line would integrate from the seed time, outside the band.
  if (o.engine.insertion == Insertion::streamline) o.engine.insertion = Insertion::cubic;
  impl_ = make_run(Run{*streamed_, streamed_.get(), &cache}, seed, seed_count, o, resume);
}

PathSurfaceBuilder::PathSurfaceBuilder(StreamedField& shared, BrickCache& cache,
                                       const SeedCurve& seed, int seed_count,
                                       const PathSurfaceOptions& options, const PathState* resume) {
  PathSurfaceOptions o = options;
  if (o.engine.insertion == Insertion::streamline) o.engine.insertion = Insertion::cubic;
  impl_ = make_run(Run{shared, &shared, &cache, true}, seed, seed_count, o, resume);
}

PathSurfaceBuilder::~PathSurfaceBuilder() = default;
bool PathSurfaceBuilder::next() { return impl_->next(); }
void PathSurfaceBuilder::step() { impl_->step(); }
void PathSurfaceBuilder::cancel() { impl_->cancel(); }
double PathSurfaceBuilder::front_time() { return impl_->front_time(); }
double PathSurfaceBuilder::step_time() const { return impl_->step_time(); }
void PathSurfaceBuilder::front_samples(std::vector<FrontSample>& out) { impl_->front_samples(out); }
BandPrediction PathSurfaceBuilder::prediction() const { return impl_->prediction(); }
int PathSurfaceBuilder::steps_done() const { return impl_->steps_done(); }
PathState PathSurfaceBuilder::state() const { return impl_->state(); }
PathSurfaceResult PathSurfaceBuilder::finish() { return impl_->finish(); }

PathSurfaceResult build_path_surface(const UnsteadyField& flow, const SeedCurve& seed,
                                     int seed_count, const PathSurfaceOptions& options) {
  PathSurfaceBuilder builder(flow, seed, seed_count, options);
  return drive(builder);
}

PathSurfaceResult build_path_surface(BrickCache& cache, const SeedCurve& seed, int seed_count,
                                     const PathSurfaceOptions& options) {
  PathSurfaceBuilder builder(cache, seed, seed_count, options);
  return drive(builder);
}

}  // namespace orthofront::spacetime
