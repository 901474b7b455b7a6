#include "orthofront/spacetime/path_surface.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>

#include "orthofront/error.h"
#include "orthofront/seed/seed.h"
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
  void note(double t) const {
    double lo = lo_.load(std::memory_order_relaxed);
    while (t < lo && !lo_.compare_exchange_weak(lo, t, std::memory_order_relaxed)) {
    }
    double hi = hi_.load(std::memory_order_relaxed);
    while (t > hi && !hi_.compare_exchange_weak(hi, t, std::memory_order_relaxed)) {
    }
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
// says less): the message names the seed, the field, t0 and the domain, and tells a seed where
// the field has no data (NaN, fill values, zero vectors) from one outside.
void check_seed(const UnsteadyField& flow, const Seed<3>& seed, const PathSurfaceOptions& o) {
  const int d = flow.dimension();
  std::size_t inside = 0, no_data = 0;
  Vec3 first_outside = Vec3::Zero(), first_no_data = Vec3::Zero();
  bool any_outside = false;
  for (double s : seed.parameters) {
    Vec3 v;
    const Vec3 x = seed.point(s);
    const FieldStatus status = flow.velocity(x, o.t0, v);
    if (status == FieldStatus::inside) {
      ++inside;
    } else if (status == FieldStatus::no_data) {
      if (no_data++ == 0) first_no_data = x;
    } else if (!any_outside) {
      any_outside = true;
      first_outside = x;
    }
  }
  if (inside >= 2) return;
  const auto number = [](double value) {
    char text[32];
    std::snprintf(text, sizeof text, "%g", value);
    return std::string(text);
  };
  const auto point = [&](const Vec3& x) {
    std::string text = "(";
    for (int a = 0; a < d; ++a) text += (a ? ", " : "") + number(x[a]);
    return text + ")";
  };
  const Box<3> box = flow.domain();
  std::string domain;
  for (int a = 0; a < d; ++a)
    domain += (a ? " x [" : "[") + number(box.lo[a]) + ", " + number(box.hi[a]) + "]";
  const TimeRange times = flow.time_range();
  if (std::isfinite(times.begin) || std::isfinite(times.end))
    domain += ", t in [" + number(times.begin) + ", " + number(times.end) + "]";
  const std::string seed_text =
      o.seed_name.empty() ? "the seed curve" : "seed '" + o.seed_name + "'";
  const std::string field_text =
      "field '" + (o.field_name.empty() ? flow.describe() : o.field_name) + "'";
  const std::string about = o.field_name.empty() ? "" : "; " + flow.describe();
  if (no_data > 0 && !any_outside)
    throw InvalidArgument(seed_text + " lies where " + field_text + " has no data at t0 = " +
                          number(o.t0) + " (NaN, fill values or zero vectors; " +
                          std::to_string(inside) + " of " + std::to_string(seed.parameters.size()) +
                          " seed vertices with data, at least 2 needed; e.g. at the point " +
                          point(first_no_data) + "; domain " + domain + about + ")");
  throw InvalidArgument(seed_text + " lies outside the domain of " + field_text + " at t0 = " +
                        number(o.t0) + " (" + std::to_string(inside) + " of " +
                        std::to_string(seed.parameters.size()) +
                        " seed vertices inside, at least 2 needed; e.g. the point " +
                        point(first_outside) + " is outside the domain " + domain + about + ")");
}

struct Run {
  const UnsteadyField& flow;
  StreamedField* streamed = nullptr;
  BrickCache* cache = nullptr;
};

template <int N>
PathSurfaceResult run_path(const Run& run, const SeedCurve& curve, int seed_count,
                           const PathSurfaceOptions& o) {
  const auto start = Clock::now();
  if (seed_count < 2)
    throw InvalidArgument("a path surface needs at least 2 seed vertices, got " +
                          std::to_string(seed_count));
  PathSurfaceResult result;
  PathReport& pr = result.path;
  pr.t0 = o.t0;
  pr.t1 = o.t1;
  pr.dimension = N - 1;
  pr.streamed = run.streamed != nullptr;
  TrackedFlow tracked(run.flow);
  const Seed<3> seed3 = make_seed(curve, seed_count);
  if (run.streamed) {
    // The seed's own units, for the time scale and the engine's first evaluations (checks fit).
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
  // Not a structured binding: lambdas below capture c (clang before 16 refuses bindings there).
  const std::pair<double, std::string> scale = choose_time_scale(run.flow, seed3, o);
  const double c = scale.first;
  pr.time_scale = c;
  pr.time_scale_source = scale.second;
  const LiftedField<N> lifted(tracked, c, TimeRange{o.t0, o.t1});
  Seed<N> seed;
  seed.parameters = seed3.parameters;
  seed.closed = seed3.closed;
  seed.point = [curve, &lifted, t0 = o.t0](double s) { return lifted.lift(curve.point(s), t0); };

  const double step_time = o.engine.edge / c;  // the most a vertex moves in time per step
  const bool backwards = o.engine.negative_alpha == NegativeAlpha::keep;
  std::pair<double, double> observed{o.t0, o.t0};
  double wait_before = 0;
  BandUpdate band;
  BandPrediction prediction;
  prediction.edge = o.engine.edge;
  prediction.time_scale = c;
  prediction.back_time = (backwards ? 1.0 : 0.25) * step_time;
  std::vector<FrontSample> samples;
  // The cache's own hook: before each front step, pin what the step samples around each vertex
  // and prefetch what the following steps will reach.
  FrontHook before_step;
  CacheStatistics before;
  if (run.streamed) {
    before = run.cache->statistics();
    wait_before = before.wait_seconds;
    before_step = [&](const FrontSnapshot& f) -> bool {
      samples.resize(f.positions.size() / N);
      for (std::size_t i = 0; i < samples.size(); ++i) {
        FrontSample& sample = samples[i];
        sample.x.setZero();
        for (int a = 0; a < N - 1; ++a) sample.x[a] = f.positions[i * N + static_cast<std::size_t>(a)];
        sample.t = f.positions[i * N + N - 1] / c;
        if (!run.streamed->resident_velocity(sample.x, sample.t, sample.v)) sample.v.setZero();
      }
      try {
        band = run.streamed->update_front(samples, prediction);
      } catch (const std::exception& e) {
        pr.complete = false;
        pr.message = e.what();
        return false;
      }
      return true;
    };
  }
  auto callback = [&](const Progress& p) -> bool {
    const auto [lo, hi] = tracked.take();
    if (lo <= hi) observed = {lo, hi};
    if (p.step > 0) {
      BandRecord b;
      b.step = p.step;
      b.t_min = observed.first;
      b.t_max = observed.second;
      if (run.streamed) b.first_step = band.first_step, b.last_step = band.last_step;
      if (run.streamed) b.pinned_units = band.pinned;
      pr.band.push_back(b);
    }
    pr.time_reached = std::max(pr.time_reached, observed.second);
    if (run.streamed) {
      if (const std::string e = run.streamed->error(); !e.empty()) {
        pr.complete = false;
        pr.message = e;
        return false;
      }
    }
    if (o.progress) {
      PathProgress pp;
      pp.engine = p;
      pp.t0 = o.t0;
      pp.t1 = o.t1;
      pp.time_reached = pr.time_reached;
      pp.band_begin = observed.first;
      pp.band_end = observed.second;
      pp.streamed = pr.streamed;
      if (run.streamed) {
        pp.band_first = band.first_step;
        pp.band_last = band.last_step;
        pp.cache = run.cache->statistics();
      }
      if (!o.progress(pp)) {
        pr.complete = false;
        if (pr.message.empty()) pr.message = "cancelled";
        return false;
      }
    }
    return true;
  };
  StreamSurfaceOptions engine = o.engine;
  if (o.max_band > 0) {
    engine.lag_axis = N - 1;  // the lifted time coordinate τ = c t
    engine.max_lag = c * o.max_band;
  }
  SurfaceResult sr = build_stream_surface<N>(lifted, seed, engine, callback, before_step);
  // The last step has no callback after it: record its band here.
  if (const auto [lo, hi] = tracked.take(); lo <= hi && sr.report.steps > 0 &&
                                            pr.band.size() < static_cast<std::size_t>(sr.report.steps)) {
    BandRecord b;
    b.step = sr.report.steps;
    b.t_min = lo;
    b.t_max = hi;
    if (run.streamed) b.first_step = band.first_step, b.last_step = band.last_step;
    if (run.streamed) b.pinned_units = band.pinned;
    pr.band.push_back(b);
  }
  if (run.streamed && pr.complete) {
    if (const std::string e = run.streamed->error(); !e.empty()) {
      pr.complete = false;
      pr.message = e;
    }
  }
  // Spatial mesh with physical time; space-time positions for 2D flows.
  result.mesh = std::move(sr.mesh);
  Mesh& mesh = result.mesh;
  for (std::size_t i = 0; i < mesh.vertex_count(); ++i) {
    if constexpr (N == 3) {
      const double t = mesh.positions[i][2] / c;
      result.spacetime_positions.emplace_back(mesh.positions[i][0], mesh.positions[i][1], t);
      mesh.positions[i][2] = 0;
      mesh.time[i] = t;
    } else {
      mesh.time[i] += o.t0;
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
  if (pr.complete && pr.time_reached < o.t1 - 1e-6 * (o.t1 - o.t0) &&
      (reason == StopReason::steps || reason == StopReason::vertex_budget ||
       reason == StopReason::time_budget)) {
    pr.complete = false;
    const char* raise = reason == StopReason::steps           ? "--steps"
                        : reason == StopReason::vertex_budget ? "--max-vertices"
                                                              : "--time-budget";
    pr.message = "stopped at t = " + std::to_string(pr.time_reached) + " of t1 = " +
                 std::to_string(o.t1) + ": " + to_string(reason) + " reached (raise " + raise +
                 ")";
  }
  result.report = std::move(sr.report);
  if (!pr.complete) {
    result.report.complete = false;
    if (!result.report.message.empty()) result.report.message += "; ";
    result.report.message += pr.message;
  }
  pr.total_seconds = std::chrono::duration<double>(Clock::now() - start).count();
  if (run.streamed) {
    pr.cache = run.cache->statistics();
    pr.slow_evaluations = run.streamed->slow_evaluations();
    pr.wait_seconds = pr.cache.wait_seconds - wait_before;
    // This surface's share (a cache may have served an earlier surface first).
    pr.io_seconds = pr.cache.read_seconds - before.read_seconds;
    pr.decode_seconds = pr.cache.decode_seconds - before.decode_seconds;
  }
  pr.compute_seconds = pr.total_seconds - pr.wait_seconds;
  return result;
}

PathSurfaceResult dispatch(const Run& run, const SeedCurve& seed, int seed_count,
                           const PathSurfaceOptions& options) {
  check_options(options, run.flow);
  if (run.flow.dimension() == 2) return run_path<3>(run, seed, seed_count, options);
  return run_path<4>(run, seed, seed_count, options);
}

}  // namespace

PathSurfaceResult build_path_surface(const UnsteadyField& flow, const SeedCurve& seed,
                                     int seed_count, const PathSurfaceOptions& options) {
  return dispatch(Run{flow}, seed, seed_count, options);
}

PathSurfaceResult build_path_surface(BrickCache& cache, const SeedCurve& seed, int seed_count,
                                     const PathSurfaceOptions& options) {
  StreamedField field(cache);
  PathSurfaceOptions o = options;
  // Inserting on the true path line would integrate from the seed time, outside the band.
  if (o.engine.insertion == Insertion::streamline) o.engine.insertion = Insertion::cubic;
  return dispatch(Run{field, &field, &cache}, seed, seed_count, o);
}

}  // namespace orthofront::spacetime
