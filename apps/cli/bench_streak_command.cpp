// `orthofront-bench streak`: streak surfaces of a streamed time series much larger than the
// cache budget, adaptive (exact and interpolated insertion) against a fixed-resolution baseline
// with the same final vertex count, in one run. Prints a table and JSON.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <limits>
#include <nlohmann/json.hpp>

#include "cli/bench_series_file.h"
#include "cli/bench_streak_real.h"
#include "cli/commands.h"
#include "orthofront/error.h"
#include "orthofront/field/unsteady.h"
#include "orthofront/io/error.h"
#include "orthofront/io/hdf5_layout.h"
#include "orthofront/quality/mesh_distance.h"
#include "orthofront/spacetime/brick_cache.h"
#include "orthofront/spacetime/sampled_series.h"
#include "orthofront/spacetime/spacetime_streak.h"
#include "orthofront/spacetime/streak_line_field.h"
#include "orthofront/spacetime/streak_surface.h"

namespace orthofront::cli {

namespace {

struct BenchStreakArgs {
  std::string field = "double-gyre", seed = "0.3,0.3:0.3,0.45";
  int resolution = 256, steps = 101;
  double t1 = 10, release_end = 5, edge = 0.02;
  int frames = 10;
  double budget_share = 16;  // data size / cache budget
  std::string keep;          // keep the series here (default: a temporary file, removed)
  bool json_only = false;
  BenchStreakRealArgs real;
};

// The release point of the route comparison: the middle of the seed segment.
Vec3 x0_point(double x0, double y0, double x1, double y1) {
  return Vec3(0.5 * (x0 + x1), 0.5 * (y0 + y1), 0);
}

struct Row {
  std::string name;
  spacetime::StreakReport report;
  double edge = 0;
};

nlohmann::json row_json(const Row& r, std::size_t data_bytes) {
  const auto& rep = r.report;
  const auto& f = rep.frames.back();
  return {{"name", r.name},
          {"seconds", rep.total_seconds},
          {"advect_seconds", rep.advect_seconds},
          {"refine_seconds", rep.refine_seconds},
          {"frame_seconds", rep.frame_seconds},
          {"wait_seconds", rep.wait_seconds},
          {"io_seconds", rep.io_seconds},
          {"decode_seconds", rep.decode_seconds},
          {"particle_steps", rep.particle_steps},
          {"particle_steps_per_second", rep.particle_steps / rep.total_seconds},
          {"particle_time", rep.particle_time},
          {"seconds_per_particle_time", rep.total_seconds / rep.particle_time},
          {"evaluations", rep.evaluations},
          {"exact_insertions", rep.exact_insertions},
          {"interpolated_insertions", rep.interpolated_insertions},
          {"last_frame",
           {{"time", f.time},
            {"vertices", f.vertices},
            {"faces", f.faces},
            {"quads", f.quality.quad_share},
            {"quad_angles_within_10", f.quality.quad_angles_within_10},
            {"triangle_min_angle_median", f.quality.triangle_min_angle_median},
            {"max_edge_over_edge", f.max_edge / r.edge},
            {"folds", f.quality.folds},
            {"t_junctions", f.quality.t_junctions},
            {"degenerate_faces", f.quality.degenerate_faces}}},
          {"bytes_read", rep.cache.bytes_read},
          {"data_bytes", data_bytes},
          {"max_reads_of_a_unit", rep.cache.max_reads_of_a_unit},
          {"peak_cache_bytes", rep.cache.peak_bytes}};
}

}  // namespace

void add_bench_streak_command(CLI::App& app) {
  auto a = std::make_shared<BenchStreakArgs>();
  CLI::App* c = app.add_subcommand(
      "streak",
      "Benchmark streak surfaces on a streamed series (adaptive vs fixed resolution)");
  c->add_option("--field", a->field, "Unsteady 2D analytic field sampled into the series")
      ->capture_default_str();
  c->add_option("--seed", a->seed, "Seed segment x0,y0:x1,y1")->capture_default_str();
  c->add_option("--resolution", a->resolution, "Grid points along x (y: half)")
      ->capture_default_str();
  c->add_option("--steps", a->steps, "Time steps of the series")->capture_default_str();
  c->add_option("--t1", a->t1, "Last time of the series (and the last frame)")
      ->capture_default_str();
  c->add_option("--release-end", a->release_end, "Release from 0 to this time")
      ->capture_default_str();
  c->add_option("--edge", a->edge, "Target edge length")->capture_default_str();
  c->add_option("--frames", a->frames, "Observation times, evenly up to --t1")
      ->capture_default_str();
  c->add_option("--data-over-budget", a->budget_share, "Data size / cache budget")
      ->capture_default_str();
  c->add_option("--keep", a->keep, "Write the series here and keep it");
  c->add_flag("--json", a->json_only, "Print only the JSON");
  c->add_option("--real", a->real.field,
                "Real unsteady series for the real-data rows (\"\": none; skipped when absent)")
      ->capture_default_str();
  c->add_option("--real-seed", a->real.seed, "Seed curve of the real-data rows")
      ->capture_default_str();
  c->add_option("--real-release", a->real.release, "Release interval T0:T1 of the real-data rows")
      ->capture_default_str();
  c->add_option("--real-frames", a->real.frames, "Observation times of the real-data rows")
      ->capture_default_str();
  c->add_option("--real-edge", a->real.edge, "Edge length of the real-data rows")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  c->add_option("--real-limit", a->real.limit_seconds,
                "Seconds after which a real-data run stops (and says how far it got)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  c->callback([a]() {
    const auto flow = make_unsteady_field(a->field);
    if (flow->dimension() != 2) throw InvalidArgument("orthofront-bench streak: --field must be a 2D flow");
    double x0, y0, x1, y1;
    if (std::sscanf(a->seed.c_str(), "%lf,%lf:%lf,%lf", &x0, &y0, &x1, &y1) != 4)
      throw InvalidArgument("--seed '" + a->seed + "': expected x0,y0:x1,y1");
    if (a->resolution < 8 || a->steps < 4 || a->frames < 1)
      throw InvalidArgument("orthofront-bench streak: --resolution >= 8, --steps >= 4 and --frames >= 1");
    const GridGeometry grid = spacetime::uniform_grid(flow->domain(), 2, a->resolution);
    GridGeometry g = grid;
    g.size[1] = a->resolution / 2 + 1;
    g.spacing[1] =
        (flow->domain().hi[1] - flow->domain().lo[1]) / static_cast<double>(g.size[1] - 1);
    const auto times = spacetime::uniform_times(0, a->t1, static_cast<std::size_t>(a->steps - 1));
    const spacetime::SampledTimeSeries sampled(*flow, g, times);
    const BenchSeriesFile series_file(a->keep, "orthofront-bench-streak");
    const std::filesystem::path& file = series_file.path();
    const auto w0 = std::chrono::steady_clock::now();
    {
      io::Hdf5WriteOptions w;
      w.codec = io::Hdf5Codec::lz4;
      w.zero_is_no_data = false;
      w.xdmf = false;
      io::Hdf5SeriesWriter writer(file, g, 3, times, w);
      std::vector<float> values(sampled.step_floats());
      for (std::size_t k = 0; k < sampled.step_count(); ++k) {
        sampled.sample(k, values.data());
        writer.write_step(values);
      }
      writer.commit();
    }
    const double write_seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count();
    const auto series = io::open_hdf5_series(file);
    const std::size_t data_bytes = sampled.step_floats() * sizeof(float) * sampled.step_count();
    const auto budget = static_cast<std::size_t>(static_cast<double>(data_bytes) / a->budget_share);

    spacetime::StreakOptions o;
    o.release_begin = 0;
    o.release_end = a->release_end;
    for (int i = 1; i <= a->frames; ++i) o.frames.push_back(a->t1 * i / a->frames);
    o.edge = a->edge;
    const SeedCurve seed = SeedCurve::line(Vec3(x0, y0, 0), Vec3(x1, y1, 0));
    const auto run = [&](const spacetime::StreakOptions& opts) {
      spacetime::CacheOptions co;
      co.budget_bytes = budget;
      spacetime::BrickCache cache(*series, co);
      return spacetime::build_streak_surface(cache, seed, opts, {});
    };
    std::vector<Row> rows;
    o.insertion = spacetime::ParticleInsertion::interpolate;
    rows.push_back({"adaptive, interpolated insertion", run(o), o.edge});
    o.insertion = spacetime::ParticleInsertion::exact;
    rows.push_back({"adaptive, exact insertion", run(o), o.edge});
    // Baseline: no insertion or removal, rows and particles per row scaled so that its last
    // frame has the adaptive run's vertex count.
    const auto& adaptive = rows.back().report;
    const double target = static_cast<double>(adaptive.frames.back().vertices);
    const double base = static_cast<double>(adaptive.seed_count * adaptive.rows_released);
    const double k = std::sqrt(std::max(1.0, target / base));
    spacetime::StreakOptions fixed = o;
    fixed.adaptive = false;
    fixed.seed_count = static_cast<int>(std::round(static_cast<double>(adaptive.seed_count) * k));
    fixed.release_step = adaptive.release_step / k;
    rows.push_back({"fixed resolution (baseline)", run(fixed), o.edge});
    for (const Row& r : rows)
      if (!r.report.complete)
        throw Error("orthofront-bench streak: '" + r.name + "' stopped: " + r.report.message);

    // The two routes on one point seed of the analytic field: the direct release (a seed segment
    // of length 1e-9, refined across rows) and the space-time stream surface through the
    // flow-orthogonal engine; agreement = farthest slice point from the direct streak line.
    const Vec3 point = x0_point(x0, y0, x1, y1);
    spacetime::SpacetimeStreakOptions so;
    so.release_begin = 0;
    so.release_end = a->release_end;
    so.t_end = a->t1;
    so.engine.edge = a->edge;
    so.engine.max_steps = 1'000'000;
    const spacetime::SpacetimeStreakResult st =
        spacetime::build_spacetime_streak_surface(*flow, point, so);
    spacetime::StreakOptions po;
    po.release_begin = 0;
    po.release_end = a->release_end;
    po.edge = a->edge;
    po.seed_count = 2;
    for (int i = 1; i <= a->frames; ++i) po.frames.push_back(0.999 * a->t1 * i / a->frames);
    std::vector<double> route_distance;
    const spacetime::StreakReport pr = spacetime::build_streak_surface(
        *flow, SeedCurve::line(point, point + Vec3(1e-9, 0, 0)), po,
        [&](const spacetime::StreakFrame& f) {
          std::vector<std::pair<double, Vec3>> by_release;
          for (std::size_t i = 0; i < f.mesh.vertex_count(); ++i)
            if (f.mesh.s[i] == 0)
              by_release.push_back({f.mesh.release_time[i], f.mesh.positions[i]});
          std::sort(by_release.begin(), by_release.end(),
                    [](const auto& p, const auto& q) { return p.first < q.first; });
          double far = 0;
          for (const Vec3& p : spacetime::slice_at_time(st.mesh, f.time)) {
            double best = std::numeric_limits<double>::infinity();
            for (std::size_t i = 0; i + 1 < by_release.size(); ++i) {
              const Vec3 q0 = by_release[i].second, d = by_release[i + 1].second - q0;
              const Vec3 q(p.x(), p.y(), 0);
              const double w = d.squaredNorm() > 0
                                   ? std::clamp((q - q0).dot(d) / d.squaredNorm(), 0.0, 1.0)
                                   : 0.0;
              best = std::min(best, (q0 + w * d - q).norm());
            }
            far = std::max(far, best);
          }
          route_distance.push_back(far);
        });
    const double farthest = route_distance.empty()
                                ? 0
                                : *std::max_element(route_distance.begin(), route_distance.end());
    const QualityReport& sq = st.report.quality;

    // The paper's route for the seed segment: at each frame, the stream surface of the
    // streak-line field over (x, y, age), against the direct route's frame lifted by age (the
    // farthest vertex of either surface from the other; the direct one only up to 0.95 t, since
    // the engine's last front ends within a step of the oldest age).
    spacetime::StreakOptions lo = o;
    lo.insertion = spacetime::ParticleInsertion::exact;
    std::vector<Mesh> direct_frames;
    const spacetime::StreakReport lr = spacetime::build_streak_surface(
        *flow, seed, lo, [&](const spacetime::StreakFrame& f) { direct_frames.push_back(f.mesh); });
    spacetime::StreakLineSurfaceOptions wo;
    wo.release_begin = 0;
    wo.release_end = a->release_end;
    wo.path.engine.edge = a->edge;
    wo.path.engine.max_steps = 1'000'000;
    double streak_line_seconds = 0, on_direct = 0, covers_direct = 0;
    std::size_t streak_line_vertices = 0, streak_line_values = 0, streak_line_folds = 0;
    double streak_line_quads = 0, streak_line_angles = 0;
    for (std::size_t frame = 0; frame < direct_frames.size(); ++frame) {
      wo.observation_time = lo.frames[frame];
      const spacetime::StreakLineSurface w = spacetime::build_streak_line_surface(*flow, seed, wo);
      streak_line_seconds += w.seconds;
      streak_line_values += w.derived_evaluations;
      streak_line_folds += w.report.quality.folds;
      const Mesh& d = direct_frames[frame];
      std::vector<Vec3> lifted(d.positions.begin(), d.positions.end());
      for (std::size_t i = 0; i < lifted.size(); ++i) lifted[i].z() = d.age[i];
      const auto direct_triangles = triangles_of(lifted, d.faces);
      for (const Vec3& p : w.lifted)
        on_direct = std::max(on_direct, distance_to(p, direct_triangles));
      const auto own = triangles_of(w.lifted, w.mesh.faces);
      for (std::size_t i = 0; i < lifted.size(); ++i)
        if (d.age[i] <= 0.95 * wo.observation_time)
          covers_direct = std::max(covers_direct, distance_to(lifted[i], own));
      if (frame + 1 == direct_frames.size()) {
        streak_line_vertices = w.mesh.vertex_count();
        streak_line_quads = w.report.quality.quad_share;
        streak_line_angles = w.report.quality.quad_angles_within_10;
      }
    }

    nlohmann::json out = {
        {"field", a->field},
        {"routes",
         {{"seed_point", {point.x(), point.y()}},
          {"direct_seconds", pr.total_seconds},
          {"direct_particles_last_frame", pr.frames.empty() ? 0 : pr.frames.back().vertices},
          {"spacetime_seconds", st.report.times.total},
          {"spacetime_vertices", st.mesh.vertex_count()},
          {"spacetime_time_scale", st.time_scale},
          {"spacetime_quads", sq.quad_share},
          {"spacetime_quad_angles_within_10", sq.quad_angles_within_10},
          {"spacetime_edge_spread_median", sq.edge_spread_median},
          {"spacetime_folds", sq.folds},
          {"farthest_slice_point_from_direct", farthest}}},
        {"streak_line_route",
         {{"direct_seconds", lr.total_seconds},
          {"direct_vertices_last_frame", lr.frames.empty() ? 0 : lr.frames.back().vertices},
          {"seconds", streak_line_seconds},
          {"field_values", streak_line_values},
          {"vertices_last_frame", streak_line_vertices},
          {"quads_last_frame", streak_line_quads},
          {"quad_angles_within_10_last_frame", streak_line_angles},
          {"folds", streak_line_folds},
          {"farthest_vertex_from_direct", on_direct},
          {"farthest_direct_vertex_from_it", covers_direct}}},
        {"grid", {g.size[0], g.size[1]}},
        {"steps", a->steps},
        {"data_bytes", data_bytes},
        {"cache_budget_bytes", budget},
        {"series_write_seconds", write_seconds},
        {"edge", a->edge},
        {"rows", nlohmann::json::array()}};
    for (const Row& r : rows) out["rows"].push_back(row_json(r, data_bytes));
    if (!a->json_only) {
      std::printf(
          "orthofront-bench streak: %s on %lld x %lld, %d steps, %.1f MiB of data through a %.1f MiB "
          "cache (1/%g), edge %g, release [0, %g], %d frames to t = %g\n",
          a->field.c_str(), static_cast<long long>(g.size[0]), static_cast<long long>(g.size[1]),
          a->steps, data_bytes / 1048576.0, budget / 1048576.0, a->budget_share, a->edge,
          a->release_end, a->frames, a->t1);
      std::printf("%-34s %8s %10s %9s %9s %8s %8s %8s %7s %7s %8s %8s %6s %8s\n", "run", "time s",
                  "p-steps", "us/p-step", "us/p-time", "refine%", "vertices", "quads%", "maxE/l",
                  "triMin", "read/data", "maxreads", "wait s", "io s");
      for (const Row& r : rows) {
        const auto& rep = r.report;
        const auto& f = rep.frames.back();
        std::printf(
            "%-34s %8.3f %10zu %9.3f %9.2f %8.1f %8zu %8.1f %7.2f %7.1f %8.3f %8zu %6.2f "
            "%8.3f\n",
            r.name.c_str(), rep.total_seconds, rep.particle_steps,
            1e6 * rep.total_seconds / static_cast<double>(rep.particle_steps),
            1e6 * rep.total_seconds / rep.particle_time,
            100 * rep.refine_seconds / rep.total_seconds, f.vertices, 100 * f.quality.quad_share,
            f.max_edge / a->edge, f.quality.triangle_min_angle_median,
            static_cast<double>(rep.cache.bytes_read) / static_cast<double>(data_bytes),
            rep.cache.max_reads_of_a_unit, rep.wait_seconds, rep.io_seconds);
      }
      std::printf(
          "\nRoutes, point seed (%g, %g), release [0, %g], to t = %g:\n"
          "  direct (rows of particles):        %.3f s, %zu particles on the last streak line\n"
          "  space-time (flow-orthogonal, c = %.3g): %.3f s, %zu vertices, %.1f%% quads, "
          "%.1f%% of quad angles within 90±10° (in (x, y, c t)), edge spread %.3f, %zu folds\n"
          "  agreement: slices of the space-time surface lie within %.3g (%.4f edge lengths) "
          "of the direct streak lines at %d times\n",
          point.x(), point.y(), a->release_end, a->t1, pr.total_seconds,
          pr.frames.empty() ? std::size_t{0} : pr.frames.back().vertices, st.time_scale,
          st.report.times.total, st.mesh.vertex_count(), 100 * sq.quad_share,
          100 * sq.quad_angles_within_10, sq.edge_spread_median, sq.folds, farthest,
          farthest / a->edge, a->frames);
      std::printf(
          "\nRoutes, seed segment, %d frames (in (x, y, age)):\n"
          "  direct (rows of particles, exact insertion): %.3f s, %zu vertices in the last frame\n"
          "  streak-line field (flow-orthogonal): %.3f s, %zu values of the field, %zu vertices "
          "in the last frame, %.1f%% quads, %.1f%% of quad angles within 90±10° (in (x, y, c "
          "age)), %zu folds in all frames\n"
          "  agreement: its vertices lie within %.3g (%.4f edge lengths) of the direct "
          "surface; direct particles up to age 0.95 t lie within %.3g (%.4f) of it\n",
          a->frames, lr.total_seconds,
          lr.frames.empty() ? std::size_t{0} : lr.frames.back().vertices, streak_line_seconds,
          streak_line_values, streak_line_vertices, 100 * streak_line_quads,
          100 * streak_line_angles, streak_line_folds, on_direct, on_direct / a->edge,
          covers_direct, covers_direct / a->edge);
      // The goals, adaptive against the baseline: time per particle and simulated time
      // unit within 1.3x, every edge <= 2 l, every step read once, total <= 1.15 x the larger of
      // the I/O floor (reading the bytes) and the compute (time not spent waiting for data).
      const auto& baseline = rows.back().report;
      std::printf("\nGoals (adaptive vs the baseline):\n");
      for (std::size_t i = 0; i + 1 < rows.size(); ++i) {
        const auto& rep = rows[i].report;
        const double compute = rep.total_seconds - rep.wait_seconds;
        std::printf(
            "  %-32s time per particle-time %.2fx the baseline's (goal <= 1.3); max edge "
            "%.2f l (goal <= 2); %zu reads of a step at most (goal 1); total %.2fx "
            "max(I/O %.2f s, compute %.2f s) (goal <= 1.15)\n",
            rows[i].name.c_str(),
            (rep.total_seconds / rep.particle_time) /
                (baseline.total_seconds / baseline.particle_time),
            rep.frames.back().max_edge / a->edge, rep.cache.max_reads_of_a_unit,
            rep.total_seconds / std::max(rep.io_seconds, compute), rep.io_seconds, compute);
      }
      std::printf(
          "\nColumns: p-steps = particle advances over one interval; refine%% = share of time "
          "inserting and removing; maxE/l = longest edge of the last frame in edge lengths; "
          "triMin = median minimum triangle angle (deg); read/data = bytes read / series "
          "size (raw, compressed).\n");
    }
    if (!a->real.field.empty()) out["real"] = bench_streak_real(a->real, a->json_only);
    std::cout << out.dump(1) << "\n";
  });
}

}  // namespace orthofront::cli
