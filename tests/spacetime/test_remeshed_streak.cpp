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
// With an offset y0 the flow is y - y0: it runs backward below y0. `dimension` 3: the same flow
// in space (a seed at constant z makes a flat sheet there).
class ShearFlow final : public UnsteadyField {
 public:
  explicit ShearFlow(double x_hi = 1e9, double y0 = 0, int dimension = 2)
      : x_hi_(x_hi), y0_(y0), dimension_(dimension) {}
  int dimension() const override { return dimension_; }
  FieldStatus velocity(const Vec3& x, double, Vec3& v) const override {
    if (!(x.x() >= -1 && x.x() <= x_hi_ && x.y() >= 0 && x.y() <= 1)) return FieldStatus::outside;
    v = Vec3(x.y() - y0_, 0, 0);
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
  double x_hi_, y0_;
  int dimension_;
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

// Steady rotation about the z axis at an angular speed 1 + z, and a stretch along it, w = z / 2,
// on |x|, |y| <= 1, 0 <= z <= 2: particles keep their radius, so dye released from a segment at
// radius R along z lies on the cylinder of radius R, stretched along z and twisted about it.
class TwistFlow final : public UnsteadyField {
 public:
  int dimension() const override { return 3; }
  FieldStatus velocity(const Vec3& x, double, Vec3& v) const override {
    if (!(std::abs(x.x()) <= 1 && std::abs(x.y()) <= 1 && x.z() >= 0 && x.z() <= 2))
      return FieldStatus::outside;
    const double w = 1 + x.z();
    v = Vec3(-w * x.y(), w * x.x(), 0.5 * x.z());
    return FieldStatus::inside;
  }
  FieldStatus velocity_jacobian(const Vec3& x, double t, Vec3& v, Mat3& J,
                                Vec3& dvdt) const override {
    const double w = 1 + x.z();
    J << 0, -w, -x.y(), w, 0, x.x(), 0, 0, 0.5;
    dvdt.setZero();
    return velocity(x, t, v);
  }
  Box<3> domain() const override {
    Box<3> b;
    b.lo = Vec3(-1, -1, 0);
    b.hi = Vec3(1, 1, 2);
    return b;
  }
  TimeRange time_range() const override { return {}; }
  std::string describe() const override { return "twist"; }
};

// Steady irrotational vortex v = (-y, x) / r² on 0.5 <= r <= 3: particles keep their radius and
// turn by age / r², so dye released from the radial segment r in [1, 2] at angle 0 has its
// particle of label (s, τ) at radius 1 + s and angle (t - τ) / (1 + s)²: the oldest row winds
// into a spiral (a time line that stretches and bends), its sides are circles (streak lines).
class VortexFlow final : public UnsteadyField {
 public:
  int dimension() const override { return 2; }
  FieldStatus velocity(const Vec3& x, double, Vec3& v) const override {
    const double r2 = x.x() * x.x() + x.y() * x.y();
    if (!(r2 >= 0.25 && r2 <= 9)) return FieldStatus::outside;
    v = Vec3(-x.y() / r2, x.x() / r2, 0);
    return FieldStatus::inside;
  }
  FieldStatus velocity_jacobian(const Vec3& x, double t, Vec3& v, Mat3& J,
                                Vec3& dvdt) const override {
    const double r2 = x.x() * x.x() + x.y() * x.y(), r4 = r2 * r2;
    J.setZero();
    J(0, 0) = 2 * x.x() * x.y() / r4;
    J(0, 1) = (x.y() * x.y() - x.x() * x.x()) / r4;
    J(1, 0) = (x.y() * x.y() - x.x() * x.x()) / r4;
    J(1, 1) = -2 * x.x() * x.y() / r4;
    dvdt.setZero();
    return velocity(x, t, v);
  }
  Box<3> domain() const override {
    Box<3> b;
    b.lo = Vec3(-3, -3, -1);
    b.hi = Vec3(3, 3, 1);
    return b;
  }
  TimeRange time_range() const override { return {}; }
  std::string describe() const override { return "vortex"; }
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
  o.flat_split = 0;  // every particle on its path: exact insertion is what these tests check
  return o;
}

// Remeshed, released from 0 to release_end and observed at `frames`, with every part of the
// dye kept (no pruning, no vertex budget), for tests that measure exact areas or positions.
StreakOptions whole_dye_options(double release_end, std::vector<double> frames, double edge) {
  StreakOptions o;
  o.mesh = StreakMesh::remeshed;
  o.release_begin = 0;
  o.release_end = release_end;
  o.frames = std::move(frames);
  o.edge = edge;
  o.prune = 0;
  o.vertex_budget = 0;
  return o;
}

// Steady shear, across the flow from y = 0.2 to 0.8: flux 0.3 per time unit. Dye released for
// 8 time units, observed every 2 (the acute corners thin below any width: kept, so the area
// stays exact).
StreakOptions shear_growth_options() { return whole_dye_options(8, {2, 4, 6, 8}, 0.05); }

SeedCurve shear_seed() { return SeedCurve::line(Vec3(0, 0.2, 0), Vec3(0, 0.8, 0)); }

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
    // Every particle placed exactly, and said so.
    REQUIRE(f.mesh.on_path.size() == f.mesh.vertex_count());
    CHECK(std::count(f.mesh.on_path.begin(), f.mesh.on_path.end(), 0) == 0);
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
  // The rows route's mesh grows with the shear, the area does not.
  const SeedCurve seed = shear_seed();
  StreakOptions o = shear_growth_options();
  o.release_end = 4;
  o.frames = {1, 2, 4, 8};
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
  // A 2D dye is a region of the plane: its splits go to their edges' midpoints, with no
  // integration, and the area above stays exact.
  INFO("splits " << r.splits << ", flat " << r.flat_insertions << ", exact " << r.exact_insertions);
  CHECK(r.flat_insertions > r.splits / 2);
}

TEST_CASE("a remeshed streak surface where the flow crosses the seed both ways: two sheets, no "
          "fold (2D and 3D)",
          "[spacetime][streak][remeshed]") {
  // v = (y - 0.5, 0): below y = 0.5 the dye goes upstream. Through the seed, y in [0.2, 0.75],
  // the flux is 0.3² / 2 + 0.25² / 2 = 0.07625 per time unit, either way.
  const int dimension = GENERATE(2, 3);
  INFO(dimension << "D");
  const ShearFlow flow(1e9, 0.5, dimension);
  const SeedCurve seed = SeedCurve::line(Vec3(0, 0.2, 0.25), Vec3(0, 0.75, 0.25));
  const StreakOptions o = whole_dye_options(2, {1, 2}, 0.02);
  StreakReport r;
  const std::vector<StreakFrame> frames = collect(flow, seed, o, r);
  REQUIRE(r.complete);
  REQUIRE(frames.size() == 2);
  for (const StreakFrame& f : frames) {
    require_valid(f);  // no fold, every edge consistent
    const StreakFrameRecord& rec = r.frames[static_cast<std::size_t>(f.index)];
    INFO("t = " << f.time << ": area " << rec.area << ", pieces " << rec.pieces);
    CHECK(rec.pieces == 2);
    // Less only the strip of quads that the flow turns within (where it runs along the seed).
    CHECK(rec.area == Approx(0.07625 * f.time).epsilon(0.02));
    CHECK(rec.area <= 0.07625 * f.time * (1 + 1e-9));
  }
}

TEST_CASE("remeshed streaks split flat edges at their midpoints and integrate across a bend",
          "[spacetime][streak][remeshed]") {
  // The dye lies on the cylinder of radius R, where a chord around it falls inside by L² / 8R:
  // with ℓ = 0.05 and R = 0.3, 0.03 ℓ for the longest edges (1.5 ℓ), above the 0.01 ℓ
  // tolerance. The surface bends at every edge, so (but for a few along its boundary, which
  // the boundary's own turn decides) every split is integrated.
  const TwistFlow flow;
  const double radius = 0.3;
  const SeedCurve seed = SeedCurve::line(Vec3(radius, 0, 0.2), Vec3(radius, 0, 0.6));
  StreakOptions o = whole_dye_options(3, {1.5, 3}, 0.05);
  const double tolerance = o.flat_split;
  const auto off_cylinder = [&](const StreakFrame& f) {
    double worst = 0;
    for (const Vec3& p : f.mesh.positions)
      worst = std::max(worst, std::abs(std::hypot(p.x(), p.y()) - radius));
    return worst;
  };
  StreakReport flat_report, exact_report;
  const std::vector<StreakFrame> flat = collect(flow, seed, o, flat_report);
  o.flat_split = 0;
  const std::vector<StreakFrame> exact = collect(flow, seed, o, exact_report);
  REQUIRE(flat_report.complete);
  REQUIRE(exact_report.complete);
  REQUIRE(flat.size() == 2);
  INFO("splits " << flat_report.splits << ", flat " << flat_report.flat_insertions << ", exact "
                 << flat_report.exact_insertions << ", interpolated "
                 << flat_report.interpolated_insertions);
  CHECK(flat_report.flat_insertions * 10 < flat_report.splits);
  CHECK(flat_report.exact_insertions > 0);
  CHECK(exact_report.flat_insertions == 0);
  for (std::size_t k = 0; k < flat.size(); ++k) {
    require_valid(flat[k]);
    INFO("t = " << flat[k].time << ": off the cylinder by " << off_cylinder(flat[k])
                << " (flat splits), " << off_cylinder(exact[k]) << " (none)");
    CHECK(off_cylinder(exact[k]) < 1e-6);
    // Each midpoint within the tolerance of the surface (the estimate is to first order).
    CHECK(off_cylinder(flat[k]) <= 2 * tolerance * o.split * o.edge);
  }
}

TEST_CASE("remeshed streaks place splits of a curved boundary on it by a cubic with no integration",
          "[spacetime][streak][remeshed]") {
  // The oldest row winds into a spiral whose edges bend by more than the flat-split tolerance:
  // its splits go on the cubic through four of its particles, in s. Each must lie on the
  // spiral within the tolerance the cubic was held to (its label, interpolated, may lie off
  // along it: on_path 0).
  const VortexFlow flow;
  const SeedCurve seed = SeedCurve::line(Vec3(1, 0, 0), Vec3(2, 0, 0));
  StreakOptions o = whole_dye_options(6, {3, 6}, 0.1);
  o.smooth = false;  // smoothing slides boundary particles along chords, off the curve
  StreakReport r;
  const std::vector<StreakFrame> frames = collect(flow, seed, o, r);
  REQUIRE(r.complete);
  REQUIRE(frames.size() == 2);
  INFO("splits " << r.splits << ", flat " << r.flat_insertions << ", curve "
                 << r.curve_insertions << ", exact " << r.exact_insertions);
  CHECK(r.curve_insertions > 10);
  for (const StreakFrame& f : frames) {
    require_valid(f);
    // The oldest row at time t: radius 1 + s at angle t / (1 + s)², finely sampled.
    std::vector<Vec3> spiral;
    for (int k = 0; k <= 20000; ++k) {
      const double radius = 1 + k / 20000.0, angle = f.time / (radius * radius);
      spiral.emplace_back(radius * std::cos(angle), radius * std::sin(angle), 0);
    }
    const Mesh& m = f.mesh;
    double worst = 0;
    std::size_t interpolated = 0;
    for (std::size_t i = 0; i < m.vertex_count(); ++i) {
      if (m.release_time[i] != o.release_begin || m.on_path[i] != 0) continue;
      ++interpolated;
      double nearest = std::numeric_limits<double>::infinity();
      for (const Vec3& p : spiral) nearest = std::min(nearest, (m.positions[i] - p).norm());
      worst = std::max(worst, nearest);
    }
    INFO("t = " << f.time << ": " << interpolated << " interpolated particles on the oldest row, "
                << "the farthest " << worst / o.edge << " edge lengths off it");
    CHECK(interpolated > 10);
    // Within the tolerance (a quarter over: flat splits estimate to first order). Chord
    // midpoints in the cubic's place land 0.016 and 0.022 ℓ off.
    CHECK(worst <= 1.25 * o.flat_split * o.edge);
  }
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
  // Exact particles: a strip one face wide, which splits at midpoints leave behind, ends in a
  // face whose inner edge is a diagonal, and is read as wider than it is.
  o.flat_split = 0;
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

namespace {

// Every vertex marked on_path where its label's path is at the frame's time: (y age, y) for y
// on the seed. At least 90 % are on their paths (the rest were placed by interpolation).
double worst_path_error(const StreakFrame& f, const SeedCurve& seed) {
  double worst = 0;
  REQUIRE(f.mesh.on_path.size() == f.mesh.vertex_count());
  std::size_t on_path = 0;
  for (std::size_t i = 0; i < f.mesh.vertex_count(); ++i) {
    if (!f.mesh.on_path[i]) continue;
    ++on_path;
    const double y = seed.point(f.mesh.s[i]).y();
    const Vec3 expected(y * (f.time - f.mesh.release_time[i]), y, 0);
    worst = std::max(worst, (f.mesh.positions[i] - expected).norm());
  }
  CHECK(static_cast<double>(on_path) >= 0.9 * static_cast<double>(f.mesh.vertex_count()));
  return worst;
}

}  // namespace

TEST_CASE("a vertex budget keeps a growing streak surface within it by coarsening its oldest dye",
          "[spacetime][streak][remeshed]") {
  const ShearFlow flow;
  const SeedCurve seed = shear_seed();
  StreakOptions o = shear_growth_options();
  StreakReport free_run;
  const std::vector<StreakFrame> unbounded = collect(flow, seed, o, free_run);
  REQUIRE(free_run.complete);
  REQUIRE(unbounded.size() == 4);
  CHECK(free_run.budget_coarsenings == 0);
  CHECK(free_run.coarsened == 0);
  CHECK(std::isinf(free_run.coarsen_age));
  // Area grows linearly, and with a fixed edge length so does the vertex count.
  const std::size_t last = unbounded.back().mesh.vertex_count();
  CHECK(last > 3 * unbounded.front().mesh.vertex_count());

  o.vertex_budget = last / 2;
  StreakReport r;
  const std::vector<StreakFrame> frames = collect(flow, seed, o, r);
  REQUIRE(r.complete);
  REQUIRE(frames.size() == 4);
  CHECK(r.budget_coarsenings >= 1);
  CHECK(r.coarsened > 0);
  CHECK(std::isfinite(r.coarsen_age));
  CHECK(r.max_particles <= o.vertex_budget);
  INFO("exact " << r.exact_insertions << ", interpolated " << r.interpolated_insertions
                << ", diverged " << r.diverged_insertions << ", inexact ends " << r.inexact_ends
                << ", smoothed " << r.smoothed << ", coarsened " << r.coarsened << ", collapses "
                << r.collapses);
  for (const StreakFrame& f : frames) {
    require_valid(f);
    const StreakFrameRecord& rec = r.frames[static_cast<std::size_t>(f.index)];
    INFO("t = " << f.time << ": " << rec.vertices << " vertices of a budget of " << o.vertex_budget
                << ", coarsening age " << rec.coarsen_age << ", p05 min angle "
                << rec.quality.triangle_min_angle_p05);
    CHECK(rec.vertices <= o.vertex_budget);
    // Coarsening removes particles: the rest are still on their paths, and the polygon whole
    // but for slivers at its corner of 170° (boundary collapses need only 160°).
    CHECK(worst_path_error(f, seed) < 1e-6);
    CHECK(rec.area == Approx(0.3 * f.time).epsilon(1e-3));
    CHECK(rec.pieces == 1);
    CHECK(rec.max_edge_ratio <= o.split * (1 + 1e-9));
    CHECK(rec.quality.triangle_min_angle_p05 >= 20);
  }
}

TEST_CASE("remeshed streaks past the coarsening age are meshed at edge times age over it",
          "[spacetime][streak][remeshed]") {
  const ShearFlow flow;
  const SeedCurve seed = shear_seed();
  StreakOptions o = shear_growth_options();
  o.frames = {8};
  StreakReport fine;
  const std::vector<StreakFrame> reference = collect(flow, seed, o, fine);
  o.coarsen_age = 2;
  StreakReport r;
  const std::vector<StreakFrame> frames = collect(flow, seed, o, r);
  REQUIRE(r.complete);
  REQUIRE(frames.size() == 1);
  const StreakFrame& f = frames[0];
  require_valid(f);
  CHECK(r.coarsen_age == 2);
  CHECK(r.budget_coarsenings == 0);
  CHECK(r.coarsened > 0);
  CHECK(r.frames[0].max_edge_ratio <= o.split * (1 + 1e-9));
  CHECK(r.frames[0].area == Approx(0.3 * 8).epsilon(1e-3));
  CHECK(worst_path_error(f, seed) < 1e-6);
  CHECK(f.mesh.vertex_count() < reference[0].mesh.vertex_count() / 2);
  // Edges whose ends are both older than 6 have targets of at least 3 edge lengths.
  double sum = 0;
  std::size_t count = 0;
  for (const auto& face : f.mesh.faces)
    for (int e = 0; e < 3; ++e) {
      const auto a = static_cast<std::size_t>(face.v[static_cast<std::size_t>(e)]);
      const auto b = static_cast<std::size_t>(face.v[static_cast<std::size_t>((e + 1) % 3)]);
      if (f.mesh.age[a] > 6 && f.mesh.age[b] > 6) {
        sum += (f.mesh.positions[a] - f.mesh.positions[b]).norm();
        ++count;
      }
    }
  REQUIRE(count > 0);
  CHECK(sum / static_cast<double>(count) > 2 * o.edge);
}

TEST_CASE("remeshed streaks: dye that leaves the region of interest takes its faces with it",
          "[spacetime][streak][remeshed]") {
  const ShearFlow flow;  // no outflow: the region alone crops
  const SeedCurve seed = shear_seed();
  StreakOptions o = shear_growth_options();
  o.release_end = 6;
  o.frames = {6};
  Box<3> region;
  region.lo = Vec3(-1, 0, -std::numeric_limits<double>::infinity());
  region.hi = Vec3(1, 1, std::numeric_limits<double>::infinity());
  o.region = region;
  StreakReport r;
  const std::vector<StreakFrame> frames = collect(flow, seed, o, r);
  REQUIRE(r.complete);
  REQUIRE(frames.size() == 1);
  require_valid(frames[0]);
  CHECK(r.left_region > 0);
  CHECK(r.left_domain == 0);
  for (const Vec3& p : frames[0].mesh.positions) CHECK(p.x() <= 1.0);
  // Between the seed and x = 1 the strip's area is 0.6; the cut loses less than a row.
  CHECK(r.frames[0].area <= 0.6 + 1e-9);
  CHECK(r.frames[0].area > 0.6 - 0.6 * o.split * o.edge);

  SECTION("a region the seed misses is refused") {
    region.lo.x() = 0.5;
    o.region = region;
    CHECK_THROWS_WITH(collect(flow, seed, o, r), Catch::Contains("region of interest"));
  }
  SECTION("an empty region is refused") {
    region.hi.y() = region.lo.y();
    o.region = region;
    CHECK_THROWS_WITH(collect(flow, seed, o, r), Catch::Contains("region of interest is empty"));
  }
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
