#include "orthofront/io/data_file.h"

#include <algorithm>
#include <cctype>
#include <cstring>

#include "orthofront/error.h"
#include "orthofront/io/grid_data_file.h"
#include "orthofront/io/grid_series.h"
#include "orthofront/io/hdf5_layout.h"
#include "orthofront/io/netcdf_series.h"

namespace orthofront::io {

namespace {

std::string lower(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return text;
}

std::string compression_text(const Hdf5Description& d) {
  if (d.filters.empty()) return "none";
  std::string text;
  for (const std::string& f : d.filters) {
    if (!text.empty()) text += " + ";
    text += f == "deflate" ? "gzip level " + std::to_string(d.gzip_level) : f;
  }
  return text;
}

DataFile open_hdf5(const DataFileSpec& spec) {
  Hdf5ReadOptions options;
  options.steady_as_single_step = true;
  auto series = open_hdf5_series(spec.path, spec.selector.empty() ? "/" : spec.selector, options);
  const Hdf5Description& d = series->description();
  DataFile file;
  file.format = "HDF5 (orthofront layout)";
  file.steady = d.storage == Hdf5Storage::steady;
  file.zero_is_no_data = d.zero_is_no_data;
  file.stored_bytes = d.stored_bytes;
  file.details.emplace_back("group", d.group);
  file.details.emplace_back("samples", d.dataset + " (" + d.stored_type + ")");
  std::string storage = to_string(d.storage);
  const std::int64_t slices = d.geometry.dimension == 3 ? d.geometry.size[2] : d.geometry.size[1];
  if (d.storage == Hdf5Storage::bricked) {
    const BrickLayout b = series->bricks();
    storage += ", bricks of " + std::to_string(b.size[0]) + " x " + std::to_string(b.size[1]) +
               (d.geometry.dimension == 3 ? " x " + std::to_string(b.size[2]) : std::string()) +
               " points (" + std::to_string(b.bricks()) + " per step)";
  } else if (d.chunk_slices >= slices)
    storage += ", one chunk per step";
  else if (d.chunk_slices > 0)
    storage += ", chunks of " + std::to_string(d.chunk_slices) +
               (d.geometry.dimension == 3 ? " z-slices" : " y-rows");
  else
    storage += ", contiguous";
  file.details.emplace_back("storage", storage);
  if (!d.missing_steps.empty()) {
    std::string missing;
    for (std::size_t s : d.missing_steps)
      missing += (missing.empty() ? "" : ", ") + std::to_string(s);
    file.details.emplace_back("missing steps",
                              missing + " (no dataset: reading them fails; surfaces stop there)");
  }
  file.details.emplace_back("compression", compression_text(d));
  const auto unit = [](const std::string& u) { return u.empty() ? std::string("-") : u; };
  file.details.emplace_back("units", "length " + unit(d.units.length) + ", time " +
                                         unit(d.units.time) + ", velocity " +
                                         unit(d.units.velocity));
  file.details.emplace_back("fill value", d.fill_value ? std::to_string(*d.fill_value) : "-");
  file.details.emplace_back("zeros mean",
                            d.zero_is_no_data ? "no data (land, solid)" : "flow (critical points)");
  file.series = std::move(series);
  return file;
}

DataFile open_netcdf(const DataFileSpec& spec) {
  DataFile file;
  file.series = open_netcdf_series(spec);
  file.format = "NetCDF (CF)";
  file.steady = file.series->step_count() == 1;
  file.zero_is_no_data = false;  // no data is NaN, fill values and the valid range
#ifdef ORTHOFRONT_HAVE_NETCDF
  const NetcdfDescription& d = *netcdf_description(*file.series);
  file.format = d.format + " (CF)";
  std::string vars;
  for (const std::string& v : d.variables) vars += (vars.empty() ? "" : ", ") + v;
  file.details.emplace_back("files", std::to_string(d.files));
  file.details.emplace_back("variables", vars + " (" + d.found_by + ")");
  file.details.emplace_back("coordinates", d.coordinates);
  file.details.emplace_back("time", d.time);
  file.details.emplace_back("velocity units", (d.velocity_units.empty() ? "-" : d.velocity_units) +
                                                 std::string(d.velocity_units_given ? " (given by units=)" : ""));
  if (d.lonlat) file.details.emplace_back("lon/lat", d.metric_note);
  file.details.emplace_back("no data", d.fill);
  file.details.emplace_back("zeros mean", "flow (critical points); land is the fill value");
#endif
  return file;
}

}  // namespace

std::unique_ptr<TimeSeries> open_netcdf_series(const DataFileSpec& spec) {
#ifdef ORTHOFRONT_HAVE_NETCDF
  return open_netcdf_series(expand_file_pattern(spec.path.string()),
                            parse_netcdf_selector(spec.selector));
#else
  throw InvalidArgument("'" + spec.path.string() +
                        "': this build reads no NetCDF (install libnetcdf-dev and configure "
                        "again)");
#endif
}

const std::vector<DataFileFormat>& data_file_formats() {
  static const std::vector<DataFileFormat> formats = {
      {"HDF5", {".h5", ".hdf5", ".hdf"}, open_hdf5},
      {"OSUFlow .vec", {".vec"}, open_grid_file},
      {"AmiraMesh", {".am"}, open_grid_file},
      {"NRRD", {".nrrd", ".nhdr"}, open_grid_file},
      {"VTK XML ImageData", {".vti"}, open_grid_file},
      {"legacy VTK", {".vtk"}, open_grid_file},
      {"ParaView collection", {".pvd"}, open_pvd_file},
      {"OpenVDB", {".vdb"}, open_vdb_file},
      {"NetCDF (CF)", {".nc", ".nc4", ".cdf"}, open_netcdf},
  };
  return formats;
}

std::string data_file_extensions() {
  std::string text;
  for (const DataFileFormat& f : data_file_formats())
    for (const std::string& e : f.extensions) text += (text.empty() ? "" : ", ") + e;
  return text;
}

std::optional<std::pair<DataFileSpec, const DataFileFormat*>> find_data_file(
    const std::string& spec) {
  const std::string lowered = lower(spec);
  for (std::size_t colon = spec.find(':');; colon = spec.find(':', colon + 1)) {
    const std::size_t end = colon == std::string::npos ? spec.size() : colon;
    for (const DataFileFormat& format : data_file_formats()) {
      for (const std::string& e : format.extensions) {
        if (end > e.size() && lowered.compare(end - e.size(), e.size(), e) == 0) {
          DataFileSpec file{spec.substr(0, end),
                            colon == std::string::npos ? std::string() : spec.substr(colon + 1)};
          return std::make_pair(std::move(file), &format);
        }
      }
    }
    if (colon == std::string::npos) return std::nullopt;
  }
}

bool looks_like_file(const std::string& spec) {
  const std::string head = spec.substr(0, spec.find(':'));
  return head.find('/') != std::string::npos || head.find('.') != std::string::npos;
}

DataFile open_data_file(const std::string& spec) {
  const auto found = find_data_file(spec);
  if (!found)
    throw InvalidArgument("'" + spec + "' is not a data file of a known format (extensions: " +
                          data_file_extensions() + ")");
  return found->second->open(found->first);
}

std::unique_ptr<TimeSeries> single_grid_series(VectorGrid grid, std::string description,
                                               bool zero_is_no_data) {
  return std::make_unique<SingleGridSeries>(std::move(grid), std::move(description),
                                            zero_is_no_data);
}

}  // namespace orthofront::io
