// `orthofront generate`: samples an analytic field (steady, or unsteady as a time series) onto a
// uniform grid and writes the project's HDF5 layout, streaming a series step by step.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "cli/commands.h"
#include "jobs/grid_args.h"
#include "jobs/process_memory.h"
#include "cli/progress_bar.h"
#include "orthofront/error.h"
#include "orthofront/field/analytic.h"
#include "orthofront/field/sample_field.h"
#include "orthofront/field/unsteady.h"
#include "orthofront/io/hdf5_layout.h"

namespace orthofront::cli {

using namespace jobs;

namespace {

struct GenerateArgs {
  std::string field;
  std::string out;
  std::string resolution;
  std::string box;
  std::string compress = "lz4";
  std::string layout = "bricked";
  std::int64_t brick = 32;
  std::string group = "/";
  int steps = 0;
  double t0 = 0;
  double t1 = std::nan("");
  double chunk_mib = 16;
  io::Hdf5Units units;
  bool quiet = false;
};

/// The unsteady field frozen at time t, as a steady field (for sampling one step).
class FieldAtTime final : public Field3 {
 public:
  FieldAtTime(const UnsteadyField& field, double t) : field_(field), t_(t) {}
  FieldStatus velocity(const Vec3& x, Vec3& v) const override { return field_.velocity(x, t_, v); }
  FieldStatus velocity_jacobian(const Vec3& x, Vec3& v, Mat3& J) const override {
    Vec3 dvdt;
    return field_.velocity_jacobian(x, t_, v, J, dvdt);
  }
  Box<3> domain() const override { return field_.domain(); }
  std::string describe() const override { return field_.describe(); }

 private:
  const UnsteadyField& field_;
  double t_;
};

void run_generate(const GenerateArgs& args) {
  const std::filesystem::path out = args.out;
  const std::string extension = out.extension().string();
  if (extension != ".h5" && extension != ".hdf5")
    throw InvalidArgument("output '" + args.out + "' must end in .h5 or .hdf5");
  if (!(args.chunk_mib > 0))
    throw InvalidArgument("--chunk-mib must be positive, got " + std::to_string(args.chunk_mib));

  io::Hdf5WriteOptions options;
  options.group = args.group;
  apply_compression(parse_compression(args.compress), options);
  options.brick_size = args.brick;
  options.storage = parse_layout(args.layout);
  options.units = args.units;
  options.max_chunk_bytes = static_cast<std::size_t>(args.chunk_mib * 1024 * 1024);
  options.zero_is_no_data = false;  // zero vectors of a formula are critical points, not land

  SampleOptions sampling;
  sampling.resolution = parse_resolution(args.resolution);
  if (!args.box.empty()) sampling.box = parse_box(args.box);
  // One step is sampled in memory: a resolution whose step cannot fit is refused before anything
  // is allocated (or written), naming the sizes.
  {
    double step_bytes = 3.0 * sizeof(float);
    for (const std::int64_t n : sampling.resolution) step_bytes *= static_cast<double>(std::max<std::int64_t>(n, 1));
    const std::size_t available = available_memory_bytes();
    if (available > 0 && step_bytes > 0.5 * static_cast<double>(available))
      throw InvalidArgument("--resolution " + args.resolution + ": one step of " +
                            std::to_string(sampling.resolution[0]) + " x " +
                            std::to_string(sampling.resolution[1]) + " x " +
                            std::to_string(sampling.resolution[2]) + " points needs " +
                            format_memory(step_bytes >= 0x1p62 ? std::size_t{1} << 62
                                                               : static_cast<std::size_t>(step_bytes)) +
                            " in memory, more than half of the " + format_memory(available) +
                            " available; lower --resolution (" + args.out + " was not written)");
  }

  const auto start = std::chrono::steady_clock::now();
  std::size_t steps_written = 1;
  GridGeometry geometry;
  int components = 3;
  if (is_unsteady_field_name(args.field)) {
    const auto field = make_unsteady_field(args.field);
    if (args.steps < 1)
      throw InvalidArgument("field '" + args.field +
                            "' is time-dependent: give --steps N (and --t0, --t1)");
    if (args.steps > 1 && !std::isfinite(args.t1))
      throw InvalidArgument("--steps " + std::to_string(args.steps) + " needs --t1 (end time)");
    const double t1 = args.steps > 1 ? args.t1 : args.t0;
    if (args.steps > 1 && !(t1 > args.t0))
      throw InvalidArgument("--t1 (" + std::to_string(t1) + ") must exceed --t0 (" +
                            std::to_string(args.t0) + ")");
    const TimeRange range = field->time_range();
    if (!range.contains(args.t0) || !range.contains(t1))
      throw InvalidArgument("times [" + std::to_string(args.t0) + ", " + std::to_string(t1) +
                            "] lie outside the time range of '" + args.field + "' [" +
                            std::to_string(range.begin) + ", " + std::to_string(range.end) + "]");
    std::vector<double> times(static_cast<std::size_t>(args.steps));
    for (int i = 0; i < args.steps; ++i)
      times[static_cast<std::size_t>(i)] =
          args.steps == 1 ? args.t0
                          : args.t0 + (t1 - args.t0) * i / static_cast<double>(args.steps - 1);
    geometry = sampling_geometry(sampling, field->domain());
    components = field->dimension() == 2 && geometry.dimension == 2 ? 2 : 3;
    // One step in memory at a time, whatever the series' size.
    io::Hdf5SeriesWriter writer(out, geometry, components, times, options);
    std::vector<float> values(geometry.point_count() * static_cast<std::size_t>(components));
    ProgressBar bar("generate " + args.field);
    for (std::size_t s = 0; s < times.size(); ++s) {
      sample_field_into(FieldAtTime(*field, times[s]), geometry, components, values);
      writer.write_step(values);
      Progress progress;
      progress.step = static_cast<int>(s + 1);
      progress.max_steps = args.steps;
      progress.elapsed_seconds =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      if (!bar.update(progress))
        throw Error("interrupted after " + std::to_string(s + 1) + " of " +
                    std::to_string(times.size()) + " steps: no file written");
    }
    bar.finish();
    writer.commit();
    steps_written = times.size();
  } else {
    if (args.steps > 0)
      throw InvalidArgument("field '" + args.field +
                            "' is steady: --steps needs a time-dependent field (see `orthofront "
                            "fields`)");
    const auto field = make_analytic_field(args.field);
    const VectorGrid grid = sample_field(*field, sampling);
    geometry = grid.geometry;
    components = grid.components;
    io::write_hdf5_grid(grid, out, options);
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (!args.quiet) {
    const std::size_t step_bytes = geometry.point_count() * static_cast<std::size_t>(components) * 4;
    std::cout << "Wrote " << args.out << sidecar_text(options, args.out) << ": "
              << args.field << " on " << geometry.size[0] << " x " << geometry.size[1];
    if (geometry.dimension == 3) std::cout << " x " << geometry.size[2];
    std::cout << " points, " << components << " components, " << steps_written
              << (steps_written == 1 ? " step" : " steps") << " of " << format_memory(step_bytes) << " ("
              << format_memory(std::filesystem::file_size(out)) << " on disk) in "
              << seconds << " s\n";
  }
}

}  // namespace

void add_generate_command(CLI::App& app) {
  auto args = std::make_shared<GenerateArgs>();
  CLI::App* c = app.add_subcommand(
      "generate", "Sample an analytic field onto a grid and write the project's HDF5 layout");
  c->add_option("--field", args->field,
                "Analytic field NAME[:key=value,...]; time-dependent ones need --steps "
                "(see `orthofront fields`)")
      ->required();
  c->add_option("--out", args->out,
                "Output file (.h5); FILE.xmf is written beside it for ParaView (--compress none "
                "or gzip)")
      ->required();
  c->add_option("--resolution", args->resolution,
                "Samples per axis NX,NY,NZ (NZ = 1 or NX,NY: a 2D grid)")
      ->required();
  c->add_option("--box", args->box,
                "Sampled region xmin,ymin,zmin:xmax,ymax,zmax (default: the field's domain)");
  c->add_option("--compress", args->compress, "none | lz4 | zstd | gzip, each with an optional :LEVEL (1-9); lz4 (Blosc, byte "
                "shuffle) decodes fastest, see docs/hdf5-layout.md")
      ->capture_default_str();
  c->add_option("--layout", args->layout,
                "Time series storage: bricked (one 4D/5D dataset, a chunk per brick and step: "
                "partial reads) | chunked (chunks of whole z-slices) | per-step")
      ->capture_default_str();
  c->add_option("--brick", args->brick, "Bricked layout: points per brick along each axis")
      ->check(CLI::Range(2, 1024))
      ->capture_default_str();
  c->add_option("--group", args->group, "HDF5 group of the field")->capture_default_str();
  c->add_option("--steps", args->steps, "Time steps (time-dependent fields)");
  c->add_option("--t0", args->t0, "Time of the first step")->capture_default_str();
  c->add_option("--t1", args->t1, "Time of the last step");
  c->add_option(
       "--chunk-mib", args->chunk_mib,
       "Largest chunk in MiB: steps are chunked by whole z-slices (2D: y-rows) up to this size")
      ->capture_default_str();
  c->add_option("--units-length", args->units.length, "Length unit, e.g. m");
  c->add_option("--units-time", args->units.time, "Time unit, e.g. s");
  c->add_option("--units-velocity", args->units.velocity, "Velocity unit, e.g. m/s");
  c->add_flag("--quiet", args->quiet, "No summary on stdout");
  c->callback([args]() { run_generate(*args); });
}

}  // namespace orthofront::cli
