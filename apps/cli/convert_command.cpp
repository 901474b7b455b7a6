// `orthofront convert INPUT... --out OUT.h5|OUT.vdb`: real data formats (.vec, .am, .nrrd, .vti,
// .vtk, .pvd, .vdb, .h5) into the project's HDF5 layout or OpenVDB. One steady input gives a
// steady field; several inputs (or a glob, a .pvd, a VDB/HDF5 series) give a time series,
// streamed one step at a time.
#include <algorithm>
#include <cctype>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
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
#include "orthofront/io/data_file.h"
#include "orthofront/io/grid_file.h"
#include "orthofront/io/grid_series.h"
#include "orthofront/io/hdf5_layout.h"
#include "orthofront/io/vdb_grid.h"

namespace orthofront::cli {

using namespace jobs;

namespace {

struct ConvertArgs {
  std::vector<std::string> inputs;
  std::string out;
  std::string times;
  double dt = std::nan("");
  double t0 = 0.0;
  std::string origin;
  std::string spacing;
  bool keep_order = false;
  std::string compress = "lz4";
  std::string layout = "bricked";
  std::int64_t brick = 32;
  std::string group = "/";
  double chunk_mib = std::nan("");  // NaN: the HDF5 writer's default
  io::Hdf5Units units;
  double fill_value = std::nan("");
  bool zeros_are_flow = false;
  std::string grid_name = "velocity";
  bool quiet = false;
};

std::string lower(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return text;
}

std::string extension_of(const std::string& path) {
  return lower(std::filesystem::path(path).extension().string());
}

/// Inputs with glob patterns expanded (a pattern that names an existing file is kept as is).
std::vector<std::string> expand_inputs(const std::vector<std::string>& inputs) {
  std::vector<std::string> files;
  for (const std::string& input : inputs) {
    const bool pattern = input.find_first_of("*?[") != std::string::npos;
    // NetCDF specs stay whole: the reader expands them and applies the selector to every file.
    const auto found = io::find_data_file(input);
    if (!pattern || std::filesystem::exists(input) ||
        (found && io::is_netcdf_path(found->first.path))) {
      files.push_back(input);
      continue;
    }
    for (const auto& file : io::expand_file_pattern(input)) files.push_back(file.string());
  }
  return files;
}

std::vector<double> parse_times(const std::string& text) {
  std::vector<double> times;
  std::size_t start = 0;
  for (;;) {
    const std::size_t comma = text.find(',', start);
    const std::string part =
        text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    double t = 0.0;
    const auto r = std::from_chars(part.data(), part.data() + part.size(), t);
    if (r.ec != std::errc() || r.ptr != part.data() + part.size() || !std::isfinite(t))
      throw InvalidArgument("--times '" + text + "': '" + part + "' is not a finite number");
    times.push_back(t);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return times;
}

Vec3 parse_triple(const std::string& text, const std::string& what) {
  Vec3 v;
  std::size_t start = 0;
  for (int a = 0; a < 3; ++a) {
    const std::size_t comma = text.find(',', start);
    if ((a < 2) == (comma == std::string::npos))
      throw InvalidArgument(what + " '" + text + "' must be three numbers x,y,z");
    const std::string part =
        text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    const auto r = std::from_chars(part.data(), part.data() + part.size(), v[a]);
    if (r.ec != std::errc() || r.ptr != part.data() + part.size() || !std::isfinite(v[a]))
      throw InvalidArgument(what + " '" + text + "': '" + part + "' is not a finite number");
    start = comma + 1;
  }
  return v;
}

/// A series whose geometry is replaced (origin and/or spacing; the samples are unchanged).
class PlacedSeries final : public io::TimeSeries {
 public:
  PlacedSeries(std::unique_ptr<io::TimeSeries> inner, GridGeometry geometry)
      : inner_(std::move(inner)), geometry_(std::move(geometry)) {}
  std::size_t step_count() const override { return inner_->step_count(); }
  double time(std::size_t step) const override { return inner_->time(step); }
  const GridGeometry& geometry() const override { return geometry_; }
  int components() const override { return inner_->components(); }
  std::string describe() const override { return inner_->describe(); }
  bool zero_is_no_data() const override { return inner_->zero_is_no_data(); }
  io::RawStep read_raw(std::size_t step) const override { return inner_->read_raw(step); }
  void decode(const io::RawStep& raw, std::span<float> values) const override {
    inner_->decode(raw, values);
  }

 private:
  std::unique_ptr<io::TimeSeries> inner_;
  GridGeometry geometry_;
};

/// A series with other times (same steps).
class RetimedSeries final : public io::TimeSeries {
 public:
  RetimedSeries(std::unique_ptr<io::TimeSeries> inner, std::vector<double> times)
      : inner_(std::move(inner)), times_(std::move(times)) {}
  std::size_t step_count() const override { return inner_->step_count(); }
  double time(std::size_t step) const override { return times_.at(step); }
  const GridGeometry& geometry() const override { return inner_->geometry(); }
  int components() const override { return inner_->components(); }
  std::string describe() const override { return inner_->describe(); }
  bool zero_is_no_data() const override { return inner_->zero_is_no_data(); }
  io::RawStep read_raw(std::size_t step) const override { return inner_->read_raw(step); }
  void decode(const io::RawStep& raw, std::span<float> values) const override {
    inner_->decode(raw, values);
  }

 private:
  std::unique_ptr<io::TimeSeries> inner_;
  std::vector<double> times_;
};

struct Input {
  std::unique_ptr<io::TimeSeries> series;
  bool steady = true;      // one step, no time of its own
  bool has_times = false;  // the input stated its times (.pvd, HDF5 series, VDB 'time' metadata)
};

/// "FILE.ext[:SELECTOR]" split at the first ':' after a known data-file extension.
io::DataFileSpec split_spec(const std::string& spec) {
  const auto found = io::find_data_file(spec);
  if (!found) {
    throw InvalidArgument("input '" + spec + "' has an unknown extension (expected " +
                          io::data_file_extensions() + ")");
  }
  return found->first;
}

bool is_hdf5(const std::filesystem::path& path) {
  const std::string ext = lower(path.extension().string());
  return ext == ".h5" || ext == ".hdf5" || ext == ".hdf";
}

/// The inputs as a time series. `times` (optional) are the steps' times for several files.
Input open_inputs(const std::vector<std::string>& files, const std::vector<double>& times) {
  Input input;
  if (files.size() == 1) {
    const io::DataFileSpec spec = split_spec(files.front());
    const std::string ext = lower(spec.path.extension().string());
    if (io::is_netcdf_path(spec.path)) {
      input.series = io::open_netcdf_series(spec);
      input.steady = input.series->step_count() == 1;
      input.has_times = true;
      return input;
    }
    if (ext == ".pvd") {
      input.series = io::open_pvd(spec.path, spec.selector);
      input.steady = false;
      input.has_times = true;
      return input;
    }
    if (is_hdf5(spec.path)) {
      io::Hdf5ReadOptions options;
      options.steady_as_single_step = true;
      auto series =
          io::open_hdf5_series(spec.path, spec.selector.empty() ? "/" : spec.selector, options);
      input.steady = series->description().storage == io::Hdf5Storage::steady;
      input.has_times = !input.steady;
      input.series = std::move(series);
      return input;
    }
    if (io::grid_format_of(spec.path) == io::GridFormat::kVdb && spec.selector.empty()) {
      std::size_t timed = 0;
      std::size_t vectors = 0;
      for (const auto& g : io::list_vdb_grids(spec.path)) {
        if (g.value_type != "vec3s" && g.value_type != "vec3d") continue;
        ++vectors;
        timed += g.time ? 1 : 0;
      }
      if (vectors > 1 && timed == vectors) {
        input.series = io::open_vdb_file_series(spec.path);
        input.steady = false;
        input.has_times = true;
        return input;
      }
    }
    // Zero vectors: no data in grid files, flow in VDB (whose inactive voxels are the no data).
    input.series = std::make_unique<io::SingleGridSeries>(
        io::read_vector_grid(spec.path, spec.selector), files.front(),
        io::grid_format_of(spec.path) != io::GridFormat::kVdb);
    return input;
  }
  // Several NetCDF files: one series over all of them (steps and times from the files).
  if (std::all_of(files.begin(), files.end(), [](const std::string& f) {
        const auto found = io::find_data_file(f);
        return found && io::is_netcdf_path(found->first.path);
      })) {
    io::DataFileSpec all = split_spec(files.front());
    std::string list;
    for (const std::string& f : files) {
      const io::DataFileSpec spec = split_spec(f);
      if (spec.selector != all.selector)
        throw InvalidArgument("inputs name different variables ('" + all.selector + "', '" +
                              spec.selector + "'); a series reads the same ones from every file");
      list += (list.empty() ? "" : ",") + spec.path.string();
    }
    all.path = list;
    input.series = io::open_netcdf_series(all);
    input.steady = false;
    input.has_times = true;
    return input;
  }
  // Several files: one step each, the same array of each.
  std::vector<io::DataFileSpec> specs;
  bool all_vdb = true;
  for (const std::string& file : files) {
    io::DataFileSpec spec = split_spec(file);
    if (io::grid_format_of(spec.path) == io::GridFormat::kUnknown) {
      throw InvalidArgument("input '" + file + "': a time series is made of grid files (" +
                            io::grid_extensions_text() + "); a .pvd or .h5 input stands alone");
    }
    if (!specs.empty() && spec.selector != specs.front().selector) {
      throw InvalidArgument("inputs name different arrays ('" + specs.front().selector + "', '" +
                            spec.selector + "'); a series reads the same array from every file");
    }
    all_vdb = all_vdb && io::grid_format_of(spec.path) == io::GridFormat::kVdb;
    specs.push_back(std::move(spec));
  }
  const std::vector<double> step_times =
      times.empty() ? io::evenly_spaced_times(files.size(), 0.0, 1.0) : times;
  if (all_vdb) {
    std::vector<io::VdbStep> steps;
    for (const auto& spec : specs) steps.push_back(io::VdbStep{spec.path, spec.selector});
    input.series = io::open_vdb_series(std::move(steps), step_times);
  } else {
    std::vector<std::filesystem::path> paths;
    for (const auto& spec : specs) paths.push_back(spec.path);
    input.series =
        std::make_unique<io::GridFileSeries>(std::move(paths), step_times, specs.front().selector);
  }
  input.steady = false;
  input.has_times = !times.empty();
  return input;
}

void run_convert(const ConvertArgs& args) {
  const auto start = std::chrono::steady_clock::now();
  const std::filesystem::path out = args.out;
  const std::string out_ext = extension_of(args.out);
  const bool to_vdb = out_ext == ".vdb";
  std::string sidecar;  // what "Wrote OUT" goes on with: its .xmf, or why there is none
  if (!to_vdb && out_ext != ".h5" && out_ext != ".hdf5")
    throw InvalidArgument("output '" + args.out + "' must end in .h5, .hdf5 or .vdb");
  if (!args.times.empty() && std::isfinite(args.dt))
    throw InvalidArgument("give --times or --dt, not both");
  if (std::isfinite(args.dt) && !(args.dt > 0))
    throw InvalidArgument("--dt must be positive, got " + std::to_string(args.dt));
  if (std::isfinite(args.chunk_mib) && !(args.chunk_mib > 0))
    throw InvalidArgument("--chunk-mib must be positive, got " + std::to_string(args.chunk_mib));

  std::vector<std::string> files = expand_inputs(args.inputs);
  if (files.empty()) throw InvalidArgument("no input files");
  if (!args.keep_order) std::stable_sort(files.begin(), files.end(), io::natural_less);

  std::vector<double> times;
  if (!args.times.empty()) times = parse_times(args.times);
  if (std::isfinite(args.dt)) times = io::evenly_spaced_times(files.size(), args.t0, args.dt);
  if (!times.empty() && files.size() > 1 && times.size() != files.size()) {
    throw InvalidArgument("--times gives " + std::to_string(times.size()) + " times for " +
                          std::to_string(files.size()) + " input files");
  }
  Input input = open_inputs(files, files.size() > 1 ? times : std::vector<double>{});
  bool steady = input.steady && times.empty();
  if (files.size() == 1 && !times.empty()) {
    // New times for a single input's steps (a steady input becomes a series of one step).
    if (std::isfinite(args.dt))
      times = io::evenly_spaced_times(input.series->step_count(), args.t0, args.dt);
    if (times.size() != input.series->step_count()) {
      throw InvalidArgument("--times gives " + std::to_string(times.size()) + " times for the " +
                            std::to_string(input.series->step_count()) + " steps of " +
                            files.front());
    }
    input.series = std::make_unique<RetimedSeries>(std::move(input.series), times);
    input.has_times = true;
    steady = false;
  }
  const bool default_times = !steady && !input.has_times;

  // Geometry given on the command line (formats that store none, such as .vec).
  if (!args.origin.empty() || !args.spacing.empty()) {
    GridGeometry g = input.series->geometry();
    if (g.rectilinear()) throw InvalidArgument("--origin/--spacing apply to uniform grids only");
    if (!args.origin.empty()) g.origin = parse_triple(args.origin, "--origin");
    if (!args.spacing.empty()) {
      g.spacing = parse_triple(args.spacing, "--spacing");
      if ((g.spacing.array() <= 0.0).any())
        throw InvalidArgument("--spacing '" + args.spacing + "' must be positive");
    }
    input.series = std::make_unique<PlacedSeries>(std::move(input.series), g);
  }

  const io::TimeSeries& series = *input.series;
  const GridGeometry& geometry = series.geometry();
  const std::size_t steps = series.step_count();
  std::vector<double> out_times;
  for (std::size_t s = 0; s < steps; ++s) out_times.push_back(series.time(s));

  std::vector<float> values(series.step_floats());
  const auto read_step = [&](std::size_t s) {
    if (interrupted())
      throw Error("interrupted after " + std::to_string(s) + " of " + std::to_string(steps) +
                  " steps: no file written");
    series.read(s, values);
  };
  const auto grid_of = [&]() {
    VectorGrid grid;
    grid.geometry = geometry;
    grid.components = series.components();
    grid.values = values;
    return grid;
  };
  ProgressBar bar("convert");
  const auto tick = [&](std::size_t s) {
    Progress progress;
    progress.step = static_cast<int>(s + 1);
    progress.max_steps = static_cast<int>(steps);
    progress.elapsed_seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (!bar.update(progress))
      throw Error("interrupted after " + std::to_string(s + 1) + " of " + std::to_string(steps) +
                  " steps: no file written");
  };

  if (to_vdb) {
    io::VdbFileWriter writer(out);
    for (std::size_t s = 0; s < steps; ++s) {
      read_step(s);
      char name[32];
      std::snprintf(name, sizeof name, "_%04zu", s);
      writer.add(steady ? args.grid_name : args.grid_name + name, grid_of(),
                 steady ? std::nullopt : std::optional<double>(out_times[s]));
      tick(s);
    }
    bar.finish();
    writer.commit();
  } else {
    io::Hdf5WriteOptions options;
    options.group = args.group;
    apply_compression(parse_compression(args.compress), options);
    sidecar = sidecar_text(options, args.out);
    options.brick_size = args.brick;
    options.storage = parse_layout(args.layout);
    options.units = args.units;
    if (std::isfinite(args.chunk_mib))
      options.max_chunk_bytes = static_cast<std::size_t>(args.chunk_mib * 1024 * 1024);
    // The output keeps the input's rule for zero vectors (an HDF5 file whose zeros are flow
    // stays so); --zeros-are-flow overrides it.
    options.zero_is_no_data = !args.zeros_are_flow && series.zero_is_no_data();
    if (std::isfinite(args.fill_value)) options.fill_value = static_cast<float>(args.fill_value);
    if (steady) {
      read_step(0);
      io::write_hdf5_grid(grid_of(), out, options);
    } else {
      io::Hdf5SeriesWriter writer(out, geometry, series.components(), out_times, options);
      for (std::size_t s = 0; s < steps; ++s) {
        read_step(s);
        writer.write_step(values);
        tick(s);
      }
      bar.finish();
      writer.commit();
    }
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (!args.quiet) {
    std::cout << "Wrote " << args.out;
    std::cout << sidecar;
    std::cout << ": " << series.describe() << " -> " << geometry.size[0] << " x "
              << geometry.size[1];
    if (geometry.dimension == 3) std::cout << " x " << geometry.size[2];
    std::cout << " points, " << series.components() << " components, ";
    if (steady) {
      std::cout << "steady";
    } else {
      std::cout << steps << (steps == 1 ? " step" : " steps") << " at t = " << out_times.front();
      if (steps > 1) std::cout << " .. " << out_times.back();
      if (default_times) std::cout << " (no --times or --dt: steps at t = 0, 1, 2, ...)";
    }
    std::cout << ", " << format_memory(series.step_bytes() * steps) << " ("
              << format_memory(std::filesystem::file_size(out))
              << " on disk) in " << seconds << " s\n";
  }
}

}  // namespace

void add_convert_command(CLI::App& app) {
  auto args = std::make_shared<ConvertArgs>();
  CLI::App* c = app.add_subcommand(
      "convert",
      "Convert vector-field files (.vec, .am, .nrrd, .vti, .vtk, .pvd, .vdb, .h5) to the HDF5 "
      "layout or OpenVDB");
  c->add_option("inputs", args->inputs,
                "Input files (FILE or FILE:ARRAY; globs like 'data/*.vec' are expanded). Several "
                "files make a time series, in natural order (2 before 10) unless --keep-order")
      ->required();
  c->add_option("--out", args->out, "Output: OUT.h5 (HDF5 layout + OUT.xmf) or OUT.vdb")
      ->required();
  c->add_option("--times", args->times, "Times of the steps t0,t1,... (strictly increasing)");
  c->add_option("--dt", args->dt, "Time between steps (times t0 + i dt)");
  c->add_option("--t0", args->t0, "Time of the first step with --dt")->capture_default_str();
  c->add_option("--origin", args->origin, "Override the grid origin x,y,z (e.g. for .vec)");
  c->add_option("--spacing", args->spacing, "Override the grid spacing dx,dy,dz (e.g. for .vec)");
  c->add_flag("--keep-order", args->keep_order, "Keep the inputs in the given order");
  c->add_option("--compress", args->compress,
                "HDF5: none | lz4 | zstd | gzip, each with an optional :LEVEL (1-9); lz4 (Blosc, "
                "byte shuffle) decodes fastest, see docs/hdf5-layout.md")
      ->capture_default_str();
  c->add_option("--layout", args->layout,
                "HDF5 time series storage: bricked (a chunk per brick and step: partial "
                "reads) | chunked | per-step")
      ->capture_default_str();
  c->add_option("--brick", args->brick, "Bricked layout: points per brick along each axis")
      ->check(CLI::Range(2, 1024))
      ->capture_default_str();
  c->add_option("--group", args->group, "HDF5 group of the field")->capture_default_str();
  c->add_option(
      "--chunk-mib", args->chunk_mib,
      "HDF5: largest chunk in MiB (default: the writer's; steps are chunked by z-slices)");
  c->add_option("--units-length", args->units.length, "Length unit, e.g. m");
  c->add_option("--units-time", args->units.time, "Time unit, e.g. s");
  c->add_option("--units-velocity", args->units.velocity, "Velocity unit, e.g. m/s");
  c->add_option("--fill-value", args->fill_value,
                "HDF5: store missing samples (NaN) as this value");
  c->add_flag("--zeros-are-flow", args->zeros_are_flow,
              "Zero vectors are flow (critical points), not land/solid (HDF5 attribute)");
  c->add_option("--grid-name", args->grid_name,
                "VDB: grid name (a series: NAME_0000, NAME_0001, ... with 'time' metadata)")
      ->capture_default_str();
  c->add_flag("--quiet", args->quiet, "No summary on stdout");
  c->callback([args]() { run_convert(*args); });
}

}  // namespace orthofront::cli
