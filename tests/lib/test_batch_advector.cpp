// Bulk advection on the CPU backend: against the exact flow of a linear field (which multilinear
// interpolation and linear time interpolation reproduce exactly), statuses at the domain's edge,
// in cells without data and outside the time range, and results that do not depend on the batch;
// a resident set (particles kept between calls) against the same calls.
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "orthofront/advect/batch_advector.h"
#include "orthofront/error.h"
#include "lib/grid_faces.h"
#include "lib/resident_scenario.h"

using namespace orthofront;
using namespace orthofront::advect;

namespace {

// v(x, t) = (A0 + t A1) x: a rotation in (x, y) with a strain growing in time, and a decay in z.
// Samples on grids of quarter steps at times of quarter units are exact in float.
std::array<double, 3> linear_velocity(const std::array<double, 3>& x, double t) {
  return {-x[1] + 0.5 * t * x[0], x[0] - 0.5 * t * x[1], -0.25 * x[2]};
}

// The exact path by classic RK4 with a tiny fixed step on the formula (no grid, no slabs).
std::array<double, 3> reference(std::array<double, 3> x, double t0, double t1, int dimension) {
  const int n = 20000;
  const double h = (t1 - t0) / n;
  double t = t0;
  const auto add = [](std::array<double, 3> a, const std::array<double, 3>& b, double s) {
    for (int d = 0; d < 3; ++d) a[static_cast<std::size_t>(d)] += s * b[static_cast<std::size_t>(d)];
    return a;
  };
  for (int i = 0; i < n; ++i) {
    const auto k1 = linear_velocity(x, t), k2 = linear_velocity(add(x, k1, h / 2), t + h / 2);
    const auto k3 = linear_velocity(add(x, k2, h / 2), t + h / 2), k4 = linear_velocity(add(x, k3, h), t + h);
    for (std::size_t d = 0; d < 3; ++d) x[d] += h / 6 * (k1[d] + 2 * k2[d] + 2 * k3[d] + k4[d]);
    t += h;
  }
  if (dimension == 2) x[2] = 0;
  return x;
}

GridGeometry grid_of(int dimension, bool rectilinear) {
  GridGeometry g;
  g.dimension = dimension;
  g.size = {17, 17, dimension == 3 ? 17 : 1};
  g.origin = Vec3(-2, -2, dimension == 3 ? -2 : 0);
  g.spacing = Vec3(0.25, 0.25, 0.25);
  if (rectilinear) {
    // Uneven widths (1/8 to 1/2), still exact binary fractions.
    const std::vector<double> axis{-2,  -1.5, -1.25, -1,    -0.875, -0.75, -0.5, -0.25, 0,
                                   0.125, 0.25, 0.5, 0.75, 1, 1.25, 1.5, 2};
    for (int a = 0; a < dimension; ++a) g.axes[static_cast<std::size_t>(a)] = axis;
    if (dimension == 2) g.axes[2] = {0};
  }
  return g;
}

ResidentSteps linear_series(int dimension, bool rectilinear, int components,
                            double nan_beyond_x = std::numeric_limits<double>::infinity()) {
  const GridGeometry g = grid_of(dimension, rectilinear);
  std::vector<double> times{0, 0.25, 0.5, 0.75, 1};
  std::vector<std::vector<float>> steps;
  for (const double t : times) {
    std::vector<float> v(g.point_count() * static_cast<std::size_t>(components));
    for (std::int64_t k = 0; k < g.size[2]; ++k)
      for (std::int64_t j = 0; j < g.size[1]; ++j)
        for (std::int64_t i = 0; i < g.size[0]; ++i) {
          const std::array<double, 3> x{g.coordinate(0, i), g.coordinate(1, j),
                                        dimension == 3 ? g.coordinate(2, k) : 0.0};
          const auto u = linear_velocity(x, t);
          for (int c = 0; c < components; ++c) {
            const double value = x[0] >= nan_beyond_x ? std::nan("") : u[static_cast<std::size_t>(c)];
            v[g.index(i, j, k) * static_cast<std::size_t>(components) + static_cast<std::size_t>(c)] =
                static_cast<float>(value);
          }
        }
    steps.push_back(std::move(v));
  }
  return ResidentSteps(g, components, times, std::move(steps));
}

ParticleBatch batch_of(const std::vector<std::array<double, 3>>& points, double t0) {
  ParticleBatch b;
  b.resize(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    for (std::size_t d = 0; d < 3; ++d) b.x[d][i] = points[i][d];
    b.t[i] = t0;
  }
  return b;
}

std::vector<std::array<double, 3>> random_points(std::size_t n, double radius, int dimension,
                                                 unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-radius, radius);
  std::vector<std::array<double, 3>> out(n);
  for (auto& p : out) p = {u(rng), u(rng), dimension == 3 ? u(rng) : 0.0};
  return out;
}

}  // namespace

TEST_CASE("particle batch: growing keeps the particles and adds fresh ones, small or large",
          "[advect]") {
  for (const std::size_t grown : {std::size_t{5}, std::size_t{200'000}}) {
    for (const bool with_stop : {false, true}) {
      ParticleBatch b;
      if (with_stop) b.stop.assign(1, 0);
      b.resize(3);
      for (std::size_t i = 0; i < 3; ++i) {
        for (std::size_t d = 0; d < 3; ++d) b.x[d][i] = 10.0 * static_cast<double>(i) + static_cast<double>(d);
        b.t[i] = 0.5 + static_cast<double>(i);
        b.h[i] = 0.25;
        b.evaluations[i] = 7;
        b.status[i] = ParticleStatus::no_data;
        if (with_stop) b.stop[i] = 2.0;
      }
      b.resize(grown);
      INFO("grown to " << grown << (with_stop ? ", with ends" : ""));
      REQUIRE(b.size() == grown);
      for (const auto& c : b.x) REQUIRE(c.size() == grown);
      REQUIRE(b.h.size() == grown);
      REQUIRE(b.evaluations.size() == grown);
      REQUIRE(b.status.size() == grown);
      REQUIRE(b.stop.size() == (with_stop ? grown : 0));
      for (std::size_t i = 0; i < grown; ++i) {
        const bool old = i < 3;
        const ParticleState p = b.state(i);
        for (std::size_t d = 0; d < 3; ++d)
          if (p.x[d] != (old ? 10.0 * static_cast<double>(i) + static_cast<double>(d) : 0.0)) FAIL("x at " << i);
        if (p.t != (old ? 0.5 + static_cast<double>(i) : 0.0) || p.h != (old ? 0.25 : 0.0) ||
            p.evaluations != (old ? 7 : 0) ||
            p.status != (old ? ParticleStatus::no_data : ParticleStatus::moving) ||
            (with_stop && b.stop[i] != (old ? 2.0 : 0.0)))
          FAIL("particle " << i);
      }
      b.resize(2);
      CHECK(b.size() == 2);
      CHECK(b.x[2][1] == 12.0);
    }
  }
}

TEST_CASE("bulk advection: the exact flow of a linear field through four slabs",
          "[advect]") {
  const auto advector = make_cpu_advector();
  for (const int dimension : {2, 3})
    for (const bool rectilinear : {false, true})
      for (const Method method : {Method::rk4, Method::dopri5}) {
        const int components = dimension;
        INFO("dimension " << dimension << (rectilinear ? ", rectilinear" : ", uniform")
                          << (method == Method::rk4 ? ", RK4" : ", DOPRI5"));
        ResidentSteps series = linear_series(dimension, rectilinear, components);
        const auto points = random_points(200, 0.7, dimension, 7);
        // Each particle starts at its own time (as released particles do).
        ParticleBatch b = batch_of(points, 0);
        for (std::size_t i = 0; i < b.size(); ++i) b.t[i] = 0.3 * static_cast<double>(i % 4) / 3.0;
        MethodOptions o;
        o.method = method;
        o.rk4_step = 1e-3;
        o.absolute = o.relative = 1e-12;
        const AdvectionStatistics s = advector->advect(series, b, 1.0, o);
        CHECK(s.slabs == 4);
        CHECK(s.steps_loaded == 5);
        double worst = 0;
        for (std::size_t i = 0; i < b.size(); ++i) {
          REQUIRE(b.status[i] == ParticleStatus::moving);
          REQUIRE(b.t[i] == 1.0);
          const auto want = reference(points[i], 0.3 * static_cast<double>(i % 4) / 3.0, 1.0, dimension);
          for (std::size_t d = 0; d < 3; ++d) worst = std::max(worst, std::abs(b.x[d][i] - want[d]));
        }
        CHECK(worst < 1e-10);
        CHECK(s.particle_steps > 0);
        CHECK(s.evaluations >= 4 * s.particle_steps);
      }
}

TEST_CASE("bulk advection: leaving the grid, cells without data and times outside the series",
          "[advect]") {
  const auto advector = make_cpu_advector();
  ResidentSteps series = linear_series(3, false, 3, /*nan_beyond_x=*/1.0);
  MethodOptions o;
  // Samples at x >= 1 are NaN, so cells from x = 0.75 on have no data. From (0.6, -0.5) the
  // flow (-y + 0.5 t x, x - 0.5 t y) first moves +x: the particle stops on entering x = 0.75.
  ParticleBatch b = batch_of({{0.6, -0.5, 0}, {-1.0, 0, 0}, {0, 0, 0.1}, {2.5, 0, 0}, {0, 0, 0}}, 0);
  b.t[4] = 1.5;  // after the series
  for (const Method method : {Method::rk4, Method::dopri5}) {
    o.method = method;
    ParticleBatch c = b;
    advector->advect(series, c, 1.0, o);
    INFO((method == Method::rk4 ? "RK4" : "DOPRI5"));
    CHECK(c.status[0] == ParticleStatus::no_data);
    CHECK(c.x[0][0] < 0.75);
    CHECK(c.x[0][0] > 0.75 - 0.01);  // at the cell border (RK4: within one step of it)
    CHECK(c.t[0] > 0);
    CHECK(c.t[0] < 1.0);
    CHECK(c.status[1] == ParticleStatus::moving);  // an orbit of radius about 1, inside
    CHECK(c.status[2] == ParticleStatus::moving);
    CHECK(c.status[3] == ParticleStatus::left_domain);
    CHECK(c.x[0][3] == 2.5);  // never moved
    CHECK(c.t[3] == 0);
    CHECK(c.status[4] == ParticleStatus::time_bounds);
    ParticleBatch d = b;
    advector->advect(series, d, 1.25, o);  // t_end after the series: nobody moves
    for (std::size_t i = 0; i < d.size(); ++i) CHECK(d.status[i] == ParticleStatus::time_bounds);
  }
  // A uniform flow straight out of the box: the particle stops at the wall it reaches.
  GridGeometry g = grid_of(2, false);
  std::vector<float> step(g.point_count() * 2);
  for (std::size_t p = 0; p < g.point_count(); ++p) step[2 * p] = 1.0f;
  ResidentSteps out(g, 2, {0, 1}, {step, step});
  ParticleBatch e = batch_of({{1.5, 0, 0}}, 0);
  o.method = Method::dopri5;
  advector->advect(out, e, 1.0, o);
  CHECK(e.status[0] == ParticleStatus::left_domain);
  CHECK(e.x[0][0] <= 2.0);
  CHECK(e.x[0][0] > 2.0 - 1e-6);
  CHECK(e.t[0] == Approx(0.5).margin(1e-6));
}

TEST_CASE("bulk advection: a particle's result does not depend on the batch or on split calls",
          "[advect]") {
  const auto advector = make_cpu_advector();
  ResidentSteps series = linear_series(3, true, 3);
  const auto points = random_points(500, 1.0, 3, 11);
  for (const Method method : {Method::rk4, Method::dopri5}) {
    MethodOptions o;
    o.method = method;
    o.rk4_step = 0.01;
    o.absolute = o.relative = 1e-8;
    ParticleBatch all = batch_of(points, 0);
    advector->advect(series, all, 1.0, o);
    for (std::size_t i = 0; i < points.size(); i += 37) {
      ParticleBatch one = batch_of({points[i]}, 0);
      advector->advect(series, one, 1.0, o);
      for (std::size_t d = 0; d < 3; ++d) REQUIRE(one.x[d][0] == all.x[d][i]);
      REQUIRE(one.status[0] == all.status[i]);
    }
    // Two calls that meet at a step time give the bits of one call (DOPRI5 carries its step).
    ParticleBatch split = batch_of(points, 0);
    advector->advect(series, split, 0.5, o);
    advector->advect(series, split, 1.0, o);
    for (std::size_t i = 0; i < points.size(); ++i)
      for (std::size_t d = 0; d < 3; ++d) REQUIRE(split.x[d][i] == all.x[d][i]);
  }
}

TEST_CASE("bulk advection: backward in time returns to the start", "[advect]") {
  const auto advector = make_cpu_advector();
  ResidentSteps series = linear_series(2, false, 2);
  const auto points = random_points(100, 0.8, 2, 5);
  ParticleBatch b = batch_of(points, 0.1);
  MethodOptions o;
  o.absolute = o.relative = 1e-12;
  advector->advect(series, b, 0.9, o);
  for (std::size_t i = 0; i < b.size(); ++i) b.h[i] = 0;
  const AdvectionStatistics s = advector->advect(series, b, 0.1, o);
  CHECK(s.slabs == 4);
  for (std::size_t i = 0; i < b.size(); ++i) {
    REQUIRE(b.status[i] == ParticleStatus::moving);
    CHECK(b.t[i] == 0.1);
    CHECK(std::abs(b.x[0][i] - points[i][0]) < 1e-9);
    CHECK(std::abs(b.x[1][i] - points[i][1]) < 1e-9);
  }
}

TEST_CASE("bulk advection: devices by name, and cuda refused with the reason where absent",
          "[advect]") {
  CHECK(parse_device("cpu") == Device::cpu);
  CHECK(parse_device("auto") == Device::auto_select);
  CHECK_THROWS_WITH(parse_device("gpu"), Catch::Contains("'gpu'"));
  CHECK(make_advector(Device::cpu)->name() == "cpu");
  // Options that cannot integrate are refused before any particle moves.
  ResidentSteps series = linear_series(2, false, 2);
  ParticleBatch b = batch_of({{0.1, 0.2, 0}}, 0);
  MethodOptions o;
  o.method = Method::rk4;
  o.rk4_step = 0;
  CHECK_THROWS_WITH(make_cpu_advector()->advect(series, b, 1.0, o), Catch::Contains("RK4 step 0"));
  o.method = Method::dopri5;
  o.relative = std::nan("");
  CHECK_THROWS_WITH(make_cpu_advector()->advect(series, b, 1.0, o), Catch::Contains("tolerances"));
  CHECK(b.x[0][0] == 0.1);
  std::string why;
  if (!cuda_available(&why)) {
    CHECK_FALSE(why.empty());
    CHECK_THROWS_WITH(make_advector(Device::cuda), Catch::Contains(why));
    CHECK(make_advector(Device::auto_select)->name() == "cpu");
  }
}

TEST_CASE("bulk advection: each particle stops at its own end time", "[advect]") {
  const auto advector = make_cpu_advector();
  ResidentSteps series = linear_series(3, false, 3);
  const auto points = random_points(120, 0.7, 3, 11);
  MethodOptions o;
  o.method = Method::dopri5;
  o.absolute = o.relative = 1e-12;
  ParticleBatch b = batch_of(points, 0);
  b.stop.resize(b.size());
  for (std::size_t i = 0; i < b.size(); ++i) {
    b.t[i] = 0.1 * static_cast<double>(i % 3);               // 0, 0.1, 0.2
    b.stop[i] = b.t[i] + 0.05 + 0.7 * static_cast<double>(i % 5) / 4.0;  // 0.05 … 0.95 later
  }
  const double horizon = *std::max_element(b.stop.begin(), b.stop.end());
  const std::vector<double> starts = b.t, ends = b.stop;
  const AdvectionStatistics s = advector->advect(series, b, horizon, o);
  CHECK(s.slabs == 4);
  for (std::size_t i = 0; i < b.size(); ++i) {
    INFO("particle " << i);
    REQUIRE(b.status[i] == ParticleStatus::moving);
    REQUIRE(b.t[i] == ends[i]);
    const auto want = reference(points[i], starts[i], ends[i], 3);
    for (std::size_t d = 0; d < 3; ++d) CHECK(std::abs(b.x[d][i] - want[d]) < 1e-10);
    // The same particle alone, with the common end time, lands on the same bits.
    ParticleBatch one = batch_of({points[i]}, starts[i]);
    advector->advect(series, one, ends[i], o);
    for (std::size_t d = 0; d < 3; ++d) CHECK(one.x[d][0] == b.x[d][i]);
  }

  // An own end beyond the call's end, before the particle's time, or NaN: time_bounds, unmoved.
  ParticleBatch bad = batch_of({points[0], points[1], points[2]}, 0.25);
  bad.stop = {0.9, 0.2, std::nan("")};
  advector->advect(series, bad, 0.75, o);
  for (std::size_t i = 0; i < 3; ++i) {
    CHECK(bad.status[i] == ParticleStatus::time_bounds);
    CHECK(bad.t[i] == 0.25);
    CHECK(bad.x[0][i] == points[i][0]);
  }
  ParticleBatch short_stop = batch_of({points[0], points[1]}, 0.25);
  short_stop.stop = {0.5};
  CHECK_THROWS_AS(advector->advect(series, short_stop, 0.75, o), InvalidArgument);
}

TEST_CASE("bulk advection: the bulk step's cell faces are the grid's", "[advect][kinks]") {
  std::mt19937_64 rng(41);
  std::uniform_real_distribution<double> u(-1, 1);
  GridGeometry decimal;  // (x - origin) / spacing on a face rounds to either side of its index
  decimal.size = {61, 23, 37};
  decimal.origin = Vec3(0.03, -1.1, 0.7);
  decimal.spacing = Vec3(0.1, 0.3, 0.07);
  std::vector<GridGeometry> grids{decimal};
  for (int dimension : {2, 3})
    for (bool rectilinear : {false, true}) grids.push_back(grid_of(dimension, rectilinear));
  for (const GridGeometry& g : grids) {
    INFO(g.dimension << "D, " << (g.rectilinear() ? "rectilinear" : "uniform"));
    const GridTables tables(g, g.dimension, false);
    const GridView& view = tables.view();
    const Box<3> box = g.bounds();
    for (int i = 0; i < 3000; ++i) {
      Vec3 x = 0.5 * (box.lo + box.hi) +
               0.6 * (box.hi - box.lo).cwiseProduct(Vec3(u(rng), u(rng), u(rng)));
      if (i % 2 == 0)  // on a face of every axis
        for (int a = 0; a < g.dimension; ++a) {
          const std::int64_t n = g.size[static_cast<std::size_t>(a)];
          x[a] = g.coordinate(a, 1 + static_cast<std::int64_t>((u(rng) + 1) * 0.5 *
                                                               static_cast<double>(n - 3)));
        }
      const Vec3 w(u(rng), i % 5 == 0 ? 0.0 : u(rng), u(rng));
      const double after = i % 3 == 0 ? 0.0 : 0.2 * (u(rng) + 1);
      const double want = test::first_face_brute_force(g, x, w, after);
      const double got =
          g.dimension == 3
              ? (g.rectilinear() ? detail::next_face<3, true>(view, x.data(), w.data(), after)
                                 : detail::next_face<3, false>(view, x.data(), w.data(), after))
              : (g.rectilinear() ? detail::next_face<2, true>(view, x.data(), w.data(), after)
                                 : detail::next_face<2, false>(view, x.data(), w.data(), after));
      if (std::isinf(want))
        REQUIRE(got == -1);
      else
        REQUIRE(got == Approx(want).epsilon(1e-12).margin(1e-15));
    }
  }
}

TEST_CASE("bulk advection: a resident set moves its particles as advect() moves them, bit for bit",
          "[advect]") {
  // Cells without data beyond x = 1, particles leaving the box, slots parked and reused.
  ResidentSteps series = linear_series(3, true, 3, /*nan_beyond_x=*/1.0);
  const auto cpu = make_cpu_advector();
  const auto set = cpu->make_resident();
  MethodOptions o;
  o.method = Method::dopri5;
  o.absolute = o.relative = 1e-9;
  // (Bulk placements of more than kParallelPlacements slots, made in parallel.)
  const auto records = test_support::run_resident_scenario(*set, series, o, {-1.4, -1.4, -1.4}, {1.4, 1.4, 1.4}, 3,
                                                           500, 0.1, 0.9, 6, cpu.get(), kParallelPlacements + 500);
  // Some particles stopped each way, so both kinds of stop were compared.
  std::size_t left = 0, no_data = 0;
  for (const ParticleStatus s : records.back().status) {
    left += s == ParticleStatus::left_domain;
    no_data += s == ParticleStatus::no_data;
  }
  CHECK(left > 0);
  CHECK(no_data > 0);
  // Times outside the series are refused by name.
  CHECK_THROWS_WITH(set->advance(series, 0.5, 1.5, o), Catch::Contains("leave the series"));
  // A set whose particles have all stopped reads no step.
  const auto stopped = cpu->make_resident();
  const std::uint32_t slot = 3;
  const std::array<double, 3> outside{5, 0, 0};
  stopped->place(std::span<const std::uint32_t>(&slot, 1), std::span<const std::array<double, 3>>(&outside, 1));
  const AdvectionStatistics first = stopped->advance(series, 0.1, 0.2, o);
  CHECK(first.particles == 1);
  CHECK(stopped->view().status[slot] != ParticleStatus::moving);
  const AdvectionStatistics second = stopped->advance(series, 0.2, 0.3, o);
  CHECK(second.particles == 0);
  CHECK(second.steps_loaded == 0);
  CHECK(second.slabs == 0);
}

TEST_CASE("bulk advection: a corner's NaN or infinity is no data, even where its weight is 0",
          "[advect]") {
  // One cell of 8 corners (x fastest), 3 components each. The value is checked instead of the
  // corners: every bad component must still reach it, at every weight.
  const std::int64_t stride[3] = {3, 6, 12};
  const float kBad[] = {std::numeric_limits<float>::quiet_NaN(),
                        std::numeric_limits<float>::infinity(),
                        -std::numeric_limits<float>::infinity()};
  const double kWeights[] = {0.0, 0.25, 1.0};
  std::array<float, 24> cell{};
  for (std::size_t i = 0; i < cell.size(); ++i) cell[i] = 0.5f + static_cast<float>(i);
  double v[3];
  for (const double tx : kWeights)
    for (const double ty : kWeights)
      for (const double tz : kWeights) {
        REQUIRE(detail::interpolate_step<3, 3>(cell.data(), stride, tx, ty, tz, false, v));
        for (std::size_t k = 0; k < 24; ++k)
          for (const float bad : kBad) {
            std::array<float, 24> broken = cell;
            broken[k] = bad;
            INFO("corner " << k / 3 << ", component " << k % 3 << ", value " << bad << ", weights "
                           << tx << " " << ty << " " << tz);
            CHECK_FALSE(detail::interpolate_step<3, 3>(broken.data(), stride, tx, ty, tz, false, v));
            // The 2D cell is the first four corners.
            CHECK(detail::interpolate_step<2, 3>(broken.data(), stride, tx, ty, 0, false, v) ==
                  (k >= 12));
          }
      }
  // An all-zero corner is no data only where zero means so.
  std::array<float, 24> zero = cell;
  zero[9] = zero[10] = zero[11] = 0;
  CHECK(detail::interpolate_step<3, 3>(zero.data(), stride, 0.5, 0.5, 0.5, false, v));
  CHECK_FALSE(detail::interpolate_step<3, 3>(zero.data(), stride, 0.5, 0.5, 0.5, true, v));
}

TEST_CASE("bulk advection: the step controller's norm^(-1/5) is pow's to a few ulps", "[advect]") {
  std::vector<double> norms;
  for (double e = -5; e <= 5; e += 1.0 / 64) norms.push_back(std::pow(10.0, e));
  for (int j = -3; j <= 2; ++j)  // the ends of the range scaled into [1, 32)
    for (const double x : {1.0, 1.0 + 1e-12, 32.0 - 1e-12, 32.0}) norms.push_back(x * std::pow(32.0, j));
  for (const double norm : norms) {
    INFO("norm " << norm);
    CHECK(detail::inverse_fifth_root(norm) == Approx(std::pow(norm, -0.2)).epsilon(1e-15));
  }
  CHECK(detail::inverse_fifth_root(1e-9) == detail::inverse_fifth_root(1e-5));  // clamped
  CHECK(detail::inverse_fifth_root(1e9) == detail::inverse_fifth_root(1e5));
}
