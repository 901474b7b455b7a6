#include "cli/grid_data_files.h"

#include <sstream>

#include "orthofront/error.h"
#include "orthofront/io/grid_file.h"
#include "orthofront/io/grid_series.h"
#include "orthofront/io/vdb_field.h"
#include "orthofront/io/vdb_grid.h"

namespace orthofront::cli {

namespace {

std::string number(double v) {
  std::ostringstream out;
  out << v;
  return out.str();
}

/// More than one vector grid, all with "time" metadata.
bool is_vdb_series(const std::vector<io::VdbGridInfo>& grids) {
  std::size_t vectors = 0;
  bool all_timed = true;
  for (const io::VdbGridInfo& g : grids) {
    if (g.value_type != "vec3s" && g.value_type != "vec3d") continue;
    ++vectors;
    all_timed = all_timed && g.time.has_value();
  }
  return vectors > 1 && all_timed;
}

}  // namespace

DataFile open_grid_file(const DataFileSpec& spec) {
  const io::GridFormat format = io::grid_format_of(spec.path);
  VectorGrid grid = io::read_vector_grid(spec.path, spec.selector);
  DataFile file;
  file.format = io::grid_format_name(format);
  if (!spec.selector.empty()) file.details.emplace_back("array", spec.selector);
  if (format == io::GridFormat::kVec)
    file.details.emplace_back("geometry", "none stored: unit spacing at the origin");
  file.details.emplace_back("zeros mean", "no data (land, solid)");
  std::error_code ec;
  file.stored_bytes = std::filesystem::file_size(spec.path, ec);
  if (ec) file.stored_bytes = 0;
  file.series = single_grid_series(std::move(grid), spec.path.string());
  return file;
}

DataFile open_pvd_file(const DataFileSpec& spec) {
  auto series = io::open_pvd(spec.path, spec.selector);
  DataFile file;
  file.format = "ParaView collection (.pvd) of " +
                std::string(io::grid_format_name(io::grid_format_of(series->files().front())));
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
  const std::vector<io::VdbGridInfo> grids = io::list_vdb_grids(spec.path);
  DataFile file;
  file.format = "OpenVDB";
  for (const io::VdbGridInfo& g : grids) {
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
    file.series = io::open_vdb_file_series(spec.path);
    file.steady = false;
    file.zero_is_no_data = false;
    return file;
  }
  VectorGrid grid = io::read_vdb_grid(spec.path, spec.selector);
  file.series = single_grid_series(std::move(grid), spec.path.string());
  file.zero_is_no_data = false;  // inactive voxels mark missing data; zeros are flow
  return file;
}

std::unique_ptr<Field3> open_vdb_field(const DataFileSpec& spec) {
  if (spec.selector.empty() && is_vdb_series(io::list_vdb_grids(spec.path))) {
    throw InvalidArgument("'" + spec.path.string() +
                          "' holds a time series of vector grids; a stream surface needs a steady "
                          "field: name one grid as FILE.vdb:GRID (see `orthofront info`)");
  }
  return io::VdbField::open(spec.path, spec.selector);
}

}  // namespace orthofront::cli
