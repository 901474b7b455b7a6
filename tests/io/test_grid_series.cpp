// Time series of grid files: a list of files with given times, a ParaView .pvd collection,
// steps that do not match, and the format dispatch by extension.
#include <cmath>

#include "io/grid_test_support.h"
#include "orthofront/error.h"
#include "orthofront/io/error.h"
#include "orthofront/io/grid_file.h"
#include "orthofront/io/grid_series.h"

using Catch::Matchers::Contains;
using orthofront::InvalidArgument;
using orthofront::VectorGrid;
using orthofront::io::FormatError;
using orthofront::io::GridFileSeries;
using orthofront::io::open_pvd;
using namespace grid_test;

namespace {

/// An uncompressed inline-ascii .vti of `grid` with every value offset by `shift`.
std::string ascii_vti(const VectorGrid& grid, float shift, int nx_override = 0) {
  const auto& n = grid.geometry.size;
  std::string text = "<VTKFile type=\"ImageData\"><ImageData WholeExtent=\"0 " +
                     std::to_string((nx_override ? nx_override : n[0]) - 1) + " 0 " +
                     std::to_string(n[1] - 1) + " 0 " + std::to_string(n[2] - 1) +
                     "\" Origin=\"0 0 0\" Spacing=\"1 1 1\"><Piece Extent=\"0 " +
                     std::to_string((nx_override ? nx_override : n[0]) - 1) + " 0 " +
                     std::to_string(n[1] - 1) + " 0 " + std::to_string(n[2] - 1) +
                     "\"><PointData><DataArray type=\"Float32\" Name=\"v\" NumberOfComponents=\"3\" "
                     "format=\"ascii\">";
  for (const float v : grid.values) text += std::to_string(v + shift) + " ";
  return text + "</DataArray></PointData></Piece></ImageData></VTKFile>";
}

}  // namespace

TEST_CASE("grid series: a .pvd collection gives its files in time order", "[series][vti]") {
  TempDir dir("series");
  const VectorGrid grid = sample_grid(4, 3, 2);
  fs::create_directories(dir / "data");
  for (int s = 0; s < 3; ++s)
    write_file(dir / ("data/step" + std::to_string(s) + ".vti"), ascii_vti(grid, static_cast<float>(s)));
  write_file(dir / "flow.pvd",
             "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n<Collection>\n"
             "  <DataSet timestep=\"0.5\" group=\"\" part=\"0\" file=\"data/step1.vti\"/>\n"
             "  <DataSet timestep=\"0\" group=\"\" part=\"0\" file=\"data/step0.vti\"/>\n"
             "  <DataSet timestep=\"2.25\" group=\"\" part=\"0\" file=\"data/step2.vti\"/>\n"
             "</Collection>\n</VTKFile>\n");
  const auto series = open_pvd(dir / "flow.pvd");
  REQUIRE(series->step_count() == 3);
  CHECK(series->time(0) == 0.0);
  CHECK(series->time(1) == 0.5);
  CHECK(series->time(2) == 2.25);
  CHECK(series->components() == 3);
  CHECK(series->geometry().size == grid.geometry.size);
  CHECK(series->step_floats() == grid.values.size());
  CHECK_THAT(series->describe(), Contains("3 VTK XML ImageData files"));
  // Zero vectors are no data (solid, land) in a series of grid files, as in one grid file and
  // as `info` says: path and streak surfaces stop there.
  CHECK(series->zero_is_no_data());
  for (std::size_t s = 0; s < 3; ++s) {
    std::vector<float> values(series->step_floats());
    series->read(s, values);
    std::vector<float> expected = grid.values;
    for (float& v : expected) v += static_cast<float>(s);
    CHECK(same_values(values, expected));
  }
}

TEST_CASE("grid series: bad lists and mismatched steps are rejected", "[series]") {
  TempDir dir("series");
  const VectorGrid grid = sample_grid(4, 3, 2);
  write_file(dir / "a.vti", ascii_vti(grid, 0));
  write_file(dir / "b.vti", ascii_vti(grid, 1));
  VectorGrid wider = sample_grid(5, 3, 2);
  write_file(dir / "c.vti", ascii_vti(wider, 0));

  CHECK_THAT(thrown<InvalidArgument>([&] {
               GridFileSeries({dir / "a.vti", dir / "b.vti"}, {1.0, 1.0});
             }),
             Contains("strictly increasing"));
  CHECK_THAT(thrown<InvalidArgument>([&] { GridFileSeries({dir / "a.vti"}, {0.0, 1.0}); }),
             Contains("1 files but 2 times"));
  CHECK_THAT(thrown<InvalidArgument>([&] { GridFileSeries({dir / "a.txt"}, {0.0}); }),
             Contains("a.txt") && Contains("unknown grid file extension"));

  const GridFileSeries series({dir / "a.vti", dir / "b.vti", dir / "c.vti"}, {0.0, 1.0, 2.0});
  std::vector<float> values(series.step_floats());
  series.read(1, values);
  CHECK(values[0] == grid.values[0] + 1.0f);
  CHECK_THAT(thrown<FormatError>([&] { series.read(2, values); }),
             Contains("c.vti") && Contains("step 2") && Contains("5 x 3 x 2") &&
                 Contains("4 x 3 x 2"));

  write_file(dir / "bad.pvd", "<VTKFile type=\"Collection\"><Collection>"
                              "<DataSet timestep=\"0\" part=\"0\" file=\"a.vti\"/>"
                              "<DataSet timestep=\"0\" part=\"1\" file=\"b.vti\"/>"
                              "</Collection></VTKFile>");
  CHECK_THAT(thrown<FormatError>([&] { open_pvd(dir / "bad.pvd"); }),
             Contains("bad.pvd") && Contains("part 1"));
  write_file(dir / "twice.pvd", "<VTKFile type=\"Collection\"><Collection>"
                                "<DataSet timestep=\"1\" file=\"a.vti\"/>"
                                "<DataSet timestep=\"1\" file=\"b.vti\"/>"
                                "</Collection></VTKFile>");
  CHECK_THAT(thrown<FormatError>([&] { open_pvd(dir / "twice.pvd"); }),
             Contains("twice.pvd") && Contains("listed twice"));
}

TEST_CASE("grid series: file specs with a selector", "[series]") {
  using orthofront::io::parse_grid_source;
  CHECK_FALSE(parse_grid_source("abc"));
  CHECK_FALSE(parse_grid_source("lorenz:rho=28"));
  const auto plain = parse_grid_source("data/flow.vti");
  REQUIRE(plain);
  CHECK(plain->path == "data/flow.vti");
  CHECK(plain->selector.empty());
  const auto named = parse_grid_source("flow.vdb:velocity");
  REQUIRE(named);
  CHECK(named->path == "flow.vdb");
  CHECK(named->selector == "velocity");
}

TEST_CASE("grid series: the tornado steps as a series", "[series][vec][realdata]") {
  const fs::path dir = datasets_dir("tornado");
  if (dir.empty()) return;
  std::vector<fs::path> files;
  for (int s = 1; s <= 10; ++s) files.push_back(dir / (std::to_string(s) + ".vec"));
  const GridFileSeries series(files, orthofront::io::evenly_spaced_times(10, 0.0, 0.1));
  CHECK(series.step_count() == 10);
  CHECK(series.time(9) == Approx(0.9));
  std::vector<float> first(series.step_floats());
  std::vector<float> last(series.step_floats());
  series.read(0, first);
  series.read(9, last);
  CHECK(first != last);  // the tornado moves
}
