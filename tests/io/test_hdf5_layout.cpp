// The project's HDF5 layout: exact round trips (steady and series, both storages, with and
// without compression, uniform and rectilinear, 2D and 3D), raw + decode against HDF5's own
// decoding, fill values, the XDMF sidecar, and every malformed file giving a message that names
// the file, the dataset and the value.
#include <hdf5.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "temp_dir.h"
#include "orthofront/error.h"
#include "orthofront/io/error.h"
#include "orthofront/io/hdf5_layout.h"

using namespace orthofront;
using namespace orthofront::io;
namespace fs = std::filesystem;

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

using test_support::TempDir;

GridGeometry uniform(int dimension, std::int64_t nx, std::int64_t ny, std::int64_t nz) {
  GridGeometry g;
  g.dimension = dimension;
  g.size = {nx, ny, dimension == 2 ? 1 : nz};
  g.origin = Vec3(-1.5, 0.25, dimension == 2 ? 0.75 : -3);
  g.spacing = Vec3(0.5, 0.125, dimension == 2 ? 1 : 0.3);
  return g;
}

GridGeometry rectilinear(int dimension, std::int64_t nx, std::int64_t ny, std::int64_t nz) {
  GridGeometry g = uniform(dimension, nx, ny, nz);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> step(0.1, 1.0);
  for (int a = 0; a < 3; ++a) {
    auto& axis = g.axes[static_cast<std::size_t>(a)];
    axis = {-2.0 + a};
    while (static_cast<std::int64_t>(axis.size()) < g.size[static_cast<std::size_t>(a)])
      axis.push_back(axis.back() + step(rng));
  }
  return g;
}

// Deterministic pseudo-random samples with some NaN, some zero vectors and exact extremes.
std::vector<float> samples(const GridGeometry& g, int components, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> value(0.0f, 3.0f);
  std::vector<float> v(g.point_count() * static_cast<std::size_t>(components));
  for (float& x : v) x = value(rng);
  for (std::size_t p = 0; p < g.point_count(); p += 37)
    v[p * static_cast<std::size_t>(components)] = kNaN;
  for (std::size_t p = 5; p < g.point_count(); p += 53)
    for (int c = 0; c < components; ++c)
      v[p * static_cast<std::size_t>(components) + static_cast<std::size_t>(c)] = 0.0f;
  v[1] = std::numeric_limits<float>::max();
  v[2] = -std::numeric_limits<float>::denorm_min();
  return v;
}

// A steady field of `samples` (seed 1) on a uniform 7 x 5 (x 4) grid.
VectorGrid sampled_grid(int dimension, int components) {
  VectorGrid grid;
  grid.geometry = uniform(dimension, 7, 5, 4);
  grid.components = components;
  grid.values = samples(grid.geometry, components, 1);
  return grid;
}

// Bitwise equality (NaN == NaN).
bool same_bits(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

bool same_geometry(const GridGeometry& a, const GridGeometry& b) {
  if (a.dimension != b.dimension || a.size != b.size || a.rectilinear() != b.rectilinear())
    return false;
  if (a.rectilinear()) return a.axes == b.axes;
  for (int i = 0; i < a.dimension; ++i)
    if (a.origin[i] != b.origin[i] || a.spacing[i] != b.spacing[i]) return false;
  return a.origin.z() == b.origin.z();
}

std::vector<float> read_step(const TimeSeries& series, std::size_t step) {
  std::vector<float> values(series.step_floats());
  series.read(step, values);
  return values;
}

template <class F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

// --- hand-made files for the error cases -----------------------------------------------------

struct H5File {
  hid_t id;
  explicit H5File(const fs::path& p) {
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
    id = H5Fcreate(p.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    REQUIRE(id >= 0);
  }
  ~H5File() { H5Fclose(id); }
  void dataset(const char* name, const std::vector<hsize_t>& dims, hid_t type = H5T_IEEE_F32LE) {
    hid_t space = H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr);
    hid_t set = H5Dcreate2(id, name, type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    REQUIRE(set >= 0);
    std::size_t n = 1;
    for (hsize_t d : dims) n *= d;
    std::vector<double> zeros(std::max<std::size_t>(n, 1), 1.0);
    if (n > 0) H5Dwrite(set, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, zeros.data());
    H5Dclose(set);
    H5Sclose(space);
  }
  void doubles(const char* name, const std::vector<double>& values) {
    const hsize_t n = values.size();
    hid_t space = H5Screate_simple(1, &n, nullptr);
    hid_t set = H5Dcreate2(id, name, H5T_IEEE_F64LE, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    if (n > 0) H5Dwrite(set, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data());
    H5Dclose(set);
    H5Sclose(space);
  }
  void attribute(const char* name, const std::vector<double>& values) {
    const hsize_t n = values.size();
    hid_t space = H5Screate_simple(1, &n, nullptr);
    hid_t a = H5Acreate2(id, name, H5T_IEEE_F64LE, space, H5P_DEFAULT, H5P_DEFAULT);
    H5Awrite(a, H5T_NATIVE_DOUBLE, values.data());
    H5Aclose(a);
    H5Sclose(space);
  }
  void grid_attributes() {
    attribute("origin", {0, 0, 0});
    attribute("spacing", {1, 1, 1});
  }
};

// Parses an XDMF file with xml.etree and lists what a reader would follow.
const char* kXdmfScript = R"PY(
import sys, xml.etree.ElementTree as ET
root = ET.parse(sys.argv[1]).getroot()
assert root.tag == 'Xdmf', root.tag
grids = [g for g in root.iter('Grid') if g.get('GridType') == 'Uniform']
print('grids', len(grids))
for g in grids:
    t = g.find('Time')
    topo = g.find('Topology')
    geo = g.find('Geometry')
    att = g.find('Attribute')
    print('time', t.get('Value') if t is not None else '-')
    print('topology', topo.get('TopologyType'), topo.get('Dimensions'))
    print('geometry', geo.get('GeometryType'), len(list(geo)))
    assert att.get('AttributeType') == 'Vector' and att.get('Center') == 'Node'
    outer = att.find('DataItem')
    print('values', outer.get('Dimensions'), outer.get('ItemType') or 'Plain')
    for item in g.iter('DataItem'):
        if item.get('Format') == 'HDF':
            print('ref', item.text.strip(), item.get('Dimensions'))
)PY";

// Runs the XDMF listing script on `xmf` (the script and its output live beside it, removed after).
std::string list_xdmf(const fs::path& xmf) {
  const fs::path script_file = xmf.parent_path() / "check.py";
  const fs::path output = xmf.parent_path() / "check.out";
  std::ofstream(script_file) << kXdmfScript;
  const std::string command = "python3 '" + script_file.string() + "' '" + xmf.string() + "' > '" +
                              output.string() + "' 2>&1";
  const int rc = std::system(command.c_str());
  std::stringstream text;
  text << std::ifstream(output).rdbuf();
  fs::remove(script_file);
  fs::remove(output);
  if (rc != 0) return "PYTHON FAILED (" + std::to_string(rc) + "): " + text.str();
  return text.str();
}

bool python_available() {
  return std::system("python3 -c pass > /dev/null 2>&1") == 0;
}

}  // namespace

TEST_CASE("steady fields round-trip exactly", "[hdf5]") {
  TempDir dir;
  for (int dimension : {2, 3}) {
    for (bool rect : {false, true}) {
      for (int gzip : {0, 6}) {
        for (int components : {2, 3}) {
          DYNAMIC_SECTION(dimension << "D " << (rect ? "rectilinear" : "uniform") << " gzip "
                                    << gzip << " components " << components) {
            VectorGrid grid;
            grid.geometry = rect ? rectilinear(dimension, 7, 5, 4) : uniform(dimension, 7, 5, 4);
            grid.components = components;
            grid.values = samples(grid.geometry, components, 1);
            Hdf5WriteOptions options;
            options.gzip_level = gzip;
            options.units = {"m", "s", "m/s"};
            options.zero_is_no_data = false;
            const fs::path file = dir / "steady.h5";
            write_hdf5_grid(grid, file, options);
            CHECK(fs::exists(xdmf_path(file)));
            const VectorGrid back = read_hdf5_grid(file);
            CHECK(same_geometry(back.geometry, grid.geometry));
            CHECK(back.components == components);
            CHECK(same_bits(back.values, grid.values));
            const Hdf5Description d = describe_hdf5(file);
            CHECK(d.storage == Hdf5Storage::steady);
            CHECK(d.units.length == "m");
            CHECK(d.units.time == "s");
            CHECK(d.units.velocity == "m/s");
            CHECK_FALSE(d.zero_is_no_data);
            CHECK(d.gzip_level == gzip);
            CHECK(d.stored_type == "float32 little-endian");
            if (gzip > 0) CHECK(d.filters == std::vector<std::string>{"shuffle", "deflate"});
            CHECK(dir.entries() == std::vector<std::string>{"steady.h5", "steady.xmf"});
          }
        }
      }
    }
  }
}

TEST_CASE("time series round-trip exactly in both storages", "[hdf5]") {
  TempDir dir;
  const std::vector<double> times{0.0, 0.5, 1.25, 4.0};
  for (Hdf5Storage storage : {Hdf5Storage::chunked, Hdf5Storage::per_step}) {
    for (int gzip : {0, 1}) {
      for (bool rect : {false, true}) {
        for (int dimension : {2, 3}) {
          DYNAMIC_SECTION(to_string(storage)
                          << " gzip " << gzip << (rect ? " rectilinear " : " uniform ") << dimension
                          << "D") {
            const GridGeometry g =
                rect ? rectilinear(dimension, 6, 5, 3) : uniform(dimension, 6, 5, 3);
            const int components = dimension;
            Hdf5WriteOptions options;
            options.storage = storage;
            options.gzip_level = gzip;
            options.group = "/flow/run1";
            const fs::path file = dir / "series.h5";
            std::vector<std::vector<float>> steps;
            {
              Hdf5SeriesWriter writer(file, g, components, times, options);
              for (std::size_t s = 0; s < times.size(); ++s) {
                steps.push_back(samples(g, components, 10u + static_cast<unsigned>(s)));
                writer.write_step(steps.back());
              }
              CHECK_FALSE(fs::exists(file));  // only the temporary file exists until commit
              writer.commit();
            }
            CHECK(fs::exists(file));
            CHECK(fs::exists(xdmf_path(file)));
            for (bool raw : {true, false}) {
              Hdf5ReadOptions read_options;
              read_options.raw_chunks = raw;
              const auto series = open_hdf5_series(file, "/flow/run1", read_options);
              REQUIRE(series->step_count() == times.size());
              CHECK(series->components() == components);
              CHECK(same_geometry(series->geometry(), g));
              for (std::size_t s = 0; s < times.size(); ++s) {
                CHECK(series->time(s) == times[s]);
                CHECK(same_bits(read_step(*series, s), steps[s]));
                CHECK(series->read_raw(s).encoded == (raw && gzip > 0));
              }
              CHECK(series->description().storage == storage);
            }
            // A step can also be read as a grid; a dataset path picks the same field.
            CHECK(same_bits(read_hdf5_grid(file, "/flow/run1", 2).values, steps[2]));
            if (storage == Hdf5Storage::chunked)
              CHECK(open_hdf5_series(file, "/flow/run1/velocity")->step_count() == times.size());
          }
        }
      }
    }
  }
}

TEST_CASE("raw chunk reads decoded in parallel equal HDF5's own decoding", "[hdf5]") {
  TempDir dir;
  const GridGeometry g = uniform(3, 40, 30, 20);
  const std::vector<double> times{1, 2, 3};
  for (bool library_filters : {false, true}) {
    for (std::size_t max_chunk : {std::size_t{1} << 30, std::size_t{40 * 30 * 3 * 4 * 3}}) {
      for (bool shuffle : {true, false}) {
        DYNAMIC_SECTION((library_filters ? "HDF5 filters" : "parallel compression")
                        << ", chunk limit " << max_chunk << (shuffle ? ", shuffle" : "")) {
          Hdf5WriteOptions options;
          options.storage = Hdf5Storage::chunked;  // slices: whole-step raw reads
          options.gzip_level = 4;
          options.shuffle = shuffle;
          options.parallel_compression = !library_filters;
          options.max_chunk_bytes = max_chunk;  // small: 3 z-slices per chunk, 7 chunks a step
          const fs::path file = dir / "raw.h5";
          {
            Hdf5SeriesWriter writer(file, g, 3, times, options);
            for (unsigned s = 0; s < 3; ++s) writer.write_step(samples(g, 3, s));
            writer.commit();
          }
          Hdf5ReadOptions plain;
          plain.raw_chunks = false;
          const auto raw_series = open_hdf5_series(file);
          const auto plain_series = open_hdf5_series(file, "/", plain);
          CHECK(raw_series->describe().find("raw chunk reads") != std::string::npos);
          CHECK(raw_series->description().chunk_slices == (max_chunk > 1000000 ? 20 : 3));
          for (std::size_t s = 0; s < 3; ++s) {
            const RawStep raw = raw_series->read_raw(s);
            REQUIRE(raw.encoded);
            CHECK(raw.bytes.size() < raw_series->step_bytes());  // still compressed
            std::vector<float> decoded(raw_series->step_floats());
            raw_series->decode(raw, decoded);
            CHECK(same_bits(decoded, read_step(*plain_series, s)));
            CHECK(same_bits(decoded, samples(g, 3, static_cast<unsigned>(s))));
          }
          // Damaged raw bytes are reported, naming the file and the step.
          RawStep broken = raw_series->read_raw(1);
          broken.bytes[broken.bytes.size() - 10] ^= std::byte{0x5a};
          broken.bytes[broken.bytes.size() / 2] ^= std::byte{0xa5};
          std::vector<float> out(raw_series->step_floats());
          const std::string message = error_of([&] { raw_series->decode(broken, out); });
          CHECK_THAT(message, Catch::Contains("raw.h5") && Catch::Contains("step 1"));
        }
      }
    }
  }
}

TEST_CASE("fill values become NaN", "[hdf5]") {
  TempDir dir;
  VectorGrid grid;
  grid.geometry = uniform(3, 4, 4, 4);
  grid.values = samples(grid.geometry, 3, 2);
  SECTION("written by the layout writer") {
    Hdf5WriteOptions options;
    options.fill_value = -9999.0f;
    for (int gzip : {0, 3}) {
      options.gzip_level = gzip;
      write_hdf5_grid(grid, dir / "fill.h5", options);
      CHECK(describe_hdf5(dir / "fill.h5").fill_value == -9999.0f);
      CHECK(same_bits(read_hdf5_grid(dir / "fill.h5").values, grid.values));
    }
  }
  SECTION("a _FillValue attribute written by another tool") {
    {
      H5File f(dir / "other.h5");
      f.grid_attributes();
      f.dataset("velocity", {2, 2, 2, 3});  // all ones
      f.attribute("_FillValue", {1.0});
    }
    const VectorGrid back = read_hdf5_grid(dir / "other.h5");
    REQUIRE(back.values.size() == 24);
    for (float v : back.values) CHECK(std::isnan(v));
  }
}

TEST_CASE("the XDMF sidecar is valid XML that points at the datasets", "[hdf5][xdmf]") {
  if (!python_available()) {
    WARN("python3 not found: XDMF parsing check skipped");
    return;
  }
  TempDir dir;
  SECTION("steady uniform 3D") {
    write_hdf5_grid(sampled_grid(3, 3), dir / "a&b.h5");
    const std::string parsed = list_xdmf(dir / "a&b.xmf");
    CHECK(parsed ==
          "grids 1\ntime -\ntopology 3DCoRectMesh 4 5 7\ngeometry ORIGIN_DXDYDZ 2\n"
          "values 4 5 7 3 Plain\nref a&b.h5:/velocity 4 5 7 3\n");
  }
  SECTION("chunked series, rectilinear 2D, in a group") {
    Hdf5WriteOptions options;
    options.group = "/g";
    const GridGeometry g = rectilinear(2, 6, 5, 1);
    {
      Hdf5SeriesWriter writer(dir / "s.h5", g, 2, {0.5, 1.5}, options);
      writer.write_step(samples(g, 2, 1));
      writer.write_step(samples(g, 2, 2));
      writer.commit();
    }
    const std::string parsed = list_xdmf(dir / "s.xmf");
    CHECK(parsed ==
          "grids 2\n"
          "time 0.5\ntopology 3DRectMesh 1 5 6\ngeometry VXVYVZ 3\nvalues 1 5 6 2 HyperSlab\n"
          "ref s.h5:/g/x 6\nref s.h5:/g/y 5\nref s.h5:/g/velocity 2 5 6 2\n"
          "time 1.5\ntopology 3DRectMesh 1 5 6\ngeometry VXVYVZ 3\nvalues 1 5 6 2 HyperSlab\n"
          "ref s.h5:/g/x 6\nref s.h5:/g/y 5\nref s.h5:/g/velocity 2 5 6 2\n");
    // Every referenced dataset exists in the file.
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
    const hid_t f = H5Fopen((dir / "s.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
    for (const char* path : {"/g/x", "/g/y", "/g/velocity"})
      CHECK(H5Lexists(f, path, H5P_DEFAULT) > 0);
    H5Fclose(f);
  }
  SECTION("steady uniform 2D: one z layer, so ParaView places it in z = 0") {
    write_hdf5_grid(sampled_grid(2, 2), dir / "flat.h5");
    const std::string parsed = list_xdmf(dir / "flat.xmf");
    CHECK(parsed ==
          "grids 1\ntime -\ntopology 3DCoRectMesh 1 5 7\ngeometry ORIGIN_DXDYDZ 2\n"
          "values 1 5 7 2 Plain\nref flat.h5:/velocity 1 5 7 2\n");
  }
  SECTION("Blosc-compressed files get no sidecar, and a stale one goes") {
    const VectorGrid grid = sampled_grid(3, 3);
    write_hdf5_grid(grid, dir / "c.h5");
    REQUIRE(fs::exists(dir / "c.xmf"));
    Hdf5WriteOptions options;
    options.codec = Hdf5Codec::lz4;
    write_hdf5_grid(grid, dir / "c.h5", options);
    CHECK_FALSE(fs::exists(dir / "c.xmf"));
    CHECK(same_bits(read_hdf5_grid(dir / "c.h5").values, grid.values));
  }
  SECTION("per-step series") {
    Hdf5WriteOptions options;
    options.storage = Hdf5Storage::per_step;
    const GridGeometry g = uniform(3, 3, 3, 3);
    {
      Hdf5SeriesWriter writer(dir / "p.h5", g, 3, {0, 1}, options);
      writer.write_step(samples(g, 3, 1));
      writer.write_step(samples(g, 3, 2));
      writer.commit();
    }
    const std::string parsed = list_xdmf(dir / "p.xmf");
    CHECK_THAT(parsed, Catch::Contains("ref p.h5:/steps/000000 3 3 3 3") &&
                           Catch::Contains("ref p.h5:/steps/000001 3 3 3 3") &&
                           Catch::Contains("time 1\n"));
  }
}

TEST_CASE("bad files give errors naming the file, the dataset and the value", "[hdf5][errors]") {
  TempDir dir;
  const fs::path file = dir / "bad.h5";
  const auto open_error = [&](const std::string& group = "/") {
    return error_of([&] { open_hdf5_series(file, group); });
  };
  const auto read_error = [&]() { return error_of([&] { read_hdf5_grid(file); }); };

  SECTION("missing file") {
    CHECK_THAT(read_error(), Catch::Contains("cannot open") && Catch::Contains("bad.h5") &&
                                 Catch::Contains("no such file"));
  }
  SECTION("not an HDF5 file") {
    std::ofstream(file) << "hello";
    CHECK_THAT(read_error(), Catch::Contains("bad.h5 is not an HDF5 file"));
  }
  SECTION("missing dataset") {
    { H5File f(file); }
    CHECK_THAT(read_error(),
               Catch::Contains("bad.h5") && Catch::Contains("no dataset '/velocity'"));
    CHECK_THAT(open_error("/nowhere/field"), Catch::Contains("no group or dataset '/nowhere'"));
  }
  SECTION("missing attribute") {
    {
      H5File f(file);
      f.dataset("velocity", {2, 2, 2, 3});
    }
    CHECK_THAT(read_error(), Catch::Contains("bad.h5: group '/' has no attribute 'origin'"));
    {
      H5File f(file);
      f.dataset("velocity", {2, 2, 2, 3});
      f.attribute("origin", {0, 0, 0});
    }
    CHECK_THAT(read_error(), Catch::Contains("no attribute 'spacing'"));
  }
  SECTION("not a vector field") {
    {
      H5File f(file);
      f.grid_attributes();
      f.dataset("velocity", {2, 2, 2, 4});
    }
    CHECK_THAT(read_error(), Catch::Contains("bad.h5") && Catch::Contains("'/velocity'") &&
                                 Catch::Contains("not a vector field") &&
                                 Catch::Contains("last dimension is 4"));
  }
  SECTION("wrong dimensions") {
    {
      H5File f(file);
      f.grid_attributes();
      f.dataset("velocity", {8, 3});
    }
    CHECK_THAT(read_error(), Catch::Contains("'/velocity' has shape [8][3]"));
    {
      H5File f(file);
      f.grid_attributes();
      f.dataset("velocity", {2, 2, 2, 3});
      f.attribute("dimension", {2});
    }
    CHECK_THAT(read_error(), Catch::Contains("attribute 'dimension' is 2") &&
                                 Catch::Contains("[2][2][2][3] (3D)"));
    {
      H5File f(file);
      f.grid_attributes();
      f.doubles("times", {0, 1, 2});
      f.dataset("velocity", {2, 2, 2, 2, 3});
    }
    CHECK_THAT(open_error(), Catch::Contains("holds 2 steps but '/times' has 3 times"));
    {
      H5File f(file);
      f.doubles("x", {0, 1, 2});
      f.doubles("y", {0, 1});
      f.doubles("z", {0, 1});
      f.dataset("velocity", {2, 2, 2, 3});
    }
    CHECK_THAT(read_error(),
               Catch::Contains("'/x' has shape [3]") && Catch::Contains("2 samples along x"));
  }
  SECTION("empty time series") {
    {
      H5File f(file);
      f.grid_attributes();
      f.doubles("times", {});
      f.dataset("velocity", {0, 2, 2, 2, 3});
    }
    CHECK_THAT(open_error(), Catch::Contains("bad.h5: dataset '/times' is empty"));
  }
  SECTION("non-increasing times") {
    {
      H5File f(file);
      f.grid_attributes();
      f.doubles("times", {0, 1, 1});
      f.dataset("velocity", {3, 2, 2, 2, 3});
    }
    CHECK_THAT(open_error(), Catch::Contains("'/times' is not strictly increasing: times[2] = 1 "
                                             "after times[1] = 1"));
  }
  SECTION("a steady file opened as a series, a per-step series with a step missing") {
    {
      H5File f(file);
      f.grid_attributes();
      f.dataset("velocity", {2, 2, 2, 3});
    }
    CHECK_THAT(open_error(), Catch::Contains("is a steady field, not a time series"));
    {
      H5File f(file);
      f.grid_attributes();
      f.doubles("times", {0, 1});
      H5Gclose(H5Gcreate2(f.id, "steps", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
      f.dataset("steps/000000", {2, 2, 2, 3});
    }
    // Opening succeeds (a surface can run up to the gap); reading the missing step names it.
    const auto series = open_hdf5_series(file);
    CHECK(series->description().missing_steps == std::vector<std::size_t>{1});
    CHECK_THAT(error_of([&] { series->read_raw(1); }),
               Catch::Contains("no dataset '/steps/000001' (step 1 of 2)"));
  }
}

TEST_CASE("no output file is left behind on failure", "[hdf5][errors]") {
  TempDir dir;
  const GridGeometry g = uniform(3, 3, 3, 3);
  SECTION("writer destroyed before commit") {
    {
      Hdf5SeriesWriter writer(dir / "a.h5", g, 3, {0, 1});
      writer.write_step(samples(g, 3, 1));
    }
    CHECK(dir.entries().empty());
  }
  SECTION("commit with steps missing") {
    {
      Hdf5SeriesWriter writer(dir / "a.h5", g, 3, {0, 1, 2});
      writer.write_step(samples(g, 3, 1));
      CHECK_THAT(error_of([&] { writer.commit(); }), Catch::Contains("1 of 3 steps written"));
    }
    CHECK(dir.entries().empty());
  }
  SECTION("bad times, bad sizes, bad folder") {
    CHECK_THAT(error_of([&] { Hdf5SeriesWriter w(dir / "a.h5", g, 3, {}); }),
               Catch::Contains("at least one step"));
    CHECK_THAT(error_of([&] {
                 Hdf5SeriesWriter w(dir / "a.h5", g, 3, {0, 2, 1});
               }),
               Catch::Contains("strictly increasing; time 2"));
    {
      Hdf5SeriesWriter writer(dir / "a.h5", g, 3, {0});
      CHECK_THAT(error_of([&] { writer.write_step(std::vector<float>(5)); }),
                 Catch::Contains("needs 81 floats, got 5"));
    }
    VectorGrid grid;
    grid.geometry = g;
    grid.values = samples(g, 3, 1);
    CHECK_THAT(error_of([&] { write_hdf5_grid(grid, dir / "missing" / "a.h5"); }),
               Catch::Contains("missing"));
    grid.geometry = rectilinear(3, 3, 3, 3);
    grid.geometry.axes[1][2] = grid.geometry.axes[1][1];
    CHECK_THAT(error_of([&] { write_hdf5_grid(grid, dir / "a.h5"); }),
               Catch::Contains("axis 1 must be finite and strictly increasing; entry 2"));
    CHECK(dir.entries().empty());
  }
}
