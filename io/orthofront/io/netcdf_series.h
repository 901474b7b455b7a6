#pragma once
/// NetCDF time series with CF conventions (classic, 64-bit offset, CDF5 and NetCDF-4 files, read
/// through netCDF-C): the vector components chosen by name or found by CF standard_name, time
/// steps inside one file or one (or more) per file, `_FillValue` / `missing_value` /
/// `valid_min` / `valid_max` / `valid_range` -> no data (NaN), `scale_factor` / `add_offset`
/// applied, times from CF `units` and `calendar` in seconds, and lon/lat grids made consistent
/// with velocities in m/s (see LonLatMetric).
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "orthofront/io/grid_series.h"
#include "orthofront/io/time_series.h"

namespace orthofront::io {

/// What a lon/lat grid's surfaces are computed in, when its velocities are in m/s.
enum class LonLatMetric {
  /// Positions in degrees (the data's own coordinates); velocities become degrees per second on
  /// a sphere: u / (R cos φ), v / R. Exact on the sphere; no data within 0.1° of a pole.
  degrees,
  /// Positions in metres, x = R cos φ_ref λ, y = R φ (λ, φ in radians, φ_ref the grid's middle
  /// latitude); velocities stay m/s. East-west lengths are off by cos φ_ref / cos φ - 1, which
  /// the description reports as the grid's largest.
  metres,
};
const char* to_string(LonLatMetric metric);

struct NetcdfOptions {
  /// Names of u, v[, w]; empty: found by CF standard_name (eastward_sea_water_velocity,
  /// x_wind, ...) or, failing that, by the names u, v[, w].
  std::vector<std::string> variables;
  LonLatMetric lonlat = LonLatMetric::degrees;
  double earth_radius = 6371000.0;  ///< metres (IUGG mean radius)
  /// Seconds between steps for files without a CF time coordinate (0: such files are refused).
  double dt = 0;
  /// Units of the velocity components, replacing what the files say (or do not say).
  std::string velocity_units;
};

/// Parses a selector "u,v[,w][,lonlat=degrees|metres][,dt=SECONDS][,radius=METRES][,units=U]"
/// (the part of
/// FILE.nc:SELECTOR after the colon). Throws InvalidArgument naming a bad item.
NetcdfOptions parse_netcdf_selector(const std::string& selector);

/// What was found in the files, for `info` and reports.
struct NetcdfDescription {
  std::string format;                  ///< "NetCDF-3 classic", "NetCDF-4", ...
  std::vector<std::string> variables;  ///< the components read
  std::string found_by;                ///< "named", "CF standard_name" or "variable names"
  std::string velocity_units;          ///< as the file states them, or as the selector gives
  bool velocity_units_given = false;   ///< from the selector's units=
  std::string time;                    ///< "seconds since 1950-01-01 00:00:00 (calendar noleap)"
  std::string coordinates;             ///< axes, their names, units and kind
  bool lonlat = false;
  LonLatMetric metric = LonLatMetric::degrees;
  std::string metric_note;         ///< what the lon/lat choice does and its error
  double metric_error = 0;         ///< metres: largest relative east-west length error
  bool longitude_wrapped = false;  ///< a global grid: one column repeated at λ0 + 360°
  std::size_t files = 0;
  std::string fill;  ///< the no-data rules applied, in words
};

/// A series over `files` (each holding one or more steps, in file order, concatenated in time).
/// Every file must hold the same variables on the same grid. Throws IoError (a file cannot be
/// opened) or FormatError naming the file, the variable and the value (wrong variable names,
/// mismatched dimensions, times that do not increase, unknown time units or calendar, velocity
/// units that cannot be related to degrees, a grid too large to address).
std::unique_ptr<TimeSeries> open_netcdf_series(const std::vector<std::filesystem::path>& files,
                                               const NetcdfOptions& options = {});

/// The description of a series opened by open_netcdf_series (nullptr for other series).
const NetcdfDescription* netcdf_description(const TimeSeries& series);

/// The time of `date` ("YYYY-MM-DD[ hh:mm[:ss]][Z|±hh:mm]", in the series' CF calendar) as the
/// series' steps carry it: seconds since its epoch. nullopt for a series not opened by
/// open_netcdf_series or one without a CF time coordinate; FormatError for a malformed date.
std::optional<double> netcdf_time_of_date(const TimeSeries& series, const std::string& date);

/// True for a series opened by open_netcdf_series whose times come from a CF time coordinate
/// (seconds since its epoch, in a calendar), not from dt=.
bool netcdf_has_calendar(const TimeSeries& series);

/// One whole variable of a NetCDF file, unpacked: scale_factor / add_offset applied, and
/// _FillValue, missing_value and values outside valid_min / valid_max / valid_range NaN (the
/// rules of the series above), for readers of layouts other than CF grids (curvilinear models).
struct NetcdfVariable {
  std::vector<std::string> dimensions;  ///< names, slowest first
  std::vector<std::size_t> shape;       ///< lengths, slowest first
  std::vector<double> values;
  std::string units;                    ///< the `units` attribute ("" when absent)
};

/// Reads variable `name` of `file` (classic, 64-bit offset, CDF5 or NetCDF-4). Throws IoError for
/// a missing file, FormatError naming the file and the variable when it is absent (listing the
/// variables there) or holds more than `max_values` values.
NetcdfVariable read_netcdf_variable(const std::filesystem::path& file, const std::string& name,
                                    std::size_t max_values = std::size_t{1} << 31);

/// Metres per second per unit of a velocity `units` attribute ("m/s", "m s-1", "cm/s", ...), or
/// nullopt when it is not a speed.
std::optional<double> metres_per_second(const std::string& units);

}  // namespace orthofront::io
