// NetCDF with CF conventions: daily files of 2D surface currents on a lon/lat grid (classic,
// 64-bit offset and NetCDF-4 in one series), packed shorts with a fill value and land, times in
// a noleap calendar with different units per file; and a NetCDF-4 file holding several steps on
// a metric grid. The files are written here with netCDF-C itself.
#include <netcdf.h>

#include <catch2/catch.hpp>
#include <array>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "apps/cli_run.h"
#include "jobs/time_arg.h"
#include "orthofront/io/hdf5_layout.h"
#include "orthofront/io/mesh_io.h"
#include "orthofront/io/netcdf_series.h"
#include "temp_dir.h"

namespace fs = std::filesystem;
using cli_test::quoted;
using orthofront::Mesh;
using test_support::read_text;
using test_support::TempDir;

namespace {

constexpr double kR = 6371000.0;
constexpr double kDeg = 180.0 / 3.14159265358979323846;
constexpr double kEast = 0.5;  // m/s everywhere at sea

void ok(int status) {
  REQUIRE(status == NC_NOERR);
}

bool land(double lon, double lat) {
  return lon >= 24 && lon <= 27 && lat >= -6 && lat <= -3;
}

// One day of currents: lon 10..30, lat 10..-10 (stored north to south), step 0.5°, u = 0.5 m/s
// east at sea, land a block of _FillValue; u, v as shorts (scale 0.001); one step on an
// unlimited time dimension, `time_value` in `time_units` (calendar noleap).
void write_day(const fs::path& file, int format, double time_value, const std::string& time_units,
               const std::string& velocity_units = "m s-1", const char* units = "units",
               bool cf_names = true) {
  int nc = 0;
  ok(nc_create(file.c_str(), NC_CLOBBER | format, &nc));
  int dt = 0, dy = 0, dx = 0, vt = 0, vy = 0, vx = 0, vu = 0, vv = 0;
  ok(nc_def_dim(nc, "time", NC_UNLIMITED, &dt));
  ok(nc_def_dim(nc, "lat", 41, &dy));
  ok(nc_def_dim(nc, "lon", 41, &dx));
  ok(nc_def_var(nc, "time", NC_DOUBLE, 1, &dt, &vt));
  ok(nc_put_att_text(nc, vt, units, time_units.size(), time_units.c_str()));
  ok(nc_put_att_text(nc, vt, "calendar", 6, "noleap"));
  ok(nc_def_var(nc, "lat", NC_FLOAT, 1, &dy, &vy));
  if (cf_names)
    ok(nc_put_att_text(nc, vy, units, 13, "degrees_north"));
  else
    ok(nc_put_att_text(nc, vy, units, 7, "degrees"));
  ok(nc_def_var(nc, "lon", NC_FLOAT, 1, &dx, &vx));
  if (cf_names)
    ok(nc_put_att_text(nc, vx, units, 12, "degrees_east"));
  else
    ok(nc_put_att_text(nc, vx, units, 7, "degrees"));
  const int dims[3] = {dt, dy, dx};
  const short fill = -32767;
  const double scale = 0.001;
  for (const auto& [name, standard, id] :
       {std::tuple<const char*, std::string, int*>{"uo", "eastward_sea_water_velocity", &vu},
        {"vo", "northward_sea_water_velocity", &vv}}) {
    ok(nc_def_var(nc, name, NC_SHORT, 3, dims, id));
    if (cf_names)
      ok(nc_put_att_text(nc, *id, "standard_name", standard.size(), standard.c_str()));
    ok(nc_put_att_text(nc, *id, units, velocity_units.size(), velocity_units.c_str()));
    ok(nc_put_att_short(nc, *id, "_FillValue", NC_SHORT, 1, &fill));
    ok(nc_put_att_double(nc, *id, "scale_factor", NC_DOUBLE, 1, &scale));
  }
  ok(nc_enddef(nc));
  std::vector<float> lat(41), lon(41);
  for (int i = 0; i < 41; ++i) {
    lat[static_cast<std::size_t>(i)] = static_cast<float>(10 - 0.5 * i);
    lon[static_cast<std::size_t>(i)] = static_cast<float>(10 + 0.5 * i);
  }
  ok(nc_put_var_float(nc, vy, lat.data()));
  ok(nc_put_var_float(nc, vx, lon.data()));
  std::vector<short> u(41 * 41), v(41 * 41, 0);
  for (int j = 0; j < 41; ++j)
    for (int i = 0; i < 41; ++i) {
      const bool dry = land(lon[static_cast<std::size_t>(i)], lat[static_cast<std::size_t>(j)]);
      u[static_cast<std::size_t>(j * 41 + i)] = dry ? fill : static_cast<short>(kEast / scale);
      if (dry) v[static_cast<std::size_t>(j * 41 + i)] = fill;
    }
  const std::size_t start[3] = {0, 0, 0}, count[3] = {1, 41, 41};
  ok(nc_put_vara_short(nc, vu, start, count, u.data()));
  ok(nc_put_vara_short(nc, vv, start, count, v.data()));
  const std::size_t t0 = 0, one = 1;
  ok(nc_put_vara_double(nc, vt, &t0, &one, &time_value));
  ok(nc_close(nc));
}

// Three days in three formats. Day 0 and 1 count days since 1950-01-01, day 2 hours since
// 2023-12-31 (noleap: 73 years of 365 days + 364 days = 27,009 days after 1950-01-01).
fs::path write_days(const TempDir& dir) {
  const fs::path folder = dir / "days";
  fs::create_directories(folder);
  write_day(folder / "day1.nc", NC_CLASSIC_MODEL, 27010, "days since 1950-01-01");
  write_day(folder / "day2.nc", NC_64BIT_OFFSET, 27011, "days since 1950-01-01 00:00:00");
  write_day(folder / "day10.nc", NC_NETCDF4, 3 * 24, "hours since 2023-12-31");
  return folder;
}

}  // namespace

TEST_CASE("NetCDF: daily CF files on a lon/lat grid read as one series", "[apps][netcdf]") {
  TempDir dir;
  const fs::path days = write_days(dir);
  namespace io = orthofront::io;
  const auto series = io::open_netcdf_series(io::expand_file_pattern((days / "day*.nc").string()));
  const io::NetcdfDescription& d = *io::netcdf_description(*series);
  CHECK(d.found_by == "CF standard_name");
  CHECK(d.variables == std::vector<std::string>{"uo", "vo"});
  CHECK(d.lonlat);
  CHECK(d.files == 3);
  CHECK(d.format ==
        "mixed: NetCDF-3 classic (1 file), NetCDF-3 64-bit offset (1 file), NetCDF-4 (1 file)");
  // Natural order (day2 before day10); times in seconds since the first file's epoch.
  REQUIRE(series->step_count() == 3);
  CHECK(series->time(0) == 27010.0 * 86400);
  CHECK(series->time(1) == 27011.0 * 86400);
  CHECK(series->time(2) == 27012.0 * 86400);
  // Latitude stored north to south comes out increasing.
  const orthofront::GridGeometry& g = series->geometry();
  CHECK(g.dimension == 2);
  CHECK(g.size[0] == 41);
  CHECK(g.size[1] == 41);
  CHECK(g.origin.x() == Approx(10));
  CHECK(g.origin.y() == Approx(-10));
  CHECK(g.spacing.x() == Approx(0.5));
  CHECK(g.spacing.y() == Approx(0.5));
  std::vector<float> values(series->step_floats());
  series->read(2, values);
  std::size_t dry = 0;
  for (std::int64_t j = 0; j < 41; ++j)
    for (std::int64_t i = 0; i < 41; ++i) {
      const double lon = 10 + 0.5 * static_cast<double>(i),
                   lat = -10 + 0.5 * static_cast<double>(j);
      const float* v = values.data() + 2 * g.index(i, j, 0);
      if (land(lon, lat)) {
        CHECK(std::isnan(v[0]));
        CHECK(std::isnan(v[1]));
        ++dry;
        continue;
      }
      // Degrees per second on the sphere.
      REQUIRE(v[0] == Approx(kEast * kDeg / (kR * std::cos(lat / kDeg))).epsilon(1e-6));
      REQUIRE(v[1] == 0.0f);
    }
  CHECK(dry == 7 * 7);

  // The metric choice: metres keeps m/s and reports its east-west error.
  io::NetcdfOptions metres;
  metres.lonlat = io::LonLatMetric::metres;
  const auto m = io::open_netcdf_series({days / "day1.nc"}, metres);
  const io::NetcdfDescription& md = *io::netcdf_description(*m);
  CHECK(md.metric_error == Approx(1 / std::cos(10 / kDeg) - 1).epsilon(1e-9));
  std::vector<float> mv(m->step_floats());
  m->read(0, mv);
  CHECK(mv[0] == Approx(kEast));
  CHECK(m->geometry().spacing.y() == Approx(kR * 0.5 / kDeg));
}

TEST_CASE("NetCDF: units under another attribute name ('Unit') are read, not ignored",
          "[apps][netcdf]") {
  // As a real ocean product writes them: 'Unit' rather than CF's 'units', lon/lat in plain
  // "degrees", no standard names. The series must be the CF file's, value for value.
  TempDir dir;
  namespace io = orthofront::io;
  write_day(dir / "cf.nc", NC_CLASSIC_MODEL, 27010, "days since 1950-01-01");
  write_day(dir / "unit.nc", NC_CLASSIC_MODEL, 27010, "days since 1950-01-01", "m s-1", "Unit",
            false);
  io::NetcdfOptions o;
  o.variables = {"uo", "vo"};
  const auto cf = io::open_netcdf_series({dir / "cf.nc"}, o);
  const auto unit = io::open_netcdf_series({dir / "unit.nc"}, o);
  const io::NetcdfDescription& d = *io::netcdf_description(*unit);
  CHECK(d.lonlat);
  CHECK(d.velocity_units == "m s-1");
  CHECK(unit->time(0) == cf->time(0));
  CHECK(unit->geometry().spacing == cf->geometry().spacing);
  CHECK(unit->geometry().origin == cf->geometry().origin);
  std::vector<float> a(cf->step_floats()), b(unit->step_floats());
  cf->read(0, a);
  unit->read(0, b);
  std::size_t differ = 0, land_points = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    land_points += std::isnan(a[i]) ? 1 : 0;
    differ += std::isnan(a[i]) != std::isnan(b[i]) || (!std::isnan(a[i]) && a[i] != b[i]) ? 1 : 0;
  }
  CHECK(land_points > 0);  // land is no data (NaN) in both
  CHECK(differ == 0);
}

TEST_CASE("NetCDF: depth that is positive down turns an upward w into decreasing depth",
          "[apps][netcdf]") {
  // Metres on x, y; depth 0, 50, 100 m (positive="down"); w = +1e-4 m/s, upward as CF has it.
  TempDir dir;
  namespace io = orthofront::io;
  const fs::path file = dir / "column.nc";
  int nc = 0;
  ok(nc_create(file.c_str(), NC_CLOBBER, &nc));
  int dz = 0, dy = 0, dx = 0, vz = 0, vy = 0, vx = 0;
  ok(nc_def_dim(nc, "depth", 3, &dz));
  ok(nc_def_dim(nc, "y", 3, &dy));
  ok(nc_def_dim(nc, "x", 3, &dx));
  ok(nc_def_var(nc, "depth", NC_DOUBLE, 1, &dz, &vz));
  ok(nc_put_att_text(nc, vz, "units", 1, "m"));
  ok(nc_put_att_text(nc, vz, "positive", 4, "down"));
  ok(nc_def_var(nc, "y", NC_DOUBLE, 1, &dy, &vy));
  ok(nc_put_att_text(nc, vy, "units", 1, "m"));
  ok(nc_def_var(nc, "x", NC_DOUBLE, 1, &dx, &vx));
  ok(nc_put_att_text(nc, vx, "units", 1, "m"));
  const int dims[3] = {dz, dy, dx};
  int ids[3] = {};
  const char* names[3] = {"u", "v", "w"};
  for (int c = 0; c < 3; ++c) {
    ok(nc_def_var(nc, names[c], NC_DOUBLE, 3, dims, &ids[c]));
    ok(nc_put_att_text(nc, ids[c], "units", 5, "m s-1"));
  }
  ok(nc_enddef(nc));
  const double depth[3] = {0, 50, 100}, xy[3] = {0, 1000, 2000};
  ok(nc_put_var_double(nc, vz, depth));
  ok(nc_put_var_double(nc, vy, xy));
  ok(nc_put_var_double(nc, vx, xy));
  const std::vector<double> zero(27, 0.0), up(27, 1e-4);
  ok(nc_put_var_double(nc, ids[0], zero.data()));
  ok(nc_put_var_double(nc, ids[1], zero.data()));
  ok(nc_put_var_double(nc, ids[2], up.data()));
  ok(nc_close(nc));
  io::NetcdfOptions o;
  o.dt = 86400;
  const auto series = io::open_netcdf_series({file}, o);
  const io::NetcdfDescription& d = *io::netcdf_description(*series);
  INFO(d.coordinates);
  CHECK_THAT(d.coordinates, Catch::Contains("positive down") && Catch::Contains("z is depth"));
  std::vector<float> values(series->step_floats());
  series->read(0, values);
  for (std::size_t i = 0; i < 27; ++i) {
    CHECK(values[3 * i] == 0.0f);
    CHECK(values[3 * i + 2] == Approx(-1e-4));  // rising: depth decreases
  }
}

TEST_CASE("NetCDF: path lines of a uniform eastward flow stay on their latitude",
          "[apps][netcdf]") {
  TempDir dir;
  const fs::path days = write_days(dir);
  const fs::path out = dir / "p.vtp";
  const auto r = cli_test::run("path --field " + quoted(days / "day*.nc") +
                               " --seed line:12,2,0:12,6,0 --t0 2333664000 --t1 2333750400 "
                               "--edge 0.05 --out " +
                               quoted(out));
  INFO(r.output);
  REQUIRE(r.status == 0);
  // A NetCDF-4 file among them: HDF5's own error printing stays off.
  CHECK(r.output.find("HDF5-DIAG") == std::string::npos);
  const Mesh mesh = orthofront::io::read_mesh(out);
  REQUIRE(mesh.vertex_count() > 100);
  REQUIRE(mesh.s.size() == mesh.vertex_count());
  double worst_lat = 0, worst_lon = 0, longest = 0, worst_on_rows = 0;
  std::size_t on_rows = 0;
  for (std::size_t i = 0; i < mesh.vertex_count(); ++i) {
    const double lat0 = 2 + 4 * mesh.s[i];
    const orthofront::Vec3& p = mesh.positions[i];
    worst_lat = std::max(worst_lat, std::abs(p.y() - lat0));
    // The independent integration on the sphere: d lon / dt = u / (R cos lat), lat fixed.
    const double elapsed = mesh.time[i] - 2333664000.0;
    const double travel = kEast * elapsed * kDeg / (kR * std::cos(p.y() / kDeg));
    worst_lon = std::max(worst_lon, std::abs(p.x() - 12 - travel));
    longest = std::max(longest, p.x() - 12);
    // On a grid row the sampled field is exact: the relative error is the integrator's (and
    // float32 storage's).
    if (std::abs(2 * lat0 - std::round(2 * lat0)) < 1e-9 && travel > 0.01) {
      worst_on_rows = std::max(worst_on_rows, std::abs(p.x() - 12 - travel) / travel);
      ++on_rows;
    }
  }
  INFO("latitude drift " << worst_lat << "°, longitude error " << worst_lon << "°, farthest "
                         << longest << "° east; relative error on grid rows " << worst_on_rows
                         << " over " << on_rows << " vertices");
  // The file says what its positions and times are in.
  const auto note = [&](const std::string& name) {
    for (const auto& [key, text] : mesh.notes)
      if (key == name) return text;
    return std::string("(none)");
  };
  CHECK(note("position_units") == "degrees: x longitude east, y latitude north");
  CHECK(note("time").find("seconds since") != std::string::npos);
  CHECK(note("source") == (days / "day*.nc").string());
  CHECK(note("orthofront_surface").rfind("path surface, orthofront ", 0) == 0);
  CHECK(longest > 0.35);  // one day at 0.5 m/s: 0.39° to 0.44° at these latitudes
  CHECK(worst_lat < 1e-9);
  CHECK(worst_lon < 1e-4);  // bilinear 1 / cos(lat) between grid rows
  CHECK(on_rows > 10);
  CHECK(worst_on_rows < 1e-6);
}

TEST_CASE("NetCDF: info and convert read the files directly", "[apps][netcdf]") {
  TempDir dir;
  const fs::path days = write_days(dir);
  const auto info = cli_test::run("info " + quoted(days / "day*.nc"));
  INFO(info.output);
  REQUIRE(info.status == 0);
  CHECK(info.output.find("uo, vo (CF standard_name)") != std::string::npos);
  CHECK(info.output.find("seconds since 1950-01-01 (calendar noleap") != std::string::npos);
  CHECK(info.output.find("degrees per second on a sphere") != std::string::npos);
  CHECK(info.output.find("zeros mean:   flow (critical points); land is the fill value") !=
        std::string::npos);
  const fs::path h5 = dir / "days.h5";
  const auto c = cli_test::run("convert " + quoted(days / "day*.nc") + " --out " + quoted(h5));
  INFO(c.output);
  REQUIRE(c.status == 0);
  namespace io = orthofront::io;
  const auto nc = io::open_netcdf_series(io::expand_file_pattern((days / "day*.nc").string()));
  const auto back = io::open_hdf5_series(h5);
  REQUIRE(back->step_count() == 3);
  std::vector<float> a(nc->step_floats()), b(back->step_floats());
  for (std::size_t s = 0; s < 3; ++s) {
    CHECK(back->time(s) == nc->time(s));
    nc->read(s, a);
    back->read(s, b);
    for (std::size_t k = 0; k < a.size(); ++k)
      REQUIRE((a[k] == b[k] || (std::isnan(a[k]) && std::isnan(b[k]))));
  }
}

TEST_CASE("NetCDF: a NetCDF-4 file of several steps on a metric grid, with missing values",
          "[apps][netcdf]") {
  TempDir dir;
  const fs::path file = dir / "flow.nc";
  int nc = 0;
  ok(nc_create(file.c_str(), NC_CLOBBER | NC_NETCDF4, &nc));
  int dt = 0, dy = 0, dx = 0, vt = 0, vx = 0, vu = 0, vv = 0;
  ok(nc_def_dim(nc, "t", 4, &dt));
  ok(nc_def_dim(nc, "y", 5, &dy));
  ok(nc_def_dim(nc, "x", 6, &dx));
  ok(nc_def_var(nc, "t", NC_DOUBLE, 1, &dt, &vt));
  ok(nc_put_att_text(nc, vt, "units", 29, "hours since 2000-01-01T00:00Z"));
  ok(nc_def_var(nc, "x", NC_DOUBLE, 1, &dx, &vx));  // rectilinear, no units: not lon/lat
  const int dims[3] = {dt, dy, dx};
  const float missing = -999.f;
  for (const auto& [name, id] : {std::pair<const char*, int*>{"u", &vu}, {"v", &vv}}) {
    ok(nc_def_var(nc, name, NC_FLOAT, 3, dims, id));
    ok(nc_put_att_float(nc, *id, "missing_value", NC_FLOAT, 1, &missing));
  }
  ok(nc_enddef(nc));
  const double times[4] = {0, 1, 2, 4}, xs[6] = {0, 1, 2, 4, 8, 16};
  ok(nc_put_var_double(nc, vt, times));
  ok(nc_put_var_double(nc, vx, xs));
  std::vector<float> u(4 * 5 * 6), v(4 * 5 * 6);
  for (std::size_t k = 0; k < u.size(); ++k) {
    u[k] = static_cast<float>(k);
    v[k] = k % 7 == 3 ? missing : -static_cast<float>(k);
  }
  ok(nc_put_var_float(nc, vu, u.data()));
  ok(nc_put_var_float(nc, vv, v.data()));
  ok(nc_close(nc));

  namespace io = orthofront::io;
  // lonlat=metres cannot apply to a grid in metres: refused, not ignored.
  io::NetcdfOptions metres;
  metres.lonlat = io::LonLatMetric::metres;
  CHECK_THROWS_WITH(io::open_netcdf_series({file}, metres),
                    Catch::Contains("lonlat=metres") && Catch::Contains("not longitude/latitude"));
  const auto s = io::open_netcdf_series({file});
  const io::NetcdfDescription& d = *io::netcdf_description(*s);
  CHECK(d.format == "NetCDF-4");
  CHECK(d.found_by == "variable names");
  CHECK(!d.lonlat);
  REQUIRE(s->step_count() == 4);
  CHECK(s->time(3) == 4 * 3600.0);
  CHECK(s->geometry().rectilinear());
  CHECK(s->geometry().axes[0] == std::vector<double>{0, 1, 2, 4, 8, 16});
  std::vector<float> values(s->step_floats());
  s->read(2, values);
  for (std::size_t p = 0; p < 30; ++p) {
    const std::size_t k = 60 + p;
    if (k % 7 == 3) {
      CHECK(std::isnan(values[2 * p]));
    } else {
      CHECK(values[2 * p] == static_cast<float>(k));
      CHECK(values[2 * p + 1] == -static_cast<float>(k));
    }
  }
}

TEST_CASE("NetCDF: a global lon/lat grid has its seam closed", "[apps][netcdf]") {
  TempDir dir;
  const fs::path file = dir / "global.nc";
  int nc = 0;
  ok(nc_create(file.c_str(), NC_CLOBBER, &nc));
  int dy = 0, dx = 0, vy = 0, vx = 0, vu = 0, vv = 0;
  ok(nc_def_dim(nc, "latitude", 3, &dy));
  ok(nc_def_dim(nc, "longitude", 144, &dx));
  ok(nc_def_var(nc, "latitude", NC_DOUBLE, 1, &dy, &vy));
  ok(nc_put_att_text(nc, vy, "units", 13, "degrees_north"));
  ok(nc_def_var(nc, "longitude", NC_DOUBLE, 1, &dx, &vx));
  ok(nc_put_att_text(nc, vx, "units", 12, "degrees_east"));
  const int dims[2] = {dy, dx};
  for (const auto& [name, id] : {std::pair<const char*, int*>{"u", &vu}, {"v", &vv}}) {
    ok(nc_def_var(nc, name, NC_DOUBLE, 2, dims, id));
    ok(nc_put_att_text(nc, *id, "units", 3, "m/s"));
  }
  ok(nc_enddef(nc));
  const double lat[3] = {-30, 0, 30};
  std::vector<double> lon(144), u(3 * 144), v(3 * 144, 0.0);
  for (std::size_t i = 0; i < 144; ++i) lon[i] = 2.5 * static_cast<double>(i);
  for (std::size_t k = 0; k < u.size(); ++k) u[k] = static_cast<double>(k % 144);  // by column
  ok(nc_put_var_double(nc, vy, lat));
  ok(nc_put_var_double(nc, vx, lon.data()));
  ok(nc_put_var_double(nc, vu, u.data()));
  ok(nc_put_var_double(nc, vv, v.data()));
  ok(nc_close(nc));

  namespace io = orthofront::io;
  orthofront::io::NetcdfOptions o;
  o.dt = 3600;  // no time coordinate: one step
  const auto s = io::open_netcdf_series({file}, o);
  CHECK(io::netcdf_description(*s)->longitude_wrapped);
  const orthofront::GridGeometry& g = s->geometry();
  REQUIRE(g.size[0] == 145);
  CHECK(g.bounds().hi.x() == Approx(360));
  std::vector<float> values(s->step_floats());
  s->read(0, values);
  for (std::int64_t j = 0; j < 3; ++j) {
    CHECK(values[2 * g.index(144, j, 0)] == values[2 * g.index(0, j, 0)]);
    CHECK(values[2 * g.index(1, j, 0)] > 0);
  }
  // Without dt a file with no time coordinate is refused, naming it.
  CHECK_THROWS_WITH(io::open_netcdf_series({file}), Catch::Contains("no CF time coordinate"));
}

TEST_CASE("NetCDF: bad files and names get messages naming the file and the value",
          "[apps][netcdf]") {
  TempDir dir;
  const fs::path days = write_days(dir);
  const auto expect = [](const std::string& args, const std::string& text) {
    const auto r = cli_test::run(args);
    INFO(args << "\n" << r.output);
    CHECK(r.status == 2);
    CHECK(r.output.find(text) != std::string::npos);
  };
  expect("info " + quoted(days / "day1.nc:uu,vv"),
         "no variable 'uu' (variables: time, lat, lon, uo, vo)");
  expect("info " + quoted(dir / "none.nc"), "cannot open '" + (dir / "none.nc").string());
  expect("info " + quoted(dir / "none*.nc"), "matches no file");
  {
    std::ofstream bad(dir / "bad.nc");
    bad << "CDF\x01 this is not a NetCDF file";
  }
  expect("info " + quoted(dir / "bad.nc"),
         "cannot read '" + (dir / "bad.nc").string() + "' as NetCDF");
  expect("info " + quoted(days / "day2.nc") + "," + (days / "day1.nc").string(),
         "does not come after");
  expect("info " + quoted(days / "day1.nc:uo,vo,lonlat=miles"), "lonlat=miles");
  write_day(dir / "knots.nc", NC_CLASSIC_MODEL, 1, "days since 1950-01-01", "knots");
  expect("info " + quoted(dir / "knots.nc"), "units 'knots' on a lon/lat grid");
  write_day(dir / "months.nc", NC_CLASSIC_MODEL, 1, "months since 1950-01-01");
  expect("info " + quoted(dir / "months.nc"), "'months since 1950-01-01'");

  // A coordinate variable on another, longer dimension than the one it names (read whole, it
  // would overrun), and v stored transposed from u on a square grid.
  const fs::path odd = dir / "odd.nc";
  int nc = 0;
  ok(nc_create(odd.c_str(), NC_CLOBBER, &nc));
  int dlat = 0, dlon = 0, dy = 0, vlat = 0, vu = 0, vv = 0;
  ok(nc_def_dim(nc, "lat", 4, &dlat));
  ok(nc_def_dim(nc, "lon", 4, &dlon));
  ok(nc_def_dim(nc, "y", 9, &dy));
  ok(nc_def_var(nc, "lat", NC_DOUBLE, 1, &dy, &vlat));
  const int uv[2] = {dlat, dlon}, vu_dims[2] = {dlon, dlat};
  ok(nc_def_var(nc, "u", NC_FLOAT, 2, uv, &vu));
  ok(nc_def_var(nc, "v", NC_FLOAT, 2, vu_dims, &vv));
  ok(nc_close(nc));
  expect("info " + cli_test::quoted(fs::path(odd.string() + ":u,v,dt=1")),
         "coordinate variable 'lat' has 9 values for a dimension of 4");
  namespace io = orthofront::io;
  io::NetcdfOptions o;
  o.dt = 1;
  ok(nc_open(odd.c_str(), NC_WRITE, &nc));
  ok(nc_redef(nc));
  ok(nc_rename_var(nc, vlat, "ylat"));
  ok(nc_close(nc));
  CHECK_THROWS_WITH(io::open_netcdf_series({odd}, o),
                    Catch::Contains("variable 'v' has dimension 'lon' of length 4 where") &&
                        Catch::Contains("has 'lat' of length 4"));
}

#ifdef ORTHOFRONT_POP_CONVERT  // builds that read NetCDF
TEST_CASE("NetCDF: the model converter takes a 2D product of daily NetCDF-3 files",
          "[apps][netcdf][pop]") {
  TempDir dir;
  const fs::path days = write_days(dir);
  const fs::path out = dir / "surface.h5";
  const fs::path report = dir / "loss.json";
  const std::string command =
      cli_test::quoted(fs::path(ORTHOFRONT_POP_CONVERT)) + " " +
      cli_test::quoted(days / "day1.nc") + " " + cli_test::quoted(days / "day2.nc") + " " +
      cli_test::quoted(days / "day10.nc") +
      " --u uo --v vo --w none --depth none --lon lon --lat lat --dt 86400 --out " +
      cli_test::quoted(out) + " --report " + cli_test::quoted(report) + " > " +
      cli_test::quoted(dir / "log.txt") + " 2>&1";
  INFO(command);
  REQUIRE(std::system(command.c_str()) == 0);
  CHECK_THAT(read_text(dir / "log.txt"), Catch::Matchers::Contains("2D product 41 x 41 x 1"));

  orthofront::io::Hdf5ReadOptions options;
  const auto series = orthofront::io::open_hdf5_series(out, "/", options);
  REQUIRE(series->step_count() == 3);
  CHECK(series->time(2) == 2 * 86400.0);
  CHECK(series->components() == 2);
  const orthofront::GridGeometry& g = series->geometry();
  CHECK(g.dimension == 2);
  CHECK(g.size[0] == 81);  // twice the cells: every source point is a sample
  CHECK(g.size[1] == 81);
  CHECK(g.origin.x() == Approx(10));
  CHECK(g.origin.y() == Approx(-10));
  std::vector<float> values(series->step_floats());
  series->read(1, values);
  constexpr double kPopRadius = 6.37122e6;  // the converter's (POP's) sphere
  for (std::int64_t j = 0; j < 81; j += 4)
    for (std::int64_t i = 0; i < 81; i += 4) {
      const double lon = 10 + 0.25 * static_cast<double>(i),
                   lat = -10 + 0.25 * static_cast<double>(j);
      const float* v = values.data() + 2 * g.index(i, j, 0);
      INFO("lon " << lon << " lat " << lat);
      // Land and the cells touching it have no data; elsewhere u / (R cos lat) in deg/s.
      if (lon >= 23.5 && lon <= 27.5 && lat >= -6.5 && lat <= -2.5) {
        if (land(lon, lat)) CHECK(std::isnan(v[0]));
        continue;
      }
      CHECK(v[0] == Approx(kEast * kDeg / (kPopRadius * std::cos(lat / kDeg))).epsilon(1e-5));
      CHECK(v[1] == 0.0f);
    }
  std::ifstream in(report);
  const nlohmann::json loss = nlohmann::json::parse(in);
  CHECK(loss["velocity_units"] == "m s-1");
  CHECK(loss["loss"]["horizontal"]["relative_max"].get<double>() < 1e-5);
  CHECK(loss["loss"]["vertical"]["samples"].get<std::size_t>() == 0);

  // A 3D layout asked of a 2D product names the variable and its shape.
  const std::string wrong = cli_test::quoted(fs::path(ORTHOFRONT_POP_CONVERT)) + " " +
                            cli_test::quoted(days / "day1.nc") +
                            " --u uo --v vo --w wo --depth depth --lon lon --lat lat --out " +
                            cli_test::quoted(dir / "x.h5") + " > " +
                            cli_test::quoted(dir / "wrong.txt") + " 2>&1";
  CHECK(std::system(wrong.c_str()) != 0);
  CHECK_THAT(read_text(dir / "wrong.txt"),
             Catch::Matchers::Contains("day1.nc") && Catch::Matchers::Contains("uo"));
  CHECK_FALSE(fs::exists(dir / "x.h5"));
}
#endif

namespace {

// A 2D step of u, v on dimensions (y, x) with no coordinate variables; `positions` adds 2D
// longitude and latitude as a curvilinear model grid writes them (named by `coordinates`).
void write_index_grid(const fs::path& file, const char* velocity_units, bool positions,
                      bool staggered = false, bool metric_axes = false) {
  int nc = 0;
  ok(nc_create(file.c_str(), NC_CLOBBER, &nc));
  int dy = 0, dx = 0, dxu = 0, vu = 0, vv = 0, vlon = 0, vlat = 0, vx = 0, vy = 0;
  ok(nc_def_dim(nc, "y", 4, &dy));
  ok(nc_def_dim(nc, "x", 5, &dx));
  ok(nc_def_dim(nc, "x_u", 6, &dxu));
  if (metric_axes) {  // a projected grid: x, y in metres, lon/lat beside them
    ok(nc_def_var(nc, "x", NC_DOUBLE, 1, &dx, &vx));
    ok(nc_put_att_text(nc, vx, "units", 1, "m"));
    ok(nc_def_var(nc, "y", NC_DOUBLE, 1, &dy, &vy));
    ok(nc_put_att_text(nc, vy, "units", 1, "m"));
  }
  const int dims[2] = {dy, dx}, u_dims[2] = {dy, staggered ? dxu : dx};
  ok(nc_def_var(nc, "u", NC_FLOAT, 2, u_dims, &vu));
  ok(nc_def_var(nc, "v", NC_FLOAT, 2, dims, &vv));
  for (const int v : {vu, vv}) {
    if (velocity_units)
      ok(nc_put_att_text(nc, v, "units", std::strlen(velocity_units), velocity_units));
    if (positions) ok(nc_put_att_text(nc, v, "coordinates", 12, "TLONG TLAT  "));
  }
  if (positions) {
    ok(nc_def_var(nc, "TLONG", NC_DOUBLE, 2, dims, &vlon));
    ok(nc_put_att_text(nc, vlon, "units", 12, "degrees_east"));
    ok(nc_def_var(nc, "TLAT", NC_DOUBLE, 2, dims, &vlat));
    ok(nc_put_att_text(nc, vlat, "units", 13, "degrees_north"));
  }
  ok(nc_enddef(nc));
  if (metric_axes) {
    const double metres[5] = {0, 1000, 2000, 3000, 4000};
    ok(nc_put_var_double(nc, vx, metres));
    ok(nc_put_var_double(nc, vy, metres));
  }
  ok(nc_close(nc));
}

}  // namespace

TEST_CASE("NetCDF: curvilinear grids and staggered grids and index grids in m/s are refused",
          "[apps][netcdf]") {
  TempDir dir;
  namespace io = orthofront::io;
  io::NetcdfOptions o;
  o.dt = 1;
  const auto open = [&](const fs::path& file) { return io::open_netcdf_series({file}, o); };

  write_index_grid(dir / "curvilinear.nc", "cm/s", true);
  CHECK_THROWS_WITH(open(dir / "curvilinear.nc"),
                    Catch::Contains("variable 'u' lies on a curvilinear grid") &&
                        Catch::Contains("'TLONG'(y, x), 'TLAT'(y, x)") &&
                        Catch::Contains("1D coordinate variables"));
  // Without the coordinates attribute the usual names still give the grid away.
  write_index_grid(dir / "unitless.nc", nullptr, true);
  CHECK_THROWS_WITH(open(dir / "unitless.nc"), Catch::Contains("curvilinear grid"));
  // Beside axes in metres (a projected grid) 2D lon/lat are auxiliary: read in metres.
  write_index_grid(dir / "projected.nc", "m/s", true, false, true);
  CHECK(open(dir / "projected.nc")->geometry().spacing.x() == 1000);

  // Index positions and m/s: refused; unitless velocities are cells per second, and read.
  write_index_grid(dir / "index_ms.nc", "m s-1", false);
  CHECK_THROWS_WITH(open(dir / "index_ms.nc"),
                    Catch::Contains("dimension 'y' has no coordinate variable") &&
                        Catch::Contains("'u' is in m s-1"));
  write_index_grid(dir / "index.nc", nullptr, false);
  CHECK(open(dir / "index.nc")->geometry().size[0] == 5);
  // units= gives the units a file leaves out (and is held to them).
  CHECK_THROWS_WITH(io::open_netcdf_series({dir / "index.nc"},
                                           io::parse_netcdf_selector("u,v,dt=1,units=m/s")),
                    Catch::Contains("'u' is in m/s"));
  CHECK(io::parse_netcdf_selector("u,v,units=cm/s").velocity_units == "cm/s");
  CHECK_THROWS_WITH(io::parse_netcdf_selector("u,v,units="), Catch::Contains("units="));

  write_index_grid(dir / "cgrid.nc", nullptr, false, true);
  CHECK_THROWS_WITH(open(dir / "cgrid.nc"),
                    Catch::Contains("variable 'v' has dimension 'x' of length 5") &&
                        Catch::Contains("staggered C grid"));
}

#ifdef ORTHOFRONT_POP_CONVERT
TEST_CASE("NetCDF: the POP ocean files are refused as curvilinear naming ULON",
          "[apps][netcdf][realdata]") {
  const fs::path pop = fs::path(ORTHOFRONT_DATASETS_DIR) / "pop-southern-ocean";
  if (!fs::exists(pop)) {
    WARN("SKIPPED: " << pop << " is absent");
    return;
  }
  const auto r = cli_test::run("info " + quoted(fs::path(
                                   (pop / "t.x1_SAMOC_flux.169000.nc").string() +
                                   ":UVEL,VVEL,WVEL,dt=86400")));
  INFO(r.output);
  CHECK(r.status == 2);
  CHECK_THAT(r.output, Catch::Contains("curvilinear grid") && Catch::Contains("'ULON'") &&
                           Catch::Contains("orthofront-pop-convert"));
}
#endif

TEST_CASE("NetCDF: a header declaring more than the file can hold is refused before allocating",
          "[apps][netcdf]") {
  // 1000^3 points of u, v, w (12 GB a step as float) in a NetCDF-4 file of some 40 KB: no data
  // was ever written.
  TempDir dir;
  const fs::path file = dir / "huge.nc";
  int nc = 0;
  ok(nc_create(file.c_str(), NC_CLOBBER | NC_NETCDF4, &nc));
  int dims[3] = {}, ids[3] = {}, axes[3] = {};
  const char* names[3] = {"z", "y", "x"};
  for (int a = 0; a < 3; ++a) {
    ok(nc_def_dim(nc, names[a], 1000, &dims[a]));
    ok(nc_def_var(nc, names[a], NC_DOUBLE, 1, &dims[a], &axes[a]));
    ok(nc_put_att_text(nc, axes[a], "units", 1, "m"));
  }
  const char* components[3] = {"u", "v", "w"};
  for (int c = 0; c < 3; ++c) ok(nc_def_var(nc, components[c], NC_FLOAT, 3, dims, &ids[c]));
  ok(nc_enddef(nc));
  std::vector<double> coordinate(1000);
  for (std::size_t i = 0; i < coordinate.size(); ++i) coordinate[i] = static_cast<double>(i);
  for (int a = 0; a < 3; ++a) ok(nc_put_var_double(nc, axes[a], coordinate.data()));
  ok(nc_close(nc));
  REQUIRE(fs::file_size(file) < 1'000'000);
  const auto r = cli_test::run("info " + quoted(fs::path(file.string() + ":u,v,w,dt=1")));
  INFO(r.output);
  CHECK(r.status == 2);
  CHECK_THAT(r.output, Catch::Contains("declares 1000000000 points per step") &&
                           Catch::Contains("more than its") && Catch::Contains("huge.nc"));
}

TEST_CASE("NetCDF: --t0 and --t1 take dates in the series' calendar and durations",
          "[apps][netcdf]") {
  // The first day is 27010 days after 1950-01-01 in the noleap calendar: 2024-01-01.
  TempDir dir;
  const fs::path days = write_days(dir);
  namespace io = orthofront::io;
  using orthofront::jobs::resolve_time;
  const auto series = io::open_netcdf_series(io::expand_file_pattern((days / "day*.nc").string()));
  const double first = series->time(0);
  REQUIRE(first == 2333664000.0);
  CHECK(resolve_time("2024-01-01", "--t0", first, series.get()) == first);
  CHECK(resolve_time("2024-01-01 12:00", "--t1", first, series.get()) == first + 43200);
  CHECK(resolve_time("2024-01-02T06:30:00Z", "--t1", first, series.get()) == first + 109800);
  CHECK(resolve_time("0 days", "--t0", first, series.get()) == first);
  CHECK(resolve_time("12 hours", "--t1", first, series.get()) == first + 43200);
  CHECK(resolve_time("1.5 d", "--t1", first, series.get()) == first + 129600);
  CHECK(resolve_time("2333664000", "--t0", 0, series.get()) == first);
  CHECK(resolve_time("7.5", "--t1", 0, nullptr) == 7.5);
  // Months have no fixed length; a date needs a calendar the field has.
  CHECK_THROWS_WITH(resolve_time("2 months", "--t1", first, series.get()),
                    Catch::Contains("--t1 '2 months': unit 'months'"));
  CHECK_THROWS_WITH(resolve_time("2024-13-01", "--t0", first, series.get()),
                    Catch::Contains("--t0 '2024-13-01': not a date"));
  CHECK_THROWS_WITH(resolve_time("2024-01-02", "--t1", 0, nullptr),
                    Catch::Contains("--t1 '2024-01-02': durations and dates need"));
  CHECK_THROWS_WITH(resolve_time("soon", "--t1", 0, nullptr), Catch::Contains("expected a number"));

  // On the command line: the same mesh, byte for byte, as the times given in seconds.
  const std::string field = " --field " + quoted(days / "day*.nc") +
                            " --seed line:12,2,0:12,6,0 --edge 0.1 --quiet --out ";
  const auto by_number = cli_test::run("path" + field + quoted(dir / "numbers.vtp") +
                                       " --t0 2333664000 --t1 2333674800");
  const auto by_date = cli_test::run("path" + field + quoted(dir / "dates.vtp") +
                                     " --t0 2024-01-01 --t1 '3 hours'");
  INFO(by_number.output << by_date.output);
  REQUIRE(by_number.status == 0);
  REQUIRE(by_date.status == 0);
  CHECK(read_text(dir / "dates.vtp") == read_text(dir / "numbers.vtp"));
  const auto months = cli_test::run("path" + field + quoted(dir / "m.vtp") + " --t1 '2 months'");
  CHECK(months.status == 2);
  CHECK(months.output.find("--t1 '2 months': unit 'months'") != std::string::npos);
}

TEST_CASE("NetCDF: velocities in m/s or cm/s move positions in the axes' own length units",
          "[apps][netcdf]") {
  // Every component 1 in the file's velocity unit: x, y in km and z in m with m/s; all in metres
  // with cm/s. An axis in hPa (pressure levels) cannot be related to m/s.
  TempDir dir;
  namespace io = orthofront::io;
  const auto write = [&](const fs::path& file, const char* xy_units, const char* z_units,
                         const char* velocity_units) {
    int nc = 0;
    ok(nc_create(file.c_str(), NC_CLOBBER, &nc));
    int dims[3] = {}, axes[3] = {}, ids[3] = {};
    const char* names[3] = {"z", "y", "x"};
    for (int a = 0; a < 3; ++a) {
      ok(nc_def_dim(nc, names[a], 3, &dims[a]));
      ok(nc_def_var(nc, names[a], NC_DOUBLE, 1, &dims[a], &axes[a]));
      const char* units = a == 0 ? z_units : xy_units;
      ok(nc_put_att_text(nc, axes[a], "units", std::strlen(units), units));
    }
    const char* components[3] = {"u", "v", "w"};
    for (int c = 0; c < 3; ++c) {
      ok(nc_def_var(nc, components[c], NC_DOUBLE, 3, dims, &ids[c]));
      ok(nc_put_att_text(nc, ids[c], "units", std::strlen(velocity_units), velocity_units));
    }
    ok(nc_enddef(nc));
    const double coordinate[3] = {0, 1, 2};
    for (int a = 0; a < 3; ++a) ok(nc_put_var_double(nc, axes[a], coordinate));
    const std::vector<double> one(27, 1.0);
    for (int c = 0; c < 3; ++c) ok(nc_put_var_double(nc, ids[c], one.data()));
    ok(nc_close(nc));
  };
  io::NetcdfOptions o;
  o.dt = 1;
  const auto first_vector = [&](const fs::path& file) {
    const auto series = io::open_netcdf_series({file}, o);
    std::vector<float> values(series->step_floats());
    series->read(0, values);
    return std::array<float, 3>{values[0], values[1], values[2]};
  };
  write(dir / "km.nc", "km", "m", "m s-1");
  CHECK(first_vector(dir / "km.nc") == std::array<float, 3>{0.001f, 0.001f, 1.0f});
  write(dir / "cm.nc", "m", "m", "cm/s");
  CHECK(first_vector(dir / "cm.nc") == std::array<float, 3>{0.01f, 0.01f, 0.01f});
  write(dir / "plain.nc", "m", "m", "m/s");
  CHECK(first_vector(dir / "plain.nc") == std::array<float, 3>{1.0f, 1.0f, 1.0f});
  write(dir / "hpa.nc", "m", "hPa", "m/s");
  CHECK_THROWS_WITH(first_vector(dir / "hpa.nc"),
                    Catch::Contains("axis 'z' is in 'hPa', not a length"));
  const auto km = io::open_netcdf_series({dir / "km.nc"}, o);
  CHECK_THAT(io::netcdf_description(*km)->coordinates,
             Catch::Contains("x velocities m s-1 x 0.001"));
}
