// The remeshed streak surface (StreakMesh::remeshed): vertices exactly on their path lines,
// a valid triangle mesh, sizes that follow the surface's area, and removal where dye leaves.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "orthofront/field/unsteady.h"
#include "orthofront/spacetime/brick_cache.h"
#include "orthofront/spacetime/sampled_series.h"
#include "orthofront/quality/quality.h"
#include "orthofront/spacetime/streak_surface.h"
#include "spacetime/reference_path.h"

using namespace orthofront;
using namespace orthofront::spacetime;
using streak_test::reference_path;

namespace {

// Steady simple shear v = (y, 0) on [x_lo, x_hi] x [0, 1]: path lines are straight, so the dyed
// region of a seed across the flow is a polygon whose area grows exactly by the flux.
class ShearFlow final : public UnsteadyField {
 public:
  explicit ShearFlow(double x_hi = 1e9) : x_hi_(x_hi) {}
  int dimension() const override { return 2; }
  FieldStatus velocity(const Vec3& x, double, Vec3& v) const override {
    if (!(x.x() >= -1 && x.x() <= x_hi_ && x.y() >= 0 && x.y() <= 1)) return FieldStatus::outside;
    v = Vec3(x.y(), 0, 0);
    return FieldStatus::inside;
  }
  FieldStatus velocity_jacobian(const Vec3& x, double t, Vec3& v, Mat3& J,
                                Vec3& dvdt) const override {
    J.setZero();
    J(0, 1) = 1;
    dvdt.setZero();
    return velocity(x, t, v);
  }
  Box<3> domain() const override {
    Box<3> b;
    b.lo = Vec3(-1, 0, -1);
    b.hi = Vec3(x_hi_, 1, 1);
    return b;
  }
  TimeRange time_range() const override { return {}; }
  std::string describe() const override { return "shear"; }

 private:
  double x_hi_;
};

// Steady strain v = (x, -y) on [0, 3] x [-1, 1]. Dye released across the flow at x = 0.25,
// |y| <= 0.2, reaches x = 0.25 e^a at age a with |y| <= 0.05 / x: a filament of width 0.1 / x,
// flux 0.1 per time unit through the seed and every later cross-section.
class StrainFlow final : public UnsteadyField {
 public:
  int dimension() const override { return 2; }
  FieldStatus velocity(const Vec3& x, double, Vec3& v) const override {
    if (!(x.x() >= 0 && x.x() <= 3 && x.y() >= -1 && x.y() <= 1)) return FieldStatus::outside;
    v = Vec3(x.x(), -x.y(), 0);
    return FieldStatus::inside;
  }
  FieldStatus velocity_jacobian(const Vec3& x, double t, Vec3& v, Mat3& J,
                                Vec3& dvdt) const override {
    J.setZero();
    J(0, 0) = 1;
    J(1, 1) = -1;
    dvdt.setZero();
    return velocity(x, t, v);
  }
  Box<3> domain() const override {
    Box<3> b;
    b.lo = Vec3(0, -1, -1);
    b.hi = Vec3(3, 1, 1);
    return b;
  }
  TimeRange time_range() const override { return {}; }
  std::string describe() const override { return "strain"; }
};

std::vector<StreakFrame> collect(const UnsteadyField& flow, const SeedCurve& seed,
                                 const StreakOptions& o, StreakReport& report) {
  std::vector<StreakFrame> frames;
  report = build_streak_surface(flow, seed, o, [&](const StreakFrame& f) { frames.push_back(f); });
  return frames;
}

void require_valid(const StreakFrame& f) {
  INFO("frame " << f.index << " at t = " << f.time);
  CHECK(f.quality.non_manifold_edges == 0);
  CHECK(f.quality.inconsistent_edges == 0);
  CHECK(f.quality.t_junctions == 0);
  CHECK(f.quality.degenerate_faces == 0);
  CHECK(f.quality.folds == 0);
  CHECK(f.quality.quads == 0);
  const Mesh& m = f.mesh;
  REQUIRE(m.release_time.size() == m.vertex_count());
  REQUIRE(m.age.size() == m.vertex_count());
  REQUIRE(m.speed.size() == m.vertex_count());
  REQUIRE(m.particle_id.size() == m.vertex_count());
  for (std::size_t i = 0; i < m.vertex_count(); ++i) {
    CHECK(m.age[i] == Approx(f.time - m.release_time[i]).margin(1e-12));
    CHECK(m.age[i] >= 0);
  }
}

// The double gyre case of the first tests: a short seed across the left gyre, three frames.
SeedCurve double_gyre_seed() { return SeedCurve::line(Vec3(0.3, 0.3, 0), Vec3(0.3, 0.45, 0)); }

StreakOptions double_gyre_options() {
  StreakOptions o;
  o.mesh = StreakMesh::remeshed;
  o.release_begin = 0;
  o.release_end = 4;
  o.frames = {1, 3, 6};
  o.edge = 0.02;
  return o;
}

}  // namespace

TEST_CASE("remeshed streak frames of the double gyre: every vertex on its own path line",
          "[spacetime][streak][remeshed]") {
  const auto flow = make_unsteady_field("double-gyre");
  const SeedCurve seed = double_gyre_seed();
  StreakOptions o = double_gyre_options();
  StreakReport r;
  const std::vector<StreakFrame> frames = collect(*flow, seed, o, r);
  REQUIRE(r.complete);
  CHECK(r.mesh == "remeshed");
  REQUIRE(frames.size() == 3);
  CHECK(r.splits > 0);
  CHECK(r.collapses > 0);
  CHECK(r.flips > 0);
  CHECK(r.exact_insertions == r.splits);
  for (const StreakFrame& f : frames) {
    require_valid(f);
    INFO("t = " << f.time);
    // Every edge within split·ℓ once the frame is adapted (the first frame included).
    CHECK(r.frames[static_cast<std::size_t>(f.index)].max_edge <= o.split * o.edge * (1 + 1e-9));
    double worst = 0;
    for (std::size_t i = 0; i < f.mesh.vertex_count(); i += 7) {
      const Vec3 start = seed.point(f.mesh.s[i]);
      const Vec3 x = reference_path(*flow, Vec3(start.x(), start.y(), 0), f.mesh.release_time[i],
                                    f.time);
      worst = std::max(worst, (x - f.mesh.positions[i]).norm());
    }
    // The domain is 2 x 1: 1e-6 relative.
    CHECK(worst < 2e-6);
  }
}

TEST_CASE("a remeshed streak surface in steady shear: exact area, bounded size, good shapes",
          "[spacetime][streak][remeshed]") {
  const ShearFlow flow;
  // Across the flow from y = 0.2 to 0.8: flux 0.3 per time unit; the rows route's mesh grows
  // with the shear, the area does not.
  const SeedCurve seed = SeedCurve::line(Vec3(0, 0.2, 0), Vec3(0, 0.8, 0));
  StreakOptions o;
  o.mesh = StreakMesh::remeshed;
  o.release_begin = 0;
  o.release_end = 4;
  o.frames = {1, 2, 4, 8};
  o.edge = 0.05;
  o.prune = 0;  // the acute corners thin below any width: kept, so the area stays exact
  StreakReport r;
  const std::vector<StreakFrame> frames = collect(flow, seed, o, r);
  REQUIRE(r.complete);
  REQUIRE(frames.size() == 4);
  CHECK(r.faces_pruned == 0);
  for (const StreakFrame& f : frames) {
    require_valid(f);
    const StreakFrameRecord& rec = r.frames[static_cast<std::size_t>(f.index)];
    INFO("t = " << f.time << ": " << rec.vertices << " vertices, estimate " << rec.vertex_estimate
                << ", p05 min angle " << rec.quality.triangle_min_angle_p05 << ", strip faces skipped "
                << r.strip_faces_skipped << ", faces removed " << r.faces_removed_at_stops);
    const double released = std::min(f.time, o.release_end) - o.release_begin;
    // Straight path lines, straight boundary: the triangles cover the polygon exactly.
    CHECK(rec.area == Approx(0.3 * released).epsilon(1e-9));
    CHECK(rec.pieces == 1);
    CHECK(static_cast<double>(rec.vertices) <= 3 * rec.vertex_estimate);
    CHECK(rec.max_edge <= o.split * o.edge * (1 + 1e-9));
    CHECK(rec.quality.triangle_min_angle_p05 >= 20);
  }
  // After the release ends the dye is only sheared: the vertex count stays about the same.
  CHECK(static_cast<double>(frames[3].mesh.vertex_count()) <=
        1.5 * static_cast<double>(frames[2].mesh.vertex_count()));
}

TEST_CASE("remeshed streaks prune exactly the part of a filament thinner than the prune width",
          "[spacetime][streak][remeshed]") {
  const StrainFlow flow;
  const SeedCurve seed = SeedCurve::line(Vec3(0.25, -0.2, 0), Vec3(0.25, 0.2, 0));
  StreakOptions o;
  o.mesh = StreakMesh::remeshed;
  o.release_begin = 0;
  o.release_end = 4;
  o.frames = {1.5, 4};
  o.edge = 0.1;
  o.prune = 0.5;  // w = 0.05: the filament (width 0.1 / x) is thinner beyond x = 2
  StreakReport r;
  const std::vector<StreakFrame> frames = collect(flow, seed, o, r);
  REQUIRE(r.complete);
  REQUIRE(frames.size() == 2);
  const auto reach = [](const StreakFrame& f) {
    double x = 0;
    for (const Vec3& p : f.mesh.positions) x = std::max(x, p.x());
    return x;
  };
  // t = 1.5: the tip (x = 0.25 e^1.5 = 1.12) is wider than w everywhere: nothing pruned.
  const StreakFrameRecord& early = r.frames[0];
  CHECK(early.area_pruned == 0);
  CHECK(early.pieces == 1);
  CHECK(reach(frames[0]) == Approx(0.25 * std::exp(1.5)).epsilon(1e-6));
  // t = 4: the dye is eaten back to x = 2 (one edge either way), in one piece; what it lost is
  // the flux past x = 2 since the tip got there (t = ln 8), less nothing else.
  const StreakFrameRecord& late = r.frames[1];
  require_valid(frames[1]);
  INFO("reach " << reach(frames[1]) << ", area " << late.area << ", pruned " << late.area_pruned
                << ", faces pruned " << r.faces_pruned << ", stopped " << late.dead_particles);
  CHECK(std::abs(reach(frames[1]) - 2.0) <= o.edge);
  CHECK(late.pieces == 1);
  CHECK(late.dead_particles == 0);  // pruned before it reached the outflow at x = 3
  CHECK(late.area == Approx(0.1 * std::log(2.0 / 0.25)).epsilon(0.05));
  CHECK(late.area_pruned == Approx(0.1 * (4 - std::log(8.0))).epsilon(0.05));
  CHECK(late.area + late.area_pruned == Approx(0.1 * 4).epsilon(0.01));
}

TEST_CASE("remeshed streaks: dye that leaves the domain takes its faces with it",
          "[spacetime][streak][remeshed]") {
  const ShearFlow flow(1.0);  // outflow at x = 1
  const SeedCurve seed = SeedCurve::line(Vec3(0, 0.2, 0), Vec3(0, 0.8, 0));
  StreakOptions o;
  o.mesh = StreakMesh::remeshed;
  o.release_begin = 0;
  o.release_end = 6;
  o.frames = {6};
  o.edge = 0.05;
  StreakReport r;
  const std::vector<StreakFrame> frames = collect(flow, seed, o, r);
  REQUIRE(r.complete);
  REQUIRE(frames.size() == 1);
  require_valid(frames[0]);
  CHECK(r.left_domain > 0);
  CHECK(r.faces_removed_at_stops > 0);
  for (const Vec3& p : frames[0].mesh.positions) CHECK(p.x() <= 1.0);
  // What is left lies between the seed and the outflow: area at most the strip's 0.6.
  CHECK(r.frames[0].area <= 0.6 + 1e-9);
  CHECK(r.frames[0].area > 0.4);
}

TEST_CASE("remeshed streaks refuse a collapse factor that would make edges split",
          "[spacetime][streak][remeshed]") {
  const ShearFlow flow;
  const SeedCurve seed = SeedCurve::line(Vec3(0, 0.2, 0), Vec3(0, 0.8, 0));
  StreakOptions o;
  o.mesh = StreakMesh::remeshed;
  o.release_end = 1;
  o.frames = {1};
  o.collapse = 0.9;  // > split / 2
  StreakReport r;
  CHECK_THROWS_WITH(collect(flow, seed, o, r), Catch::Contains("collapse factor"));
}


TEST_CASE("remeshed streaks: streamed under a small budget give the frames of a resident series, "
          "bit for bit",
          "[spacetime][streak][remeshed]") {
  const auto flow = make_unsteady_field("double-gyre");
  const GridGeometry grid = uniform_grid(flow->domain(), 2, 81);
  const SampledTimeSeries series(*flow, grid, uniform_times(0, 5, 50));
  const SeedCurve seed = SeedCurve::line(Vec3(0.3, 0.3, 0), Vec3(0.3, 0.45, 0));
  StreakOptions o;
  o.mesh = StreakMesh::remeshed;
  o.release_end = 3;
  o.frames = {1.5, 3, 4.5};
  o.edge = 0.03;
  std::vector<std::vector<StreakFrame>> runs;
  // All of the series resident, then little more than the band.
  for (const std::size_t budget : {std::size_t{1} << 30, std::size_t{1400} << 10}) {
    CacheOptions co;
    co.budget_bytes = budget;
    co.whole_steps = true;
    BrickCache cache(series, co);
    std::vector<StreakFrame> frames;
    const StreakReport r =
        build_streak_surface(cache, seed, o, [&](const StreakFrame& f) { frames.push_back(f); });
    REQUIRE(r.complete);
    REQUIRE(r.streamed);
    CHECK(r.cache.peak_bytes <= budget);
    runs.push_back(std::move(frames));
  }
  REQUIRE(runs[0].size() == 3);
  REQUIRE(runs[1].size() == 3);
  for (std::size_t f = 0; f < 3; ++f) {
    const Mesh& a = runs[0][f].mesh;
    const Mesh& b = runs[1][f].mesh;
    require_valid(runs[1][f]);
    REQUIRE(a.vertex_count() == b.vertex_count());
    CHECK(a.faces == b.faces);
    CHECK(std::memcmp(a.positions.data(), b.positions.data(), a.vertex_count() * sizeof(Vec3)) == 0);
    CHECK(a.particle_id == b.particle_id);
  }
}

TEST_CASE("remeshed streaks smooth only particles placed by interpolation", "[spacetime][streak][remeshed]") {
  const auto flow = make_unsteady_field("double-gyre");
  const SeedCurve seed = double_gyre_seed();
  StreakOptions o = double_gyre_options();
  const auto run = [&](bool smooth, StreakReport& r) {
    StreakOptions with = o;
    with.smooth = smooth;
    return collect(*flow, seed, with, r);
  };
  SECTION("every particle exact: nothing moves, the frames are the same bit for bit") {
    StreakReport on, off;
    const auto a = run(true, on), b = run(false, off);
    REQUIRE(on.exact_insertions == on.splits);
    CHECK(on.smoothed == 0);
    REQUIRE(a.size() == b.size());
    for (std::size_t i = 0; i < a.size(); ++i) {
      REQUIRE(a[i].mesh.vertex_count() == b[i].mesh.vertex_count());
      CHECK(std::memcmp(a[i].mesh.positions.data(), b[i].mesh.positions.data(),
                        sizeof(Vec3) * a[i].mesh.vertex_count()) == 0);
    }
  }
  SECTION("interpolated insertion: smoothing widens the small angles and keeps the mesh valid") {
    o.insertion = ParticleInsertion::interpolate;
    StreakReport on, off;
    const auto a = run(true, on);
    const auto b = run(false, off);
    REQUIRE(on.complete);
    REQUIRE(off.complete);
    CHECK(on.smoothed > 0);
    CHECK(off.smoothed == 0);
    for (std::size_t i = 0; i < a.size(); ++i) {
      require_valid(a[i]);
      const StreakFrameRecord& with = on.frames[i];
      const StreakFrameRecord& without = off.frames[i];
      INFO("t = " << with.time << ": p05 " << with.quality.triangle_min_angle_p05 << " with, "
                  << without.quality.triangle_min_angle_p05 << " without; area " << with.area
                  << " / " << without.area);
      CHECK(with.max_edge <= o.split * o.edge * (1 + 1e-9));
      // Young particles are all released exactly: the first frame has none to move.
      CHECK(with.quality.triangle_min_angle_p05 >= without.quality.triangle_min_angle_p05);
      if (i > 0) CHECK(with.quality.triangle_min_angle_p05 > without.quality.triangle_min_angle_p05);
      // Moving inner particles along the plane keeps the dyed region.
      CHECK(with.area + with.area_pruned == Approx(without.area + without.area_pruned).epsilon(0.03));
    }
  }
}
