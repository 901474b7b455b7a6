#include "orthofront/io/open_field.h"

#include <filesystem>

#include "orthofront/error.h"
#include "orthofront/field/analytic.h"
#include "orthofront/field/grid_field.h"
#include "orthofront/huge_pages.h"
#include "orthofront/io/data_file.h"
#include "orthofront/io/grid_data_file.h"
#include "orthofront/io/grid_series.h"
#include "orthofront/io/hdf5_layout.h"
#include "orthofront/io/vdb_grid.h"

namespace orthofront::io {

namespace {

std::unique_ptr<Field3> open_grid_field(const std::string& spec) {
  DataFile file = open_data_file(spec);
  if (!file.steady || file.series->step_count() != 1)
    throw InvalidArgument("'" + spec + "' holds a time series of " +
                          std::to_string(file.series->step_count()) +
                          " steps; a stream surface needs a steady field");
  auto grid = std::make_shared<VectorGrid>();
  grid->geometry = file.series->geometry();
  grid->components = file.series->components();
  reserve_huge_pages(grid->values, file.series->step_floats());
  grid->values.resize(file.series->step_floats());
  file.series->read(0, grid->values);
  GridFieldOptions options;
  options.zero_is_no_data = file.zero_is_no_data;
  return std::make_unique<GridField>(std::move(grid), options);
}

}  // namespace

std::unique_ptr<Field3> open_field(const std::string& spec) {
  if (const auto found = find_data_file(spec)) {
    // OpenVDB is sampled sparsely, straight from its tree (inactive voxels: no data).
    if (found->second->open == open_vdb_file) return open_vdb_field(found->first);
    return open_grid_field(spec);
  }
  if (looks_like_file(spec))
    throw InvalidArgument("field '" + spec + "' looks like a file but has no known extension (" +
                          data_file_extensions() + "); analytic fields: `orthofront fields`");
  return make_analytic_field(spec);
}

std::unique_ptr<TimeSeries> open_time_series(const std::string& spec, const std::string& what) {
  // NetCDF: a file, a glob or a list, streamed through the same cache as HDF5.
  const auto found = find_data_file(spec);
  if (found && is_netcdf_path(found->first.path)) return open_netcdf_series(found->first);
  // A ParaView collection of grid files (.vti, .vtk, ...) with their times.
  if (found && found->first.path.extension() == ".pvd" &&
      std::filesystem::exists(found->first.path))
    return open_pvd(found->first.path, found->first.selector);
  // One grid file per step: a glob or a list of .vti, .nhdr, .vec, ... (times from dt=).
  if (found && found->second->open == open_grid_file &&
      (std::filesystem::exists(found->first.path) ||
       found->first.path.string().find_first_of("*?[,") != std::string::npos))
    return open_grid_file(found->first).series;
  const std::filesystem::path file = spec;
  if (!std::filesystem::exists(file))
    throw InvalidArgument("--field '" + spec +
                          "' is neither an unsteady field name (see `orthofront fields`) nor an "
                          "existing file");
  if (file.extension() == ".vdb")
    return open_vdb_file_series(file);  // grids with "time" metadata, read leaf-wise
  if (is_hdf5_file(file)) return open_hdf5_series(file);
  throw InvalidArgument("--field '" + spec + "': " + what +
                        " read time series in the project's HDF5 layout (docs/hdf5-layout.md), "
                        "NetCDF files (a file, a glob or a list), ParaView .pvd collections, "
                        "globs or lists of grid files (.vti, .nhdr, .vec, ...) or OpenVDB files "
                        "of timed vector grids; this file is none of them");
}

}  // namespace orthofront::io
