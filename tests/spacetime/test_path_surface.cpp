#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <random>

#include "orthofront/error.h"
#include "orthofront/field/analytic.h"
#include "orthofront/integrate/runge_kutta.h"
#include "orthofront/io/error.h"
#include "orthofront/quality/quality.h"
#include "orthofront/spacetime/path_surface.h"
#include "orthofront/spacetime/sampled_series.h"
#include "orthofront/spacetime/streamed_field.h"

using namespace orthofront;
using namespace orthofront::spacetime;

namespace {

// The unsteady field as the steady field (v, 1) over (x, t): independent path-line reference.
class TimeAsCoordinate final : public Field<4> {
 public:
  explicit TimeAsCoordinate(const UnsteadyField& f) : f_(f) {}
  FieldStatus velocity(const Vec<4>& x, Vec<4>& v) const override {
    Vec3 w = Vec3::Zero();
    const FieldStatus st = f_.velocity(x.head<3>(), x[3], w);
    v << w, 1.0;
    return st;
  }
  FieldStatus velocity_jacobian(const Vec<4>& x, Vec<4>& v, Mat<4>& J) const override {
    J.setZero();
    return velocity(x, v);
  }
  Box<4> domain() const override { return Box<4>{}; }
  std::string describe() const override { return f_.describe(); }

 private:
  const UnsteadyField& f_;
};

Vec3 path_line(const UnsteadyField& f, const Vec3& x0, double t0, double t) {
  Vec3 exact;
  if (f.exact_flow_map(x0, t0, t, exact)) return exact;
  Vec<4> start;
  start << x0, t0;
  const auto r = integrate_dopri5<4>(TimeAsCoordinate(f), start, t - t0, Tolerance{1e-13, 1e-13});
  REQUIRE(r.status == FieldStatus::inside);
  return r.x.head<3>();
}

// A steady flow seen as an unsteady one.
class Steady final : public UnsteadyField {
 public:
  Steady(const Field3& f, int d) : f_(f), d_(d) {}
  int dimension() const override { return d_; }
  FieldStatus velocity(const Vec3& x, double, Vec3& v) const override { return f_.velocity(x, v); }
  FieldStatus velocity_jacobian(const Vec3& x, double, Vec3& v, Mat3& J,
                                Vec3& dvdt) const override {
    dvdt.setZero();
    return f_.velocity_jacobian(x, v, J);
  }
  Box<3> domain() const override { return f_.domain(); }
  TimeRange time_range() const override { return {}; }
  std::string describe() const override { return f_.describe(); }

 private:
  const Field3& f_;
  int d_;
};

// The 2D steady flow (v_x, v_y) with a constant third component c: its stream surfaces are the
// lifted path surfaces, built independently of LiftedField.
class WithConstantZ final : public Field3 {
 public:
  WithConstantZ(const Field3& f, double c, double z1) : f_(f), c_(c), z1_(z1) {}
  FieldStatus velocity(const Vec3& x, Vec3& v) const override {
    if (!(x[2] >= 0 && x[2] <= z1_)) return FieldStatus::outside;
    const FieldStatus st = f_.velocity(Vec3(x[0], x[1], 0), v);
    v[2] = c_;
    return st;
  }
  FieldStatus velocity_jacobian(const Vec3& x, Vec3& v, Mat3& J) const override {
    if (!(x[2] >= 0 && x[2] <= z1_)) return FieldStatus::outside;
    const FieldStatus st = f_.velocity_jacobian(Vec3(x[0], x[1], 0), v, J);
    v[2] = c_;
    J.row(2).setZero();
    J.col(2).setZero();
    return st;
  }
  Box<3> domain() const override {
    Box<3> b = f_.domain();
    b.lo[2] = 0;
    b.hi[2] = z1_;
    return b;
  }
  std::string describe() const override { return "with-z"; }

 private:
  const Field3& f_;
  double c_, z1_;
};

PathSurfaceOptions path_options(double t0, double t1, double edge) {
  PathSurfaceOptions o;
  o.t0 = t0;
  o.t1 = t1;
  o.engine.edge = edge;
  o.engine.max_steps = 100000;
  return o;
}

}  // namespace

TEST_CASE("path surface: a steady 2D flow lifted equals the stream surface of (v, c)",
          "[spacetime][path]") {
  const auto saddle = make_analytic_field("sinus");
  const Steady flow(*saddle, 2);
  const double c = 1.5, t1 = 3.0;
  PathSurfaceOptions o = path_options(0.0, t1, 0.2);
  o.time_scale = c;
  const SeedCurve seed = SeedCurve::line(Vec3(-2, 0, 0), Vec3(2, 0, 0));
  const PathSurfaceResult path = build_path_surface(flow, seed, 12, o);
  CHECK(path.path.time_scale == c);
  CHECK(path.path.time_scale_source == "given");

  const WithConstantZ lifted(*saddle, c, c * t1);
  const SurfaceResult stream = build_stream_surface<3>(lifted, make_seed(seed, 12), o.engine);
  REQUIRE(path.mesh.vertex_count() == stream.mesh.vertex_count());
  REQUIRE(path.mesh.face_count() == stream.mesh.face_count());
  REQUIRE(path.mesh.vertex_count() > 100);
  double worst = 0;
  for (std::size_t i = 0; i < path.mesh.vertex_count(); ++i) {
    const Vec3& p = stream.mesh.positions[i];
    worst = std::max(worst, (path.spacetime_positions[i] - Vec3(p[0], p[1], p[2] / c)).norm());
    worst = std::max(worst, std::abs(path.mesh.positions[i][2]));
  }
  CHECK(worst < 1e-9);
  CHECK(path.path.time_reached == Approx(t1).epsilon(1e-3));
}

TEST_CASE("path surface: a surface that starts at a large time (seconds since 1950) is the one "
          "that starts at 0",
          "[spacetime][path]") {
  // Real data count time from an epoch: t0 ~ 2.3e9 s. The lifted coordinate counts from t0, so
  // the front's steps keep their digits: the same mesh, shifted in time, and the same stop.
  const auto sinus = make_analytic_field("sinus");
  const Steady flow(*sinus, 2);
  const double start = 2333664000.0;
  PathSurfaceOptions o = path_options(0.0, 3.0, 0.2);
  o.time_scale = 1.5;
  const SeedCurve seed = SeedCurve::line(Vec3(-2, 0, 0), Vec3(2, 0, 0));
  const PathSurfaceResult near = build_path_surface(flow, seed, 12, o);
  o.t0 += start;
  o.t1 += start;
  const PathSurfaceResult far = build_path_surface(flow, seed, 12, o);
  REQUIRE(near.mesh.vertex_count() > 100);
  CHECK(far.mesh.vertex_count() == near.mesh.vertex_count());
  CHECK(far.mesh.face_count() == near.mesh.face_count());
  CHECK(far.report.stop_reason == near.report.stop_reason);
  CHECK(far.path.time_reached - start == Approx(near.path.time_reached).margin(1e-6));
  double worst = 0;
  for (std::size_t i = 0; i < near.mesh.vertex_count() && i < far.mesh.vertex_count(); ++i) {
    const Vec3 shifted = far.spacetime_positions[i] - Vec3(0, 0, start);
    worst = std::max(worst, (shifted - near.spacetime_positions[i]).norm());
  }
  CHECK(worst < 1e-6);
}

TEST_CASE("path surface: every vertex lies on the path line of its seed parameter",
          "[spacetime][path]") {
  struct Case {
    const char* field;
    Vec3 a, b;
    double t1, edge;
  };
  const Case cases[] = {
      {"double-gyre", Vec3(0.3, 0.25, 0), Vec3(0.9, 0.7, 0), 6.0, 0.05},
      {"moving-spiral:dim=2", Vec3(-2, 1, 0), Vec3(1, 2, 0), 3.0, 0.1},
      {"moving-spiral", Vec3(-2, 1, 0.5), Vec3(1, 2, -0.5), 2.0, 0.15},
      {"double-gyre-3d", Vec3(0.3, 0.25, 0.3), Vec3(0.9, 0.7, 0.6), 3.0, 0.06},
  };
  for (const Case& k : cases) {
    const auto flow = make_unsteady_field(k.field);
    PathSurfaceOptions o = path_options(0.5, k.t1, k.edge);
    const SeedCurve seed = SeedCurve::line(k.a, k.b);
    const PathSurfaceResult r = build_path_surface(*flow, seed, 8, o);
    INFO(k.field << ": " << r.mesh.vertex_count() << " vertices, c = " << r.path.time_scale);
    REQUIRE(r.mesh.vertex_count() > 50);
    CHECK(r.path.time_scale_source == "median seed speed");
    CHECK(r.report.insertion_fallbacks == 0);
    const Vec3 extent = flow->domain().extent();
    const double size = flow->dimension() == 2 ? extent.head<2>().norm() : extent.norm();
    double worst = 0, t_max = 0;
    for (std::size_t i = 0; i < r.mesh.vertex_count(); ++i) {
      const double t = r.mesh.time[i];
      Vec3 p = r.mesh.positions[i];
      // The engine stores s modulo 1, so the end s = 1 of an open seed reads 0.
      double error = std::numeric_limits<double>::infinity();
      for (double s : {r.mesh.s[i], r.mesh.s[i] == 0 ? 1.0 : r.mesh.s[i]}) {
        const Vec3 exact = path_line(*flow, seed.point(s), o.t0, t);
        if (flow->dimension() == 2) p[2] = exact[2];
        error = std::min(error, (p - exact).norm() / size);
      }
      worst = std::max(worst, error);
      t_max = std::max(t_max, t);
      REQUIRE(t >= o.t0 - 1e-12);
      REQUIRE(t <= k.t1 + 1e-9);
    }
    CHECK(worst <= 1e-6);
    CHECK(t_max > k.t1 - k.edge / r.path.time_scale);  // the surface ends at t1
    REQUIRE_FALSE(r.path.band.empty());
    for (const BandRecord& b : r.path.band) CHECK(b.t_max >= b.t_min);
  }
}

TEST_CASE("streamed field: sampled and analytic fields agree to interpolation order",
          "[spacetime][path]") {
  const auto flow = make_unsteady_field("double-gyre");
  double errors[2] = {0, 0};
  for (int level = 0; level < 2; ++level) {
    const std::int64_t n = level == 0 ? 41 : 81;
    SampledTimeSeries series(*flow, uniform_grid(flow->domain(), 2, n),
                             uniform_times(0, 4, level == 0 ? 20 : 40));
    CacheOptions co;
    co.budget_bytes = 64 << 20;
    BrickCache cache(series, co);
    StreamedField field(cache);
    field.update_band(0, 4);
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> ux(0.05, 1.95), uy(0.05, 0.95), ut(0, 4);
    for (int i = 0; i < 2000; ++i) {
      const Vec3 x(ux(rng), uy(rng), 0);
      const double t = ut(rng);
      Vec3 a, b;
      REQUIRE(field.velocity(x, t, a) == FieldStatus::inside);
      REQUIRE(flow->velocity(x, t, b) == FieldStatus::inside);
      errors[level] = std::max(errors[level], (a.head<2>() - b.head<2>()).norm());
    }
    CHECK(field.slow_evaluations() == 0);
  }
  INFO("max errors " << errors[0] << " " << errors[1]);
  CHECK(errors[0] < 1e-2);
  CHECK(errors[0] / errors[1] > 3.0);  // second order: halving h and Δt divides the error by ~4
}

TEST_CASE("path surface: streamed through a narrow band under a budget", "[spacetime][path]") {
  const auto flow = make_unsteady_field("double-gyre");
  SampledTimeSeries series(*flow, uniform_grid(flow->domain(), 2, 101), uniform_times(0, 10, 100));
  CacheOptions co;
  co.budget_bytes = 30 * series.step_bytes();
  co.max_live_tokens = 2;  // each whole step in flight reserves 3 steps of room
  BrickCache cache(series, co);
  PathSurfaceOptions o = path_options(0.0, 6.0, 0.05);
  const SeedCurve seed = SeedCurve::line(Vec3(0.3, 0.25, 0), Vec3(0.9, 0.7, 0));
  const PathSurfaceResult r = build_path_surface(cache, seed, 8, o);
  INFO(r.path.message);
  REQUIRE(r.path.complete);
  CHECK(r.path.streamed);
  CHECK(r.path.time_reached == Approx(6.0).epsilon(1e-3));
  CHECK(r.path.cache.peak_bytes <= co.budget_bytes);
  CHECK(r.path.slow_evaluations == 0);
  // Steps 0..60 were needed; each read once.
  std::size_t reads = 0;
  for (std::size_t k = 0; k < 100; ++k) {
    CHECK(r.path.cache.units_read_per_step[k] <= 1);
    reads += r.path.cache.units_read_per_step[k];
  }
  CHECK(reads >= 61);
  CHECK(r.path.cache.evictions > 40);
  std::size_t widest = 0;
  for (const BandRecord& b : r.path.band) widest = std::max(widest, b.last_step - b.first_step + 1);
  CHECK(widest <= 28);  // the band, not the whole series (61 steps), was resident
  // Vertices lie on the analytic path lines up to the interpolation error.
  double worst = 0;
  for (std::size_t i = 0; i < r.mesh.vertex_count(); ++i) {
    double error = std::numeric_limits<double>::infinity();
    for (double s : {r.mesh.s[i], r.mesh.s[i] == 0 ? 1.0 : r.mesh.s[i]}) {
      const Vec3 exact = path_line(*flow, seed.point(s), 0.0, r.mesh.time[i]);
      error = std::min(error, (r.mesh.positions[i].head<2>() - exact.head<2>()).norm());
    }
    worst = std::max(worst, error);
  }
  CHECK(worst < 0.02);
  // Folds are a property of the surface in space-time; its projection onto the plane overlaps.
  Mesh spacetime = r.mesh;
  spacetime.positions.assign(r.spacetime_positions.begin(), r.spacetime_positions.end());
  const QualityReport q = measure_quality(spacetime);
  CHECK(q.folds == 0);
  CHECK(q.non_manifold_edges == 0);
}

TEST_CASE("path surface: a corrupt step mid-run keeps the surface built so far",
          "[spacetime][path]") {
  const auto flow = make_unsteady_field("double-gyre");
  class Broken final : public SampledTimeSeries {
   public:
    using SampledTimeSeries::SampledTimeSeries;
    io::RawStep read_raw(std::size_t step) const override {
      if (step == 30) throw io::FormatError("gyre.h5: dataset /steps/30/velocity is truncated");
      return SampledTimeSeries::read_raw(step);
    }
  };
  Broken series(*flow, uniform_grid(flow->domain(), 2, 51), uniform_times(0, 10, 100));
  CacheOptions co;
  co.budget_bytes = 40 * series.step_bytes();
  BrickCache cache(series, co);
  const PathSurfaceResult r = build_path_surface(
      cache, SeedCurve::line(Vec3(0.3, 0.25, 0), Vec3(0.9, 0.7, 0)), 8, path_options(0, 6, 0.05));
  CHECK_FALSE(r.path.complete);
  CHECK_FALSE(r.report.complete);
  CHECK_THAT(r.path.message, Catch::Contains("time step 30") && Catch::Contains("gyre.h5"));
  REQUIRE(r.mesh.vertex_count() > 50);
  CHECK(r.path.time_reached < 3.0 + 1e-9);
  CHECK(r.path.time_reached > 2.0);
  Mesh spacetime = r.mesh;
  spacetime.positions.assign(r.spacetime_positions.begin(), r.spacetime_positions.end());
  CHECK(measure_quality(spacetime).folds == 0);
}

TEST_CASE("path surface: a band that cannot fit stops with the budget it needs",
          "[spacetime][path]") {
  const auto flow = make_unsteady_field("double-gyre");
  // Time steps 0.01 apart: the first front step (ℓ/c ≈ 0.3 time units) spans ~30 steps.
  SampledTimeSeries series(*flow, uniform_grid(flow->domain(), 2, 21), uniform_times(0, 2, 200));
  CacheOptions co;
  co.budget_bytes = 8 * series.step_bytes();
  co.max_live_tokens = 1;
  BrickCache cache(series, co);
  const PathSurfaceResult r = build_path_surface(
      cache, SeedCurve::line(Vec3(0.3, 0.25, 0), Vec3(0.9, 0.7, 0)), 8, path_options(0, 1, 0.05));
  CHECK_FALSE(r.path.complete);
  CHECK_THAT(r.path.message, Catch::Contains("is too small for the front's band") &&
                                 Catch::Contains("raise --cache-budget"));
  CHECK(r.report.steps == 0);  // stopped before the first step
  CHECK(cache.statistics().peak_bytes <= co.budget_bytes);
}

TEST_CASE("max_band keeps the front's time band bounded", "[spacetime][band]") {
  // The double gyre's stagnation points hold vertices back: without a bound the band widens.
  const auto flow = make_unsteady_field("double-gyre");
  const SeedCurve seed = SeedCurve::line(Vec3(0.1, 0.5, 0), Vec3(0.6, 0.5, 0));
  const auto widest = [](const PathSurfaceResult& r) {
    double w = 0;
    for (const BandRecord& b : r.path.band) w = std::max(w, b.vertex_t_max - b.vertex_t_min);
    return w;
  };
  PathSurfaceOptions o = path_options(0.0, 10.0, 0.02);
  const PathSurfaceResult free = build_path_surface(*flow, seed, 20, o);
  o.max_band = 0.5;
  const PathSurfaceResult bounded = build_path_surface(*flow, seed, 20, o);
  INFO("widest vertex-time band: free " << widest(free) << ", bounded " << widest(bounded));
  CHECK(widest(free) > 1.0);
  CHECK(bounded.report.lag_raised_alpha > 0);
  CHECK(free.report.lag_raised_alpha == 0);
  // A step adds at most ℓ/c of time to a vertex: the band stays within one step of the bound.
  CHECK(widest(bounded) <= 0.5 + 0.02 / bounded.path.time_scale + 1e-9);
  CHECK(bounded.path.complete);
  CHECK(bounded.report.quality.non_manifold_edges == 0);
}

TEST_CASE("a path surface cut short by a budget says so", "[spacetime][path]") {
  const auto flow = make_unsteady_field("double-gyre");
  const SeedCurve seed = SeedCurve::line(Vec3(0.3, 0.25, 0), Vec3(0.9, 0.7, 0));
  PathSurfaceOptions o = path_options(0.0, 10.0, 0.05);
  o.engine.max_vertices = 300;
  const PathSurfaceResult capped = build_path_surface(*flow, seed, 8, o);
  CHECK_FALSE(capped.path.complete);
  CHECK_FALSE(capped.report.complete);
  CHECK(capped.path.time_reached < 10.0);
  CHECK_THAT(capped.path.message, Catch::Contains("of t1 = 10") &&
                                      Catch::Contains("raise --max-vertices"));
  o.engine.max_vertices = 10'000'000;
  CHECK(build_path_surface(*flow, seed, 8, o).path.complete);  // reaching t1 is complete
}

namespace {

// The double gyre without data (as NaN in a file) where y > 0.6.
class NoDataAbove final : public UnsteadyField {
 public:
  explicit NoDataAbove(const UnsteadyField& f) : f_(f) {}
  int dimension() const override { return f_.dimension(); }
  FieldStatus velocity(const Vec3& x, double t, Vec3& v) const override {
    const FieldStatus st = f_.velocity(x, t, v);
    return st == FieldStatus::inside && x[1] > 0.6 ? FieldStatus::no_data : st;
  }
  FieldStatus velocity_jacobian(const Vec3& x, double t, Vec3& v, Mat3& J,
                                Vec3& dvdt) const override {
    const FieldStatus st = f_.velocity_jacobian(x, t, v, J, dvdt);
    return st == FieldStatus::inside && x[1] > 0.6 ? FieldStatus::no_data : st;
  }
  Box<3> domain() const override { return f_.domain(); }
  TimeRange time_range() const override { return {0, 5}; }
  std::string describe() const override { return "gyre with a hole"; }

 private:
  const UnsteadyField& f_;
};

}  // namespace

TEST_CASE("path surface: a seed outside the domain or without data names seed, field and domain",
          "[spacetime][path]") {
  using Catch::Contains;
  const auto gyre = make_unsteady_field("double-gyre");
  const NoDataAbove flow(*gyre);
  PathSurfaceOptions o = path_options(1.0, 2.0, 0.05);
  const auto message = [&](const SeedCurve& seed) {
    try {
      build_path_surface(flow, seed, 20, o);
    } catch (const InvalidArgument& e) {
      return std::string(e.what());
    }
    FAIL("no InvalidArgument thrown");
    return std::string();
  };
  const SeedCurve outside = SeedCurve::line(Vec3(5, 5, 0), Vec3(6, 6, 0));
  // Without names: the seed curve and the field's description.
  CHECK_THAT(message(outside),
             Contains("the seed curve lies outside the domain of field 'gyre with a hole' at "
                      "t0 = 1 (0 of 20 seed vertices inside, at least 2 needed; e.g. the point "
                      "(5, 5) is outside the domain [0, 2] x [0, 1], t in [0, 5])"));
  // With the names a command line gave.
  o.seed_name = "line:5,5,0:6,6,0";
  o.field_name = "hole.h5";
  CHECK_THAT(message(outside),
             Contains("seed 'line:5,5,0:6,6,0' lies outside the domain of field 'hole.h5' at t0 = 1") &&
                 Contains("t in [0, 5]; gyre with a hole)"));
  // One vertex inside is not enough.
  CHECK_THAT(message(SeedCurve::line(Vec3(1.99, 0.5, 0), Vec3(3, 0.5, 0))),
             Contains("1 of 20 seed vertices inside, at least 2 needed"));
  // Inside the domain but without data is not "outside".
  o.seed_name = "line:0.2,0.8,0:1.8,0.8,0";
  const std::string hole = message(SeedCurve::line(Vec3(0.2, 0.8, 0), Vec3(1.8, 0.8, 0)));
  CHECK_THAT(hole, Contains("seed 'line:0.2,0.8,0:1.8,0.8,0' lies where field 'hole.h5' has no "
                            "data at t0 = 1") &&
                       Contains("e.g. at the point (0.2, 0.8)"));
  CHECK_THAT(hole, !Contains("outside"));
}
