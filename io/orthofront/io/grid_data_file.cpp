#include "orthofront/io/grid_data_file.h"

#include <algorithm>
#include <filesystem>
#include <sstream>
#include <stdexcept>

#include "orthofront/error.h"
#include "orthofront/io/grid_file.h"
#include "orthofront/io/grid_series.h"
#include "orthofront/io/vdb_field.h"
#include "orthofront/io/vdb_grid.h"

namespace orthofront::io {

namespace {

std::string number(double v) {
  std::ostringstream out;
  out << v;
  return out.str();
}

/// More than one vector grid, all with "time" metadata.
bool is_vdb_series(const std::vector<VdbGridInfo>& grids) {
  std::size_t vectors = 0;
  bool all_timed = true;
  for (const VdbGridInfo& g : grids) {
    if (g.value_type != "vec3s" && g.value_type != "vec3d") continue;
    ++vectors;
    all_timed = all_timed && g.time.has_value();
  }
  return vectors > 1 && all_timed;
}

/// A pattern (glob characters or a comma list) rather than one file name.
bool is_file_pattern(const std::string& path) {
  return path.find_first_of("*?[,") != std::string::npos && !std::filesystem::exists(path);
}

/// The selector of a series of grid files: "[ARRAY][,dt=DT][,t0=T0]" (an "array=NAME" key also
/// names the array).
struct GridSeriesSelector {
  std::string array;
  double dt = 1, t0 = 0;
  bool dt_given = false;
};

GridSeriesSelector parse_grid_series_selector(const std::string& text, const std::string& what) {
  GridSeriesSelector s;
  std::size_t begin = 0;
  while (begin <= text.size() && !text.empty()) {
    const std::size_t end = std::min(text.find(',', begin), text.size());
    const std::string item = text.substr(begin, end - begin);
    const std::size_t eq = item.find('=');
    if (eq == std::string::npos) {
      s.array = item;
    } else {
      const std::string key = item.substr(0, eq), value = item.substr(eq + 1);
      if (key == "array") {
        s.array = value;
      } else if (key == "dt" || key == "t0") {
        double number = 0;
        try {
          std::size_t used = 0;
          number = std::stod(value, &used);
          if (used != value.size()) throw std::invalid_argument(value);
        } catch (const std::exception&) {
          throw InvalidArgument("'" + what + "': " + key + "='" + value + "' is not a number");
        }
        if (key == "dt") {
          if (!(number > 0)) throw InvalidArgument("'" + what + "': dt must be > 0, got " + value);
          s.dt = number;
          s.dt_given = true;
        } else {
          s.t0 = number;
        }
      } else {
        throw InvalidArgument("'" + what + "': unknown selector key '" + key +
                              "' (a series of grid files takes ARRAY, array=, dt= and t0=)");
      }
    }
    begin = end + 1;
  }
  return s;
}

/// A glob or list of grid files, one step each at t0 + i dt.
DataFile open_grid_file_series(const DataFileSpec& spec) {
  const std::string what = spec.path.string();
  const GridSeriesSelector selector = parse_grid_series_selector(spec.selector, what);
  std::vector<std::filesystem::path> files = expand_file_pattern(what);
  const std::size_t count = files.size();
  auto series = std::make_unique<GridFileSeries>(
      std::move(files), evenly_spaced_times(count, selector.t0, selector.dt), selector.array);
  DataFile file;
  file.format =
      "series of " + std::string(grid_format_name(grid_format_of(series->files().front())));
  file.details.emplace_back("files", std::to_string(count) + " (" +
                                         series->files().front().filename().string() + " .. " +
                                         series->files().back().filename().string() + ")");
  file.details.emplace_back("time",
                            "t0 = " + number(selector.t0) + ", dt = " + number(selector.dt) +
                                (selector.dt_given ? "" : " (no dt= given: the step index)"));
  if (!selector.array.empty()) file.details.emplace_back("array", selector.array);
  file.details.emplace_back("zeros mean", "no data (land, solid)");
  for (const auto& f : series->files()) {
    std::error_code ec;
    const auto size = std::filesystem::file_size(f, ec);
    if (!ec) file.stored_bytes += size;
  }
  file.steady = count == 1;
  file.series = std::move(series);
  return file;
}

}  // namespace

DataFile open_grid_file(const DataFileSpec& spec) {
  if (is_file_pattern(spec.path.string())) return open_grid_file_series(spec);
  const GridFormat format = grid_format_of(spec.path);
  VectorGrid grid = read_vector_grid(spec.path, spec.selector);
  DataFile file;
  file.format = grid_format_name(format);
  if (!spec.selector.empty()) file.details.emplace_back("array", spec.selector);
  if (format == GridFormat::kVec)
    file.details.emplace_back("geometry", "none stored: unit spacing at the origin");
  file.details.emplace_back("zeros mean", "no data (land, solid)");
  std::error_code ec;
  file.stored_bytes = std::filesystem::file_size(spec.path, ec);
  if (ec) file.stored_bytes = 0;
  file.series = single_grid_series(std::move(grid), spec.path.string(), true);
  return file;
}

DataFile open_pvd_file(const DataFileSpec& spec) {
  auto series = open_pvd(spec.path, spec.selector);
  DataFile file;
  file.format = "ParaView collection (.pvd) of " +
                std::string(grid_format_name(grid_format_of(series->files().front())));
  file.details.emplace_back("files", std::to_string(series->files().size()) + " (" +
                                         series->files().front().filename().string() + " .. " +
                                         series->files().back().filename().string() + ")");
  if (!spec.selector.empty()) file.details.emplace_back("array", spec.selector);
  file.details.emplace_back("zeros mean", "no data (land, solid)");
  std::uint64_t bytes = 0;
  for (const auto& f : series->files()) {
    std::error_code ec;
    const auto size = std::filesystem::file_size(f, ec);
    if (!ec) bytes += size;
  }
  file.stored_bytes = bytes;
  file.steady = series->step_count() == 1;
  file.series = std::move(series);
  return file;
}

DataFile open_vdb_file(const DataFileSpec& spec) {
  const std::vector<VdbGridInfo> grids = list_vdb_grids(spec.path);
  DataFile file;
  file.format = "OpenVDB";
  for (const VdbGridInfo& g : grids) {
    std::string text = g.value_type + ", " + g.grid_class + ", " + std::to_string(g.active_voxels) +
                       " active voxels, voxel " + number(g.voxel_size[0]) + " x " +
                       number(g.voxel_size[1]) + " x " + number(g.voxel_size[2]);
    if (g.time) text += ", time " + number(*g.time);
    file.details.emplace_back("grid " + g.name, text);
  }
  file.details.emplace_back("inactive", "no data (NaN in the dense view)");
  std::error_code ec;
  file.stored_bytes = std::filesystem::file_size(spec.path, ec);
  if (ec) file.stored_bytes = 0;
  if (spec.selector.empty() && is_vdb_series(grids)) {
    file.series = open_vdb_file_series(spec.path);
    file.steady = false;
    file.zero_is_no_data = false;
    return file;
  }
  VectorGrid grid = read_vdb_grid(spec.path, spec.selector);
  file.zero_is_no_data = false;  // inactive voxels mark missing data; zeros are flow
  file.series = single_grid_series(std::move(grid), spec.path.string(), file.zero_is_no_data);
  return file;
}

std::unique_ptr<Field3> open_vdb_field(const DataFileSpec& spec) {
  if (spec.selector.empty() && is_vdb_series(list_vdb_grids(spec.path))) {
    throw InvalidArgument("'" + spec.path.string() +
                          "' holds a time series of vector grids; a stream surface needs a steady "
                          "field: name one grid as FILE.vdb:GRID (see `orthofront info`)");
  }
  return VdbField::open(spec.path, spec.selector);
}

}  // namespace orthofront::io
