#include "orthofront/io/netcdf_series.h"

#include <netcdf.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <limits>
#include <mutex>
#include <optional>
#include <set>
#include <sstream>

#include "orthofront/io/child_read.h"
#include "orthofront/io/error.h"
#include "orthofront/io/grid_series.h"
#include "orthofront/io/hdf5_detail.h"
#include "orthofront/io/input_files.h"
#include "orthofront/io/readable_file.h"

namespace orthofront::io {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegree = 180.0 / kPi;
// Points of one step above which a file is refused before anything is allocated.
constexpr std::uint64_t kMaxPoints = std::uint64_t{1} << 32;

std::string lower(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return text;
}

std::string trim(const std::string& text) {
  const std::size_t a = text.find_first_not_of(" \t\r\n");
  if (a == std::string::npos) return {};
  return text.substr(a, text.find_last_not_of(" \t\r\n") + 1 - a);
}

std::string number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.10g", value);
  return text;
}

// One open file; closed on destruction. Every failing call throws naming the file.
class NcFile {
 public:
  explicit NcFile(const std::filesystem::path& path) : path_(path) {
    // NetCDF-4 files are HDF5 files: netCDF-C probes attributes that may be absent, and HDF5
    // would print each miss on stderr.
    detail::silence_hdf5();
    if (const std::string why = why_unreadable(path); !why.empty())
      throw IoError("cannot open '" + path.string() + "': " + why);
    const int status = nc_open(path.c_str(), NC_NOWRITE, &id_);
    if (status != NC_NOERR)
      throw FormatError("cannot read '" + path.string() + "' as NetCDF: " + nc_strerror(status));
    note_input(path);
  }
  NcFile(const NcFile&) = delete;
  NcFile& operator=(const NcFile&) = delete;
  ~NcFile() { nc_close(id_); }

  int id() const { return id_; }
  const std::filesystem::path& path() const { return path_; }
  void check(int status, const std::string& what) const {
    if (status != NC_NOERR)
      throw FormatError("'" + path_.string() + "': " + what + ": " + nc_strerror(status));
  }

  std::string format() const {
    int f = 0;
    check(nc_inq_format(id_, &f), "format");
    switch (f) {
      case NC_FORMAT_CLASSIC:
        return "NetCDF-3 classic";
      case NC_FORMAT_64BIT_OFFSET:
        return "NetCDF-3 64-bit offset";
      case NC_FORMAT_CDF5:
        return "NetCDF CDF5";
      case NC_FORMAT_NETCDF4:
        return "NetCDF-4";
      case NC_FORMAT_NETCDF4_CLASSIC:
        return "NetCDF-4 classic model";
      default:
        return "NetCDF (format " + std::to_string(f) + ")";
    }
  }
  std::optional<int> variable(const std::string& name) const {
    int v = 0;
    if (nc_inq_varid(id_, name.c_str(), &v) != NC_NOERR) return std::nullopt;
    return v;
  }
  std::vector<std::string> variable_names() const {
    int n = 0;
    check(nc_inq_nvars(id_, &n), "variables");
    std::vector<std::string> names;
    for (int v = 0; v < n; ++v) names.push_back(variable_name(v));
    return names;
  }
  std::string variable_name(int v) const {
    char name[NC_MAX_NAME + 1] = {};
    check(nc_inq_varname(id_, v, name), "variable name");
    return name;
  }
  std::vector<int> dimensions(int v) const {
    int n = 0;
    check(nc_inq_varndims(id_, v, &n), "dimensions of " + variable_name(v));
    std::vector<int> dims(static_cast<std::size_t>(n));
    if (n > 0) check(nc_inq_vardimid(id_, v, dims.data()), "dimensions of " + variable_name(v));
    return dims;
  }
  std::string dimension_name(int d) const {
    char name[NC_MAX_NAME + 1] = {};
    check(nc_inq_dimname(id_, d, name), "dimension name");
    return name;
  }
  std::size_t dimension_length(int d) const {
    std::size_t n = 0;
    check(nc_inq_dimlen(id_, d, &n), "dimension length");
    return n;
  }
  bool unlimited(int d) const {
    int n = 0;
    check(nc_inq_unlimdims(id_, &n, nullptr), "unlimited dimensions");
    std::vector<int> ids(static_cast<std::size_t>(std::max(n, 0)));
    if (n > 0) check(nc_inq_unlimdims(id_, &n, ids.data()), "unlimited dimensions");
    return std::find(ids.begin(), ids.end(), d) != ids.end();
  }
  nc_type type(int v) const {
    nc_type t = 0;
    check(nc_inq_vartype(id_, v, &t), "type of " + variable_name(v));
    return t;
  }
  // A text attribute ("" when absent or not text).
  std::string text(int v, const char* name) const {
    nc_type t = 0;
    std::size_t n = 0;
    if (nc_inq_att(id_, v, name, &t, &n) != NC_NOERR || t != NC_CHAR || n > (1u << 16)) return {};
    std::string s(n, '\0');
    if (n > 0) check(nc_get_att_text(id_, v, name, s.data()), std::string("attribute ") + name);
    s.resize(std::strlen(s.c_str()));
    return s;
  }
  // A variable's units: CF's "units", else the spellings other tools write ("Unit", "unit",
  // "UNITS"). Left unread, m/s on a lon/lat grid would be taken for degrees per second.
  std::string units(int v) const {
    if (std::string cf = text(v, "units"); !cf.empty()) return cf;
    int count = 0;
    if (nc_inq_varnatts(id_, v, &count) != NC_NOERR) return {};
    for (int i = 0; i < count; ++i) {
      char name[NC_MAX_NAME + 1] = {};
      if (nc_inq_attname(id_, v, i, name) != NC_NOERR) continue;
      const std::string n = lower(name);
      if (n == "units" || n == "unit") return text(v, name);
    }
    return {};
  }
  // A numeric attribute as doubles (empty when absent or text).
  std::vector<double> numbers(int v, const char* name) const {
    nc_type t = 0;
    std::size_t n = 0;
    if (nc_inq_att(id_, v, name, &t, &n) != NC_NOERR || t == NC_CHAR || t == NC_STRING || n == 0 ||
        n > 4096)
      return {};
    std::vector<double> values(n);
    check(nc_get_att_double(id_, v, name, values.data()), std::string("attribute ") + name);
    return values;
  }
  std::vector<double> read_all(int v, std::size_t count) const {
    std::vector<double> values(count);
    if (count > 0) check(nc_get_var_double(id_, v, values.data()), "reading " + variable_name(v));
    return values;
  }
  void read(int v, const std::vector<std::size_t>& start, const std::vector<std::size_t>& count,
            double* out) const {
    check(nc_get_vara_double(id_, v, start.data(), count.data(), out),
          "reading " + variable_name(v));
  }

 private:
  std::filesystem::path path_;
  int id_ = -1;
};

// ---- CF time -------------------------------------------------------------------------------

enum class Calendar { mixed, proleptic, julian, noleap, all_leap, day360 };

Calendar parse_calendar(const std::string& text, const std::string& where) {
  const std::string c = lower(trim(text));
  if (c.empty() || c == "standard" || c == "gregorian") return Calendar::mixed;
  if (c == "proleptic_gregorian") return Calendar::proleptic;
  if (c == "julian") return Calendar::julian;
  if (c == "noleap" || c == "365_day") return Calendar::noleap;
  if (c == "all_leap" || c == "366_day") return Calendar::all_leap;
  if (c == "360_day") return Calendar::day360;
  throw FormatError(where + ": calendar '" + text +
                    "' is not one CF defines (standard, gregorian, proleptic_gregorian, julian, "
                    "noleap, 365_day, all_leap, 366_day, 360_day)");
}

// Julian day numbers of the two civil calendars.
long long gregorian_day(long long y, long long m, long long d) {
  const long long a = (14 - m) / 12, yy = y + 4800 - a, mm = m + 12 * a - 3;
  return d + (153 * mm + 2) / 5 + 365 * yy + yy / 4 - yy / 100 + yy / 400 - 32045;
}
long long julian_day(long long y, long long m, long long d) {
  const long long a = (14 - m) / 12, yy = y + 4800 - a, mm = m + 12 * a - 3;
  return d + (153 * mm + 2) / 5 + 365 * yy + yy / 4 - 32083;
}

// Days from a fixed origin of the calendar to the date.
double day_number(Calendar c, long long y, int m, int d) {
  static constexpr std::array<int, 12> kNoLeap{0,   31,  59,  90,  120, 151,
                                               181, 212, 243, 273, 304, 334};
  static constexpr std::array<int, 12> kLeap{0, 31, 60, 91, 121, 152, 182, 213, 244, 274, 305, 335};
  switch (c) {
    case Calendar::mixed:
      // Julian before 1582-10-15, Gregorian from then on (the days in between do not exist).
      return static_cast<double>((y < 1582 || (y == 1582 && (m < 10 || (m == 10 && d < 15))))
                                     ? julian_day(y, m, d)
                                     : gregorian_day(y, m, d));
    case Calendar::proleptic:
      return static_cast<double>(gregorian_day(y, m, d));
    case Calendar::julian:
      return static_cast<double>(julian_day(y, m, d));
    case Calendar::noleap:
      return static_cast<double>(y * 365 + kNoLeap[m - 1] + d - 1);
    case Calendar::all_leap:
      return static_cast<double>(y * 366 + kLeap[m - 1] + d - 1);
    case Calendar::day360:
      return static_cast<double>(y * 360 + (m - 1) * 30 + d - 1);
  }
  return 0;
}

struct TimeUnits {
  double seconds_per_unit = 1;
  double epoch_seconds = 0;  // the reference date, seconds from the calendar's origin
  std::string epoch_text;    // as written
};

// "<unit> since <date>[ or T<time>][Z or ±hh[:mm]]".
TimeUnits parse_time_units(const std::string& units, Calendar calendar, const std::string& where) {
  const std::string u = lower(trim(units));
  const std::size_t since = u.find(" since ");
  const auto bad = [&](const std::string& why) {
    return FormatError(where + ": time units '" + units + "' " + why +
                       " (expected e.g. 'days since 1950-01-01 00:00:00')");
  };
  if (since == std::string::npos) throw bad("name no reference date");
  const std::string unit = trim(u.substr(0, since));
  TimeUnits t;
  if (unit == "seconds" || unit == "second" || unit == "secs" || unit == "sec" || unit == "s")
    t.seconds_per_unit = 1;
  else if (unit == "minutes" || unit == "minute" || unit == "mins" || unit == "min")
    t.seconds_per_unit = 60;
  else if (unit == "hours" || unit == "hour" || unit == "hrs" || unit == "hr" || unit == "h")
    t.seconds_per_unit = 3600;
  else if (unit == "days" || unit == "day" || unit == "d")
    t.seconds_per_unit = 86400;
  else
    throw bad("have the unit '" + unit +
              "' (seconds, minutes, hours or days; months and years "
              "have no fixed length)");
  t.epoch_text = trim(units.substr(since + 7));
  long long y = 0;
  int mo = 0, d = 0, h = 0, mi = 0, used = 0;
  double s = 0;
  std::string rest = t.epoch_text;
  // ISO 8601's 'T' between date and time.
  if (const std::size_t t_at = rest.find_first_of("Tt");
      t_at != std::string::npos && t_at > 0 &&
      std::isdigit(static_cast<unsigned char>(rest[t_at - 1])))
    rest[t_at] = ' ';
  if (std::sscanf(rest.c_str(), "%lld-%d-%d%n", &y, &mo, &d, &used) != 3 || mo < 1 || mo > 12 ||
      d < 1 || d > 31 || (calendar == Calendar::day360 && d > 30))
    throw bad("have a reference date that is not YYYY-MM-DD");
  rest = trim(rest.substr(static_cast<std::size_t>(used)));
  if (!rest.empty() && std::isdigit(static_cast<unsigned char>(rest[0]))) {
    int n = 0;
    if (std::sscanf(rest.c_str(), "%d:%d%n", &h, &mi, &n) < 2) throw bad("have a bad time of day");
    rest = rest.substr(static_cast<std::size_t>(n));
    if (!rest.empty() && rest[0] == ':') {
      int m2 = 0;
      if (std::sscanf(rest.c_str(), ":%lf%n", &s, &m2) != 1) throw bad("have bad seconds");
      rest = rest.substr(static_cast<std::size_t>(m2));
    }
    rest = trim(rest);
  }
  // A time zone: Z, UTC or an offset (±hh[:mm] or ±hhmm), subtracted to give UTC.
  double zone = 0;
  if (!rest.empty()) {
    const std::string z = lower(rest);
    if (z == "z" || z == "utc" || z == "gmt") {
      zone = 0;
    } else if (z[0] == '+' || z[0] == '-') {
      int zh = 0, zm = 0;
      if (z.find(':') != std::string::npos) {
        if (std::sscanf(z.c_str() + 1, "%d:%d", &zh, &zm) < 1) throw bad("have a bad time zone");
      } else {
        const int v = std::atoi(z.c_str() + 1);
        zh = z.size() > 3 ? v / 100 : v;
        zm = z.size() > 3 ? v % 100 : 0;
      }
      zone = (z[0] == '-' ? -1.0 : 1.0) * (zh * 3600.0 + zm * 60.0);
    } else {
      throw bad("end in '" + rest + "'");
    }
  }
  t.epoch_seconds = day_number(calendar, y, mo, d) * 86400.0 + h * 3600.0 + mi * 60.0 + s - zone;
  return t;
}

// ---- Velocity units -------------------------------------------------------------------------

// Metres per second per unit of the file's velocity, or nullopt when the units are not a speed.
std::optional<double> speed_unit(const std::string& units) {
  std::string u = lower(trim(units));
  std::string compact;
  for (const char c : u)
    if (c != ' ' && c != '*' && c != '^' && c != '.') compact += c;
  static const char* const kMetres[] = {
      "m/s",           "ms-1",           "msec-1",          "meter/second",  "meter/s", "metre/s",
      "meters/second", "metre/second",   "metres/second",   "meters/sec",
      "metersecond-1", "meterssecond-1", "metrespersecond", "meterspersecond"};
  static const char* const kCentimetres[] = {
      "cm/s",           "cms-1",    "centimeter/second", "centimeters/second",
      "centimetre/second", "centimeter/s", "centimetre/s", "cm/sec"};
  for (const char* m : kMetres)
    if (compact == m) return 1.0;
  for (const char* m : kCentimetres)
    if (compact == m) return 0.01;
  return std::nullopt;
}

// Metres in one unit of a coordinate's length units, or nullopt when they are not a length.
std::optional<double> length_unit(const std::string& units) {
  const std::string u = lower(trim(units));
  if (u == "m" || u == "metre" || u == "metres" || u == "meter" || u == "meters") return 1.0;
  if (u == "km" || u == "kilometre" || u == "kilometres" || u == "kilometer" ||
      u == "kilometers")
    return 1000.0;
  if (u == "cm" || u == "centimetre" || u == "centimetres" || u == "centimeter" ||
      u == "centimeters")
    return 0.01;
  if (u == "mm" || u == "millimetre" || u == "millimetres" || u == "millimeter" ||
      u == "millimeters")
    return 0.001;
  return std::nullopt;
}

// ---- Variables ------------------------------------------------------------------------------

// CF standard names of the components, by axis.
const std::vector<std::vector<std::string>>& standard_names() {
  static const std::vector<std::vector<std::string>> names = {
      {"eastward_sea_water_velocity", "surface_eastward_sea_water_velocity",
       "baroclinic_eastward_sea_water_velocity", "barotropic_eastward_sea_water_velocity",
       "eastward_wind", "x_wind", "sea_water_x_velocity", "x_sea_water_velocity",
       "eastward_sea_ice_velocity"},
      {"northward_sea_water_velocity", "surface_northward_sea_water_velocity",
       "baroclinic_northward_sea_water_velocity", "barotropic_northward_sea_water_velocity",
       "northward_wind", "y_wind", "sea_water_y_velocity", "y_sea_water_velocity",
       "northward_sea_ice_velocity"},
      {"upward_sea_water_velocity", "upward_air_velocity", "sea_water_z_velocity"}};
  return names;
}

struct NoDataRules {
  std::optional<double> fill;
  std::vector<double> missing;
  double valid_min = -std::numeric_limits<double>::infinity();
  double valid_max = std::numeric_limits<double>::infinity();
  double scale = 1, offset = 0;
  bool is_no_data(double packed) const {
    if (std::isnan(packed)) return true;
    if (fill && packed == *fill) return true;
    for (const double m : missing)
      if (packed == m) return true;
    return packed < valid_min || packed > valid_max;
  }
};

NoDataRules no_data_rules(const NcFile& f, int v) {
  NoDataRules r;
  if (const auto x = f.numbers(v, "_FillValue"); !x.empty()) {
    r.fill = x[0];
  } else {
    // netCDF's default fill of the type applies where no _FillValue is given.
    switch (f.type(v)) {
      case NC_FLOAT:
        r.fill = static_cast<double>(NC_FILL_FLOAT);
        break;
      case NC_DOUBLE:
        r.fill = NC_FILL_DOUBLE;
        break;
      case NC_SHORT:
        r.fill = NC_FILL_SHORT;
        break;
      case NC_INT:
        r.fill = NC_FILL_INT;
        break;
      default:
        break;
    }
  }
  r.missing = f.numbers(v, "missing_value");
  if (const auto x = f.numbers(v, "valid_range"); x.size() >= 2) {
    r.valid_min = x[0];
    r.valid_max = x[1];
  }
  if (const auto x = f.numbers(v, "valid_min"); !x.empty()) r.valid_min = x[0];
  if (const auto x = f.numbers(v, "valid_max"); !x.empty()) r.valid_max = x[0];
  if (const auto x = f.numbers(v, "scale_factor"); !x.empty()) r.scale = x[0];
  if (const auto x = f.numbers(v, "add_offset"); !x.empty()) r.offset = x[0];
  return r;
}

// One spatial axis of the grid, in file order (before flips).
struct Axis {
  std::string dimension, units, standard_name;
  std::size_t length = 0;
  std::vector<double> coordinates;  // increasing after the flip
  bool flipped = false;             // stored decreasing
  bool from_index = false;          // no coordinate variable
  bool positive_down = false;       // CF positive="down": depth, increasing downward
};

bool is_longitude(const Axis& a) {
  const std::string u = lower(a.units), n = lower(a.dimension);
  return a.standard_name == "longitude" || u == "degrees_east" || u == "degree_east" ||
         u == "degree_e" || u == "degrees_e" ||
         ((n == "lon" || n == "longitude" || n == "nav_lon") && u.rfind("degree", 0) == 0);
}
bool is_latitude(const Axis& a) {
  const std::string u = lower(a.units), n = lower(a.dimension);
  return a.standard_name == "latitude" || u == "degrees_north" || u == "degree_north" ||
         u == "degree_n" || u == "degrees_n" ||
         ((n == "lat" || n == "latitude" || n == "nav_lat") && u.rfind("degree", 0) == 0);
}

// Variables that place a grid's points on the Earth: named by the velocity's CF `coordinates`
// attribute, or by a longitude/latitude standard name, units or a usual name (POP's ULONG,
// NEMO's nav_lon, ROMS's lon_rho, WRF's XLONG, ...).
bool names_position(const NcFile& f, int v, const std::vector<std::string>& listed) {
  const std::string name = f.variable_name(v);
  if (std::find(listed.begin(), listed.end(), name) != listed.end()) return true;
  const std::string sn = f.text(v, "standard_name"), u = lower(f.units(v)), n = lower(name);
  if (sn == "longitude" || sn == "latitude" || sn == "grid_longitude" || sn == "grid_latitude")
    return true;
  if (u == "degrees_east" || u == "degree_east" || u == "degrees_north" || u == "degree_north")
    return true;
  for (const char* usual : {"lon", "lat", "longitude", "latitude", "nav_lon", "nav_lat", "ulon",
                            "ulat", "tlon", "tlat", "ulong", "tlong", "glamt", "gphit", "xlong",
                            "xlat", "lon_rho", "lat_rho", "lon_u", "lat_u", "lon_v", "lat_v",
                            "geolon", "geolat"})
    if (n == usual) return true;
  return false;
}

// A curvilinear grid (2D longitude and latitude, as ocean and atmosphere models write them) read
// by index would integrate m/s as cells per second: it is refused, naming the variables.
void refuse_curvilinear(const NcFile& f, int velocity, const std::vector<std::string>& spatial) {
  std::vector<std::string> listed;
  {
    std::istringstream words(f.text(velocity, "coordinates"));
    for (std::string w; words >> w;) listed.push_back(w);
  }
  std::string found;
  int count = 0;
  for (const std::string& name : f.variable_names()) {
    const int v = *f.variable(name);
    if (v == velocity || !names_position(f, v, listed)) continue;
    std::vector<std::string> dims;
    std::size_t shared = 0;
    for (const int d : f.dimensions(v)) {
      dims.push_back(f.dimension_name(d));
      if (std::find(spatial.begin(), spatial.end(), dims.back()) != spatial.end()) ++shared;
    }
    if (shared < 2) continue;  // a 1D coordinate, or a variable of another grid
    std::string list;
    for (const std::string& d : dims) list += (list.empty() ? "" : ", ") + d;
    found += (found.empty() ? "'" : ", '") + name + "'(" + list + ")";
    ++count;
  }
  if (count == 0) return;
  throw FormatError(
      "'" + f.path().string() + "': variable '" + f.variable_name(velocity) +
      "' lies on a curvilinear grid: its points are placed by " + found +
      ", not by one coordinate per axis. orthofront reads NetCDF grids whose axes are 1D "
      "coordinate variables (uniform or rectilinear, in metres or longitude/latitude); read by "
      "index, its velocities would be taken as cells per second. Resample it onto a rectilinear "
      "grid first (POP output: datasets-scripts' orthofront-pop-convert)");
}

// Everything one file contributes: its steps and where each component lives.
struct FileLayout {
  std::filesystem::path path;
  std::size_t steps = 1;
  bool has_time_dimension = false;
  std::vector<double> times;  // seconds since the series' epoch
};

class NetcdfSeries final : public TimeSeries {
 public:
  NetcdfSeries(const std::vector<std::filesystem::path>& files, const NetcdfOptions& options);

  std::size_t step_count() const override { return times_.size(); }
  double time(std::size_t step) const override { return times_.at(step); }
  const GridGeometry& geometry() const override { return geometry_; }
  int components() const override { return components_; }
  std::string describe() const override;
  RawStep read_raw(std::size_t step) const override;
  void decode(const RawStep& raw, std::span<float> values) const override;
  const NetcdfDescription& description() const { return description_; }
  bool has_calendar() const { return epoch_.has_value(); }
  std::optional<double> time_of_date(const std::string& date) const {
    if (!epoch_) return std::nullopt;
    return parse_time_units("seconds since " + date, calendar_, "date '" + date + "'")
               .epoch_seconds -
           *epoch_;
  }

 private:
  void open_first(const NcFile& f);
  std::vector<int> component_variables(const NcFile& f) const;
  void read_times(const NcFile& f, FileLayout& layout, bool first);

  NetcdfOptions options_;
  NetcdfDescription description_;
  std::vector<FileLayout> files_;
  std::vector<std::size_t> first_step_;  // per file
  std::vector<double> times_;
  GridGeometry geometry_;
  int components_ = 2;
  std::vector<std::string> variables_;  // components present in the files (u, v[, w])
  std::vector<NoDataRules> rules_;      // per variable
  std::vector<Axis> axes_;              // spatial, file order: slowest first (z, y, x)
  std::size_t source_points_ = 0;       // points of one variable in one step
  double velocity_factor_ = 1;          // to m/s (lon/lat only)
  // Per output component (x, y, z): from the velocities' units to the axis's units per second
  // (a grid in km with velocities in m/s, one in metres with cm/s); lon/lat's x and y use the
  // sphere's factors instead.
  std::array<double, 3> axis_factor_{1, 1, 1};
  // -1 where the vertical axis is depth (positive down) and w is upward, as CF's vertical
  // velocities are: a particle rising moves to smaller depth.
  double vertical_sign_ = 1;
  Calendar calendar_ = Calendar::mixed;
  std::string calendar_text_;
  std::optional<double> epoch_;  // the first file's reference, calendar seconds
  bool lonlat_ = false, wrap_ = false;
  std::vector<double> latitude_;  // degrees, per y index of the output grid
  std::string time_variable_;
  mutable std::unique_ptr<NcFile> open_;  // the file read last (read_raw is single-threaded)
};

NetcdfSeries::NetcdfSeries(const std::vector<std::filesystem::path>& files,
                           const NetcdfOptions& options)
    : options_(options) {
  if (files.empty()) throw InvalidArgument("a NetCDF series needs at least one file");
  if (!(options.earth_radius > 0 && std::isfinite(options.earth_radius)))
    throw InvalidArgument("NetCDF: radius must be > 0 metres, got " + number(options.earth_radius));
  std::vector<std::pair<std::string, std::size_t>> formats;  // each format and its file count
  for (std::size_t i = 0; i < files.size(); ++i) {
    const NcFile f(files[i]);
    if (i == 0) open_first(f);
    const std::string format = f.format();
    auto known = std::find_if(formats.begin(), formats.end(),
                              [&](const auto& entry) { return entry.first == format; });
    if (known == formats.end())
      formats.emplace_back(format, 1);
    else
      ++known->second;
    FileLayout layout;
    layout.path = files[i];
    // The same variables on the same grid in every file.
    const std::vector<int> vars = component_variables(f);
    for (std::size_t c = 0; c < vars.size(); ++c) {
      const std::vector<int> dims = f.dimensions(vars[c]);
      std::size_t spatial = 0;
      for (std::size_t k = 0; k < dims.size(); ++k) {
        const std::size_t n = f.dimension_length(dims[k]);
        if (k == 0 && !time_variable_.empty() && f.dimension_name(dims[k]) == time_variable_) {
          layout.has_time_dimension = true;
          layout.steps = n;
          continue;
        }
        if (n == 1 && dims.size() - k > 1) continue;  // a singleton level (surface products)
        // Same lengths and names, in the same order (u and v transposed on a square grid would
        // otherwise pass).
        if (spatial >= axes_.size() || axes_[spatial].length != n ||
            axes_[spatial].dimension != f.dimension_name(dims[k]))
          throw FormatError("'" + files[i].string() + "': variable '" + variables_[c] +
                            "' has dimension '" + f.dimension_name(dims[k]) + "' of length " +
                            std::to_string(n) + " where '" + files.front().string() + "' has " +
                            (spatial < axes_.size()
                                 ? "'" + axes_[spatial].dimension + "' of length " +
                                       std::to_string(axes_[spatial].length)
                                 : std::string("no further dimension")) +
                            (c > 0 ? " (its components lie on different grids, as on a "
                                     "staggered C grid; orthofront reads components that "
                                     "share one grid: interpolate them onto it first)"
                                   : ""));
        ++spatial;
      }
      if (spatial != axes_.size())
        throw FormatError("'" + files[i].string() + "': variable '" + variables_[c] + "' has " +
                          std::to_string(spatial) + " spatial dimensions where '" +
                          files.front().string() + "' has " + std::to_string(axes_.size()));
    }
    read_times(f, layout, i == 0);
    files_.push_back(std::move(layout));
  }
  if (formats.size() > 1) {
    description_.format = "mixed:";
    for (const auto& [format, count] : formats)
      description_.format += (format == formats.front().first ? " " : ", ") + format + " (" +
                             std::to_string(count) + (count == 1 ? " file)" : " files)");
  }
  for (const FileLayout& l : files_) {
    first_step_.push_back(times_.size());
    times_.insert(times_.end(), l.times.begin(), l.times.end());
  }
  for (std::size_t s = 1; s < times_.size(); ++s)
    if (!(times_[s] > times_[s - 1])) {
      std::size_t file = 0;
      while (file + 1 < first_step_.size() && first_step_[file + 1] <= s) ++file;
      throw FormatError("'" + files_[file].path.string() + "': time " + number(times_[s]) +
                        " s of step " + std::to_string(s) + " does not come after " +
                        number(times_[s - 1]) +
                        " s (files are read in the order given; a glob "
                        "sorts them by name)");
    }
  if (times_.empty())
    throw FormatError("'" + files.front().string() + "': the time dimension is empty");
  description_.files = files_.size();
}

std::vector<int> NetcdfSeries::component_variables(const NcFile& f) const {
  std::vector<int> ids;
  for (const std::string& name : variables_) {
    const auto v = f.variable(name);
    if (!v) {
      std::string known;
      for (const std::string& n : f.variable_names()) known += (known.empty() ? "" : ", ") + n;
      throw FormatError("'" + f.path().string() + "': no variable '" + name +
                        "' (variables: " + known + ")");
    }
    ids.push_back(*v);
  }
  return ids;
}

void NetcdfSeries::open_first(const NcFile& f) {
  description_.format = f.format();
  // The components: named, or by CF standard_name, or the names u, v, w.
  if (!options_.variables.empty()) {
    if (options_.variables.size() < 2 || options_.variables.size() > 3)
      throw InvalidArgument("NetCDF: give two or three variable names (u,v[,w]), got " +
                            std::to_string(options_.variables.size()));
    variables_ = options_.variables;
    description_.found_by = "named";
  } else {
    const auto names = f.variable_names();
    // u, then v, then (optionally) w: stop at the first axis with no match.
    for (const auto& wanted : standard_names()) {
      std::optional<std::string> match;
      for (std::size_t v = 0; v < names.size() && !match; ++v)
        if (const std::string sn = f.text(static_cast<int>(v), "standard_name");
            std::find(wanted.begin(), wanted.end(), sn) != wanted.end())
          match = names[v];
      if (!match) break;
      variables_.push_back(*match);
    }
    description_.found_by = "CF standard_name";
    if (variables_.size() < 2) {
      variables_.clear();
      for (const char* n : {"u", "v", "w"})
        if (f.variable(n)) variables_.emplace_back(n);
      description_.found_by = "variable names";
    }
    if (variables_.size() < 2) {
      std::string known;
      for (const std::string& n : names) known += (known.empty() ? "" : ", ") + n;
      throw FormatError("'" + f.path().string() +
                        "': no velocity components found by CF standard_name "
                        "(eastward_sea_water_velocity, x_wind, ...) or named u, v; name them "
                        "(FILE.nc:U,V[,W]) among: " +
                        known);
    }
  }
  description_.variables = variables_;
  const std::vector<int> vars = component_variables(f);

  // Time: the leading dimension of the first component, when it is unlimited or has a CF time
  // coordinate (units "... since ...").
  const std::vector<int> dims = f.dimensions(vars[0]);
  std::size_t first_spatial = 0;
  if (!dims.empty()) {
    const std::string name = f.dimension_name(dims[0]);
    const auto coordinate = f.variable(name);
    const bool cf_time =
        coordinate && f.units(*coordinate).find(" since ") != std::string::npos;
    if (cf_time || f.unlimited(dims[0]) || lower(name) == "time" || lower(name) == "t") {
      time_variable_ = name;
      first_spatial = 1;
    }
  }
  for (std::size_t k = first_spatial; k < dims.size(); ++k) {
    const std::size_t n = f.dimension_length(dims[k]);
    if (n == 1 && dims.size() - k > 1) continue;
    Axis a;
    a.dimension = f.dimension_name(dims[k]);
    a.length = n;
    if (const auto cv = f.variable(a.dimension)) {
      const std::vector<int> cdims = f.dimensions(*cv);
      if (cdims.size() != 1)
        throw FormatError("'" + f.path().string() + "': coordinate variable '" + a.dimension +
                          "' is not one-dimensional (a curvilinear grid: resample it first, as "
                          "datasets-scripts/orthofront-pop-convert does)");
      // Read whole below: it must be exactly as long as the dimension it labels.
      if (f.dimension_length(cdims[0]) != n)
        throw FormatError("'" + f.path().string() + "': coordinate variable '" + a.dimension +
                          "' has " + std::to_string(f.dimension_length(cdims[0])) +
                          " values for a dimension of " + std::to_string(n));
      a.units = f.units(*cv);
      a.standard_name = f.text(*cv, "standard_name");
      a.positive_down = lower(trim(f.text(*cv, "positive"))) == "down";
      a.coordinates = f.read_all(*cv, n);
    } else {
      a.from_index = true;
      for (std::size_t i = 0; i < n; ++i) a.coordinates.push_back(static_cast<double>(i));
    }
    axes_.push_back(std::move(a));
  }
  description_.velocity_units =
      options_.velocity_units.empty() ? f.units(vars[0]) : options_.velocity_units;
  description_.velocity_units_given = !options_.velocity_units.empty();
  {
    std::vector<std::string> spatial;
    for (const Axis& a : axes_) spatial.push_back(a.dimension);
    const bool lonlat_axes = axes_.size() >= 2 && is_longitude(axes_.back()) &&
                             is_latitude(axes_[axes_.size() - 2]);
    // 2D longitude and latitude beside 1D lon/lat axes repeat them, and beside axes in metres
    // (a projected grid) they are auxiliary; beside anything else they are the grid.
    const bool metric_axes = axes_.size() >= 2 && length_unit(axes_.back().units) &&
                             length_unit(axes_[axes_.size() - 2].units);
    if (!lonlat_axes && !metric_axes) refuse_curvilinear(f, vars[0], spatial);
    // Index positions with velocities in m/s would be read as cells per second.
    const std::string& velocity_units = description_.velocity_units;
    for (const Axis& a : axes_)
      if (a.from_index && speed_unit(velocity_units))
        throw FormatError("'" + f.path().string() + "': dimension '" + a.dimension +
                          "' has no coordinate variable, so its points are at index 0, 1, ..., "
                          "but '" + variables_[0] + "' is in " + velocity_units +
                          ": read so, it would move in cells per second. Add a coordinate "
                          "variable '" + a.dimension + "(" + a.dimension +
                          ")' in metres or degrees (or give the velocities in cells per second "
                          "without units)");
  }
  if (axes_.size() < 2 || axes_.size() > 3)
    throw FormatError("'" + f.path().string() + "': variable '" + variables_[0] + "' has " +
                      std::to_string(axes_.size()) +
                      " spatial dimensions of more than one point; a vector field needs 2 or 3");
  if (variables_.size() == 3 && axes_.size() == 2)
    throw FormatError("'" + f.path().string() + "': three components ('" + variables_[2] +
                      "' too) on a 2D grid");
  std::uint64_t points = 1;
  for (Axis& a : axes_) {
    if (a.length < 2)
      throw FormatError("'" + f.path().string() + "': dimension '" + a.dimension +
                        "' has one point; a grid needs two along every axis");
    points *= a.length;
    if (points > kMaxPoints)
      throw FormatError("'" + f.path().string() + "': variable '" + variables_[0] +
                        "' has more than 2^32 points per step; not read");
    for (std::size_t i = 0; i < a.length; ++i)
      if (!std::isfinite(a.coordinates[i]))
        throw FormatError("'" + f.path().string() + "': coordinate '" + a.dimension + "' [" +
                          std::to_string(i) + "] is " + number(a.coordinates[i]));
    const bool increasing = a.coordinates[1] > a.coordinates[0];
    for (std::size_t i = 1; i < a.length; ++i)
      if ((a.coordinates[i] > a.coordinates[i - 1]) != increasing ||
          a.coordinates[i] == a.coordinates[i - 1])
        throw FormatError("'" + f.path().string() + "': coordinate '" + a.dimension +
                          "' is not strictly monotonic at index " + std::to_string(i) + " (" +
                          number(a.coordinates[i - 1]) + ", " + number(a.coordinates[i]) + ")");
    if (!increasing) {
      std::reverse(a.coordinates.begin(), a.coordinates.end());
      a.flipped = true;
    }
  }
  source_points_ = points;
  // A header may declare far more values than the file holds (a damaged or hostile file):
  // before anything is allocated, the components of one step must fit in the file, compressed
  // by deflate at most (it expands at most ~1,032 times).
  {
    std::uint64_t declared = 0;
    for (const int v : vars) {
      std::size_t size = 0;
      f.check(nc_inq_type(f.id(), f.type(v), nullptr, &size), "type of " + f.variable_name(v));
      declared += points * size;
    }
    std::error_code ec;
    const std::uint64_t file_bytes = std::filesystem::file_size(f.path(), ec);
    constexpr std::uint64_t kDeflateExpansion = 1032, kSlack = 1u << 20;
    if (!ec && declared > kDeflateExpansion * file_bytes + kSlack)
      throw FormatError("'" + f.path().string() + "': its header declares " +
                        std::to_string(points) + " points per step for each of " +
                        std::to_string(vars.size()) + " components (" +
                        std::to_string(declared >> 20) + " MiB a step), more than its " +
                        std::to_string(file_bytes) +
                        " bytes can hold even compressed; a damaged header? Not read");
  }
  for (const int v : vars) rules_.push_back(no_data_rules(f, v));

  // The output grid: x fastest (the file's last dimension).
  const std::size_t d = axes_.size();
  const Axis& ax = axes_[d - 1];
  const Axis& ay = axes_[d - 2];
  lonlat_ = is_longitude(ax) && is_latitude(ay);
  // A choice that cannot apply is refused rather than ignored.
  if (!lonlat_ && options_.lonlat == LonLatMetric::metres)
    throw InvalidArgument("'" + f.path().string() + "': lonlat=metres, but its grid is not " +
                          "longitude/latitude (x = '" + ax.dimension + "'" +
                          (ax.units.empty() ? "" : " in " + ax.units) + ", y = '" + ay.dimension +
                          "'" + (ay.units.empty() ? "" : " in " + ay.units) +
                          "); leave lonlat= out for a grid in metres");
  description_.lonlat = lonlat_;
  description_.metric = options_.lonlat;
  geometry_.dimension = static_cast<int>(d);
  components_ = d == 3 ? 3 : 2;
  std::array<std::vector<double>, 3> coordinates;
  coordinates[0] = ax.coordinates;
  coordinates[1] = ay.coordinates;
  if (d == 3) coordinates[2] = axes_[0].coordinates;
  if (d == 3 && vars.size() == 3 && axes_[0].positive_down &&
      lower(f.text(vars[2], "standard_name")).find("downward") == std::string::npos)
    vertical_sign_ = -1;
  if (lonlat_) {
    const std::optional<double> factor = speed_unit(description_.velocity_units);
    if (!factor)
      throw FormatError("'" + f.path().string() + "': variable '" + variables_[0] +
                        "' has units '" + description_.velocity_units +
                        "' on a lon/lat grid; only m/s and cm/s can be related to degrees (if the file "
                        "does not say, give them: FILE.nc:...,units=m/s)");
    velocity_factor_ = *factor;
    latitude_ = ay.coordinates;
    const std::vector<double>& lon = ax.coordinates;
    const double step = (lon.back() - lon.front()) / static_cast<double>(lon.size() - 1);
    // A global grid (its columns cover 360° and one more would repeat the first): close the seam
    // by repeating the first column one period on.
    wrap_ = std::abs(step * static_cast<double>(lon.size()) - 360.0) < 1e-6 * 360.0;
    description_.longitude_wrapped = wrap_;
    if (wrap_) coordinates[0].push_back(lon.front() + 360.0);
    const double R = options_.earth_radius;
    if (options_.lonlat == LonLatMetric::metres) {
      const double ref = 0.5 * (ay.coordinates.front() + ay.coordinates.back());
      double worst = 0;
      for (const double phi : ay.coordinates)
        worst = std::max(worst, std::abs(std::cos(ref / kDegree) / std::cos(phi / kDegree) - 1));
      description_.metric_error = worst;
      for (double& x : coordinates[0]) x = R * std::cos(ref / kDegree) * x / kDegree;
      for (double& y : coordinates[1]) y = R * y / kDegree;
      description_.metric_note = "positions in metres (x = R cos(" + number(ref) +
                                 "°) lon, y = R lat, R = " + number(R) +
                                 " m), velocities in m/s; east-west lengths are off by up to " +
                                 number(100 * worst) + " % away from latitude " + number(ref) + "°";
    } else {
      description_.metric_note =
          "positions in degrees; velocities converted to degrees per second on a sphere of "
          "radius " +
          number(R) +
          " m (u / (R cos lat), v / R), exact on the sphere; no data "
          "within 0.1° of a pole";
    }
  }
  // Velocities in a speed unit move positions in the axes' own length units; an axis whose
  // units are not a length cannot be related to them.
  {
    const std::optional<double> speed = speed_unit(description_.velocity_units);
    const auto per_second = [&](const Axis& a) -> double {
      if (!speed) return 1.0;                 // unitless velocities: axis units per second
      if (a.units.empty()) return *speed;     // a coordinate without units: metres
      const std::optional<double> metres = length_unit(a.units);
      if (!metres)
        throw FormatError("'" + f.path().string() + "': axis '" + a.dimension + "' is in '" +
                          a.units + "', not a length, but '" + variables_[0] + "' is in " +
                          description_.velocity_units +
                          ": the two cannot be related (a longitude or latitude axis needs CF "
                          "units degrees_east / degrees_north or its standard_name)");
      return *speed / *metres;
    };
    if (!lonlat_) {
      axis_factor_[0] = per_second(ax);
      axis_factor_[1] = per_second(ay);
    }
    if (d == 3) axis_factor_[2] = per_second(axes_[0]);
  }
  // Uniform axes stay uniform (cheaper lookups); others are rectilinear.
  bool uniform = true;
  for (std::size_t a = 0; a < d; ++a) {
    const auto& c = coordinates[a];
    const double step = (c.back() - c.front()) / static_cast<double>(c.size() - 1);
    for (std::size_t i = 1; i < c.size(); ++i)
      if (std::abs((c[i] - c[i - 1]) - step) > 1e-6 * std::abs(step)) uniform = false;
  }
  for (std::size_t a = 0; a < d; ++a) {
    geometry_.size[a] = static_cast<std::int64_t>(coordinates[a].size());
    geometry_.origin[static_cast<int>(a)] = coordinates[a].front();
    geometry_.spacing[static_cast<int>(a)] = (coordinates[a].back() - coordinates[a].front()) /
                                             static_cast<double>(coordinates[a].size() - 1);
    if (!uniform) geometry_.axes[a] = coordinates[a];
  }
  if (d == 2) geometry_.spacing[2] = 1;

  std::string text;
  for (std::size_t a = d; a-- > 0;) {
    const Axis& axis = axes_[a];
    const char* name = a == d - 1 ? "x" : a == d - 2 ? "y" : "z";
    text += std::string(text.empty() ? "" : "; ") + name + " = '" + axis.dimension + "' (" +
            std::to_string(axis.length) + ", " + number(axis.coordinates.front()) + " to " +
            number(axis.coordinates.back()) + (axis.units.empty() ? "" : " " + axis.units) +
            (axis.flipped ? ", stored decreasing" : "") +
            (axis.from_index ? ", no coordinate variable: index" : "") +
            (axis.positive_down ? ", positive down" : "") + ")";
  }
  description_.coordinates = text + (uniform ? "; uniform" : "; rectilinear") +
                             (wrap_ ? "; global in longitude, seam closed" : "") +
                             (vertical_sign_ < 0 ? "; z is depth: upward w moves to smaller z"
                                                 : "");
  for (std::size_t a = lonlat_ ? 2 : 0; a < d; ++a)
    if (axis_factor_[a] != 1.0)
      description_.coordinates += std::string("; ") + "xyz"[a] + " velocities " +
                                  description_.velocity_units + " x " + number(axis_factor_[a]) +
                                  " (to the axis's units per second)";
  std::string fill;
  const NoDataRules& r = rules_[0];
  if (r.fill) fill += "_FillValue " + number(*r.fill);
  for (const double m : r.missing)
    fill += (fill.empty() ? "" : ", ") + std::string("missing_value ") + number(m);
  if (std::isfinite(r.valid_min) || std::isfinite(r.valid_max))
    fill += (fill.empty() ? "" : ", ") + std::string("valid range [") + number(r.valid_min) + ", " +
            number(r.valid_max) + "]";
  if (r.scale != 1 || r.offset != 0)
    fill += (fill.empty() ? "" : "; ") + std::string("unpacked by scale ") + number(r.scale) +
            ", offset " + number(r.offset);
  description_.fill = fill.empty() ? "NaN only" : fill + "; NaN";
}

void NetcdfSeries::read_times(const NcFile& f, FileLayout& layout, bool first) {
  const std::string where = "'" + f.path().string() + "'";
  const auto tv = time_variable_.empty() ? std::nullopt : f.variable(time_variable_);
  const std::string units = tv ? f.units(*tv) : std::string();
  if (!tv || units.find(" since ") == std::string::npos) {
    if (!(options_.dt > 0))
      throw FormatError(where + ": no CF time coordinate (a variable '" +
                        (time_variable_.empty() ? std::string("time") : time_variable_) +
                        "' with units '<unit> since <date>'); give the step with dt=SECONDS "
                        "(FILE.nc:...,dt=86400)");
    std::size_t before = 0;  // steps of the files read so far
    for (const FileLayout& l : files_) before += l.steps;
    for (std::size_t s = 0; s < layout.steps; ++s)
      layout.times.push_back(static_cast<double>(before + s) * options_.dt);
    if (first)
      description_.time = "seconds, dt = " + number(options_.dt) + " (no CF time coordinate)";
    return;
  }
  const std::string calendar_text = f.text(*tv, "calendar");
  const Calendar calendar =
      parse_calendar(calendar_text, where + " time variable '" + time_variable_ + "'");
  if (first) {
    calendar_ = calendar;
    calendar_text_ = calendar_text.empty() ? "standard" : calendar_text;
  } else if (calendar != calendar_) {
    throw FormatError(where + ": calendar '" + calendar_text + "' differs from the first file's '" +
                      calendar_text_ + "'");
  }
  const TimeUnits t =
      parse_time_units(units, calendar, where + " time variable '" + time_variable_ + "'");
  if (!epoch_) {
    epoch_ = t.epoch_seconds;
    description_.time = "seconds since " + t.epoch_text + " (calendar " + calendar_text_ +
                        "; the file says '" + units + "')";
  }
  const std::vector<int> dims = f.dimensions(*tv);
  if (dims.size() != 1)
    throw FormatError(where + ": time variable '" + time_variable_ + "' is not one-dimensional");
  const std::size_t n = f.dimension_length(dims[0]);
  if (layout.has_time_dimension && n != layout.steps)
    throw FormatError(where + ": time variable '" + time_variable_ + "' has " + std::to_string(n) +
                      " values for " + std::to_string(layout.steps) + " steps");
  const std::vector<double> values = f.read_all(*tv, n);
  if (!layout.has_time_dimension) {
    if (n != 1)
      throw FormatError(where + ": variable '" + variables_[0] + "' has no time dimension but '" +
                        time_variable_ + "' holds " + std::to_string(n) + " times");
    layout.steps = 1;
  }
  for (const double v : values) {
    if (!std::isfinite(v))
      throw FormatError(where + ": time variable '" + time_variable_ + "' holds " + number(v));
    layout.times.push_back(t.epoch_seconds - *epoch_ + v * t.seconds_per_unit);
  }
}

std::string NetcdfSeries::describe() const {
  std::string vars;
  for (const std::string& v : variables_) vars += (vars.empty() ? "" : ", ") + v;
  return description_.format + " " +
         (files_.size() == 1 ? "'" + files_.front().path.string() + "'"
                             : std::to_string(files_.size()) + " files from '" +
                                   files_.front().path.string() + "'") +
         ", variables " + vars;
}

RawStep NetcdfSeries::read_raw(std::size_t step) const {
  if (step >= times_.size())
    throw InvalidArgument("NetCDF series: step " + std::to_string(step) + " of " +
                          std::to_string(times_.size()));
  std::size_t file = 0;
  while (file + 1 < first_step_.size() && first_step_[file + 1] <= step) ++file;
  const FileLayout& layout = files_[file];
  if (!open_ || open_->path() != layout.path) {
    open_.reset();
    open_ = std::make_unique<NcFile>(layout.path);
  }
  const std::vector<int> vars = component_variables(*open_);
  RawStep raw;
  raw.step = step;
  raw.encoded = true;
  raw.bytes.resize(vars.size() * source_points_ * sizeof(double));
  auto* out = reinterpret_cast<double*>(raw.bytes.data());
  for (std::size_t c = 0; c < vars.size(); ++c) {
    const std::vector<int> dims = open_->dimensions(vars[c]);
    // The step's index along the time dimension (the first), then every other dimension whole.
    std::vector<std::size_t> start, count;
    for (std::size_t k = 0; k < dims.size(); ++k) {
      const bool time = k == 0 && layout.has_time_dimension;
      start.push_back(time ? step - first_step_[file] : 0);
      count.push_back(time ? 1 : open_->dimension_length(dims[k]));
    }
    open_->read(vars[c], start, count, out + c * source_points_);
  }
  return raw;
}

void NetcdfSeries::decode(const RawStep& raw, std::span<float> values) const {
  const std::size_t comps = variables_.size();
  if (raw.bytes.size() != comps * source_points_ * sizeof(double))
    throw FormatError(describe() + ": step " + std::to_string(raw.step) + " has " +
                      std::to_string(raw.bytes.size()) + " bytes, expected " +
                      std::to_string(comps * source_points_ * sizeof(double)));
  const auto* in = reinterpret_cast<const double*>(raw.bytes.data());
  const std::size_t d = axes_.size();
  const std::size_t nx = axes_[d - 1].length, ny = axes_[d - 2].length;
  const std::size_t nz = d == 3 ? axes_[0].length : 1;
  const std::size_t out_nx = static_cast<std::size_t>(geometry_.size[0]);
  const double R = options_.earth_radius;
  for (std::size_t k = 0; k < nz; ++k)
    for (std::size_t j = 0; j < ny; ++j) {
      const std::size_t sk = d == 3 && axes_[0].flipped ? nz - 1 - k : k;
      const std::size_t sj = axes_[d - 2].flipped ? ny - 1 - j : j;
      // Degrees per second per m/s at this latitude (lon/lat in degrees only).
      double east = axis_factor_[0], north = axis_factor_[1];
      bool pole = false;
      if (lonlat_) {
        east = north = velocity_factor_;
        if (options_.lonlat == LonLatMetric::degrees) {
          const double lat = latitude_[j];
          pole = std::abs(lat) > 89.9;
          east *= kDegree / (R * std::cos(lat / kDegree));
          north *= kDegree / R;
        }
      }
      for (std::size_t i = 0; i < out_nx; ++i) {
        const std::size_t ii = i % nx;  // the wrapped column repeats the first
        const std::size_t si = axes_[d - 1].flipped ? nx - 1 - ii : ii;
        const std::size_t source = si + nx * (sj + ny * sk);
        float* o =
            values.data() + static_cast<std::size_t>(components_) * (i + out_nx * (j + ny * k));
        bool missing = pole;
        double v[3] = {0, 0, 0};
        for (std::size_t c = 0; c < comps; ++c) {
          const double packed = in[c * source_points_ + source];
          if (rules_[c].is_no_data(packed)) missing = true;
          v[c] = packed * rules_[c].scale + rules_[c].offset;
        }
        if (missing) {
          for (int c = 0; c < components_; ++c) o[c] = std::numeric_limits<float>::quiet_NaN();
          continue;
        }
        o[0] = static_cast<float>(v[0] * east);
        o[1] = static_cast<float>(v[1] * north);
        // A 3D grid with u and v only: w = 0.
        if (components_ == 3)
          o[2] = comps == 3 ? static_cast<float>(vertical_sign_ * v[2] * axis_factor_[2])
                            : 0.0f;
      }
    }
}

}  // namespace

const char* to_string(LonLatMetric metric) {
  return metric == LonLatMetric::degrees ? "degrees" : "metres";
}

NetcdfOptions parse_netcdf_selector(const std::string& selector) {
  NetcdfOptions o;
  if (trim(selector).empty()) return o;
  std::size_t begin = 0;
  for (;;) {
    const std::size_t end = selector.find(',', begin);
    const std::string item = trim(selector.substr(begin, end - begin));
    const std::size_t eq = item.find('=');
    if (item.empty()) {
      throw InvalidArgument("NetCDF selector '" + selector + "': an empty item");
    } else if (eq == std::string::npos) {
      o.variables.push_back(item);
    } else {
      const std::string key = lower(trim(item.substr(0, eq))), value = trim(item.substr(eq + 1));
      const auto positive = [&](const std::string& what) {
        char* stop = nullptr;
        const double x = std::strtod(value.c_str(), &stop);
        if (value.empty() || *stop != '\0' || !(x > 0) || !std::isfinite(x))
          throw InvalidArgument("NetCDF selector: " + key + "=" + value + ": " + what +
                                " must be a number > 0");
        return x;
      };
      if (key == "units") {
        if (value.empty())
          throw InvalidArgument("NetCDF selector: units= needs the velocities' units (m/s, cm/s)");
        o.velocity_units = value;
      } else if (key == "lonlat") {
        if (value == "degrees")
          o.lonlat = LonLatMetric::degrees;
        else if (value == "metres" || value == "meters")
          o.lonlat = LonLatMetric::metres;
        else
          throw InvalidArgument("NetCDF selector: lonlat=" + value +
                                ": expected degrees or metres");
      } else if (key == "dt") {
        o.dt = positive("dt (seconds between steps)");
      } else if (key == "radius") {
        o.earth_radius = positive("radius (metres)");
      } else {
        throw InvalidArgument("NetCDF selector: unknown key '" + key +
                              "' (known: lonlat, dt, radius, units; other items name variables)");
      }
    }
    if (end == std::string::npos) break;
    begin = end + 1;
  }
  return o;
}

namespace {

// netCDF-C, and libhdf5 under NetCDF-4, trust a file's header: a damaged one can make them
// allocate what it declares or crash (fuzzing found a null dereference in NC3_open's cleanup).
// So `read` runs first in a child process under a memory and time limit (child_read.h), once per
// set of files and their sizes and times in this process; an error there is the error here.
void vet_netcdf(const std::vector<std::filesystem::path>& files, const std::function<void()>& read) {
  thread_local bool vetting = false;
  if (vetting || files_trusted() || files.empty()) return;
  std::string key;
  std::uintmax_t bytes = 0;
  for (const std::filesystem::path& file : files) {
    std::error_code ec;
    const std::uintmax_t size = std::filesystem::file_size(file, ec);
    const auto time = std::filesystem::last_write_time(file, ec);
    bytes += ec ? 0 : size;
    key += file.string() + '\n' + std::to_string(size) + '\n' +
           std::to_string(time.time_since_epoch().count()) + '\n';
  }
  static std::mutex mutex;
  static std::set<std::string> vetted;
  {
    const std::lock_guard<std::mutex> lock(mutex);
    if (vetted.count(key) != 0) return;
  }
  ChildReadLimits limits;
  const std::uintmax_t cap = std::uintmax_t{1} << 40;
  limits.memory_bytes = static_cast<std::size_t>((std::uintmax_t{1} << 30) + 4 * std::min(bytes, cap));
  limits.seconds = child_read_seconds(static_cast<std::size_t>(std::min(bytes, cap)));
  const std::string what =
      files.front().string() +
      (files.size() > 1 ? " (and " + std::to_string(files.size() - 1) + " more files)" : "");
  read_in_child(what, "NetCDF",
                [&] {
                  vetting = true;
                  read();
                },
                limits);
  const std::lock_guard<std::mutex> lock(mutex);
  vetted.insert(key);
}

}  // namespace

std::unique_ptr<TimeSeries> open_netcdf_series(const std::vector<std::filesystem::path>& files,
                                               const NetcdfOptions& options) {
  vet_netcdf(files, [&] {
    const NetcdfSeries series(files, options);
    std::vector<float> values(series.step_floats());
    series.read(0, values);
    if (series.step_count() > 1) series.read(series.step_count() - 1, values);
  });
  return std::make_unique<NetcdfSeries>(files, options);
}

std::optional<double> metres_per_second(const std::string& units) { return speed_unit(units); }

NetcdfVariable read_netcdf_variable(const std::filesystem::path& file, const std::string& name,
                                    std::size_t max_values) {
  vet_netcdf({file}, [&] { (void)read_netcdf_variable(file, name, max_values); });
  const NcFile f(file);
  const std::optional<int> v = f.variable(name);
  if (!v) {
    std::string names;
    for (const std::string& n : f.variable_names()) names += (names.empty() ? "" : ", ") + n;
    throw FormatError("'" + file.string() + "': no variable '" + name + "' (the file has: " +
                      names + ")");
  }
  NetcdfVariable out;
  std::size_t count = 1;
  for (const int d : f.dimensions(*v)) {
    out.dimensions.push_back(f.dimension_name(d));
    out.shape.push_back(f.dimension_length(d));
    if (out.shape.back() != 0 && count > max_values / out.shape.back())
      throw FormatError("'" + file.string() + "': variable '" + name + "' holds more than " +
                        std::to_string(max_values) + " values");
    count *= out.shape.back();
  }
  out.values = f.read_all(*v, count);
  const NoDataRules rules = no_data_rules(f, *v);
  for (double& x : out.values)
    x = rules.is_no_data(x) ? std::numeric_limits<double>::quiet_NaN()
                            : x * rules.scale + rules.offset;
  out.units = f.units(*v);
  return out;
}

const NetcdfDescription* netcdf_description(const TimeSeries& series) {
  const auto* s = dynamic_cast<const NetcdfSeries*>(&series);
  return s ? &s->description() : nullptr;
}

bool netcdf_has_calendar(const TimeSeries& series) {
  const auto* s = dynamic_cast<const NetcdfSeries*>(&series);
  return s != nullptr && s->has_calendar();
}

std::optional<double> netcdf_time_of_date(const TimeSeries& series, const std::string& date) {
  const auto* s = dynamic_cast<const NetcdfSeries*>(&series);
  return s ? s->time_of_date(date) : std::nullopt;
}

}  // namespace orthofront::io
