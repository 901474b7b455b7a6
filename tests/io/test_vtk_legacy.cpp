// Legacy VTK reader: STRUCTURED_POINTS and RECTILINEAR_GRID, ASCII and big-endian BINARY, other
// arrays skipped; bad files rejected.
#include <cmath>

#include "io/grid_test_support.h"
#include "io/hostile_file.h"
#include "orthofront/io/error.h"
#include "orthofront/io/grid_file.h"
#include "orthofront/io/vtk_legacy_reader.h"

using Catch::Matchers::Contains;
using orthofront::Vec3;
using orthofront::VectorGrid;
using orthofront::io::FormatError;
using orthofront::io::read_vtk_legacy;
using namespace grid_test;

namespace {

std::string ascii_values(const std::vector<float>& values, std::size_t per_line) {
  std::string text;
  for (std::size_t i = 0; i < values.size(); ++i)
    text += std::to_string(values[i]) + ((i + 1) % per_line == 0 ? "\n" : " ");
  return text;
}

/// A STRUCTURED_POINTS file with a scalar array, then the vectors, then cell data.
std::string vtk_file(const VectorGrid& grid, bool binary, const std::string& type = "float") {
  const auto& n = grid.geometry.size;
  const std::size_t points = grid.geometry.point_count();
  std::vector<float> pressure(points);
  for (std::size_t i = 0; i < points; ++i) pressure[i] = static_cast<float>(i) * 0.5f;
  const auto data = [&](const std::vector<float>& values, std::size_t per_line) {
    if (!binary) return ascii_values(values, per_line);
    std::string bytes;
    for (const float v : values) {
      if (type == "double") {
        put(bytes, static_cast<double>(v), false);
      } else {
        put(bytes, v, false);
      }
    }
    return bytes + "\n";
  };
  std::vector<float> cells(static_cast<std::size_t>((n[0] - 1) * (n[1] - 1) * std::max<std::int64_t>(1, n[2] - 1)), 7.0f);
  return "# vtk DataFile Version 3.0\nwritten by the test\n" + std::string(binary ? "BINARY" : "ASCII") +
         "\nDATASET STRUCTURED_POINTS\nDIMENSIONS " + std::to_string(n[0]) + " " + std::to_string(n[1]) +
         " " + std::to_string(n[2]) + "\nSPACING 0.5 0.25 2\nORIGIN 1 -2 3.5\nPOINT_DATA " +
         std::to_string(points) + "\nSCALARS pressure " + type + " 1\nLOOKUP_TABLE default\n" +
         data(pressure, 1) + "VECTORS velocity " + type + "\n" + data(grid.values, 3) +
         "CELL_DATA " + std::to_string(cells.size()) + "\nSCALARS id " + type + "\nLOOKUP_TABLE default\n" +
         data(cells, 1);
}

}  // namespace

TEST_CASE("vtk legacy: synthetic files read back exactly", "[vtk]") {
  TempDir dir("vtk");
  const VectorGrid expected = sample_grid(5, 4, 3, 3, true);
  const bool binary = GENERATE(false, true);
  const std::string type = GENERATE(std::string("float"), std::string("double"));
  INFO((binary ? "BINARY " : "ASCII ") << type);
  write_file(dir / "a.vtk", vtk_file(expected, binary, type));
  const VectorGrid grid = read_vtk_legacy(dir / "a.vtk");
  CHECK(grid.geometry.dimension == 3);
  CHECK(grid.geometry.size == std::array<std::int64_t, 3>{5, 4, 3});
  CHECK(grid.components == 3);
  CHECK(grid.geometry.origin == Vec3(1, -2, 3.5));
  CHECK(grid.geometry.spacing == Vec3(0.5, 0.25, 2));
  CHECK(same_values(grid.values, expected.values));
  CHECK(std::isnan(grid.values[3]));
  CHECK(same_values(orthofront::io::read_vector_grid(dir / "a.vtk", "velocity").values, expected.values));
  CHECK_THAT(thrown<FormatError>([&] { read_vtk_legacy(dir / "a.vtk", "pressure"); }),
             Contains("a.vtk") && Contains("'pressure' has 1 components: not vector data"));
}

TEST_CASE("vtk legacy: rectilinear grids and FIELD arrays", "[vtk]") {
  TempDir dir("vtk");
  const VectorGrid expected = sample_grid(3, 2, 2);
  const std::string file =
      "# vtk DataFile Version 5.1\nrect\nASCII\nDATASET RECTILINEAR_GRID\nDIMENSIONS 3 2 2\n"
      "X_COORDINATES 3 float\n0 1 3\nY_COORDINATES 2 double\n-1 1\nZ_COORDINATES 2 float\n10 20\n"
      "METADATA\nINFORMATION 0\n\nPOINT_DATA 12\nFIELD FieldData 2\nid 1 12 int\n" +
      ascii_values(std::vector<float>(12, 1.0f), 12) + "flow 3 12 float\n" +
      ascii_values(expected.values, 3);
  write_file(dir / "rect.vtk", file);
  const VectorGrid grid = read_vtk_legacy(dir / "rect.vtk", "flow");
  REQUIRE(grid.geometry.rectilinear());
  CHECK(grid.geometry.axes[0] == std::vector<double>{0, 1, 3});
  CHECK(grid.geometry.axes[1] == std::vector<double>{-1, 1});
  CHECK(grid.geometry.axes[2] == std::vector<double>{10, 20});
  CHECK(same_values(grid.values, expected.values));
  CHECK_THAT(thrown<FormatError>([&] { read_vtk_legacy(dir / "rect.vtk"); }),
             Contains("rect.vtk") && Contains("no VECTORS in POINT_DATA") &&
                 Contains("FIELD array flow (3 components)"));
}

TEST_CASE("vtk legacy: bad files are rejected naming the file and the value", "[vtk]") {
  TempDir dir("vtk");
  const VectorGrid grid = sample_grid(5, 4, 3);

  SECTION("truncated binary data") {
    const std::string text = vtk_file(grid, true);
    write_file(dir / "short.vtk", text.substr(0, text.find("VECTORS") + 100));
    CHECK_THAT(thrown<FormatError>([&] { read_vtk_legacy(dir / "short.vtk"); }),
               Contains("short.vtk") && Contains("truncated") && Contains("VECTORS velocity"));
  }
  SECTION("truncated ascii data") {
    const std::string text = vtk_file(grid, false);
    write_file(dir / "short.vtk", text.substr(0, text.find("VECTORS") + 100));
    CHECK_THAT(thrown<FormatError>([&] { read_vtk_legacy(dir / "short.vtk"); }),
               Contains("short.vtk") && Contains("truncated") && Contains("of 180 values"));
  }
  SECTION("POINT_DATA that does not match DIMENSIONS") {
    std::string text = vtk_file(grid, false);
    text.replace(text.find("POINT_DATA 60"), 13, "POINT_DATA 61");
    write_file(dir / "dims.vtk", text);
    CHECK_THAT(thrown<FormatError>([&] { read_vtk_legacy(dir / "dims.vtk"); }),
               Contains("dims.vtk") && Contains("POINT_DATA 61 does not match DIMENSIONS"));
  }
  SECTION("bad dimensions") {
    std::string text = vtk_file(grid, false);
    text.replace(text.find("DIMENSIONS 5 4 3"), 16, "DIMENSIONS 5 0 3");
    write_file(dir / "zero.vtk", text);
    CHECK_THAT(thrown<FormatError>([&] { read_vtk_legacy(dir / "zero.vtk"); }),
               Contains("zero.vtk") && Contains("bad DIMENSIONS 5 0 3"));
  }
  SECTION("non-vector data") {
    std::string text = vtk_file(grid, false);
    text.erase(text.find("VECTORS"), text.find("CELL_DATA") - text.find("VECTORS"));
    write_file(dir / "scalar.vtk", text);
    CHECK_THAT(thrown<FormatError>([&] { read_vtk_legacy(dir / "scalar.vtk"); }),
               Contains("scalar.vtk") && Contains("no VECTORS") && Contains("SCALARS pressure"));
  }
  SECTION("unsupported dataset and encoding") {
    write_file(dir / "ug.vtk", "# vtk DataFile Version 3.0\nx\nASCII\nDATASET UNSTRUCTURED_GRID\n");
    CHECK_THAT(thrown<FormatError>([&] { read_vtk_legacy(dir / "ug.vtk"); }),
               Contains("ug.vtk") && Contains("unsupported DATASET 'UNSTRUCTURED_GRID'"));
    write_file(dir / "enc.vtk", "# vtk DataFile Version 3.0\nx\nHEX\nDATASET STRUCTURED_POINTS\n");
    CHECK_THAT(thrown<FormatError>([&] { read_vtk_legacy(dir / "enc.vtk"); }),
               Contains("enc.vtk") && Contains("unsupported encoding 'hex'"));
  }
}

TEST_CASE("vtk legacy: a tiny file whose header claims huge arrays is refused before allocating",
          "[vtk]") {
  // Each file is about 150 bytes; its header claims up to 768 GB. The same files are in
  // fuzz/regressions/grid_vtk.
  TempDir dir("vtk");
  const std::string head = "# vtk DataFile Version 3.0\nhostile\n";
  const std::string dims = "DATASET STRUCTURED_POINTS\nDIMENSIONS 4000 4000 4000\n"
                           "POINT_DATA 64000000000\nVECTORS velocity float\n";
  struct Case {
    const char* name;
    std::string bytes;
    std::vector<std::string> message;
  };
  const std::vector<Case> cases = {
      {"binary.vtk", head + "BINARY\n" + dims + std::string(16, '\x3f'),
       {"truncated: VECTORS velocity needs 768000000000 bytes, the file holds 16"}},
      {"ascii.vtk", head + "ASCII\n" + dims + "1 2 3\n4 5 6\n",
       {"truncated: VECTORS velocity holds 6 of 192000000000 values"}},
      {"rectilinear.vtk",
       head + "BINARY\nDATASET RECTILINEAR_GRID\nDIMENSIONS 4000000000 1 1\n"
              "X_COORDINATES 4000000000 float\n" + std::string(16, '\0'),
       {"truncated: X_COORDINATES needs 16000000000 bytes, the file holds 16"}},
      // components x tuples once wrapped around (signed overflow) to 0 values.
      {"field.vtk",
       head + "ASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS 2 1 1\nPOINT_DATA 2\n"
              "FIELD f 1\na 4611686018427387904 4 float\n1 2\n",
       {"FIELD array a declares 4611686018427387904 x 4 values, more than any file holds"}},
      {"cells.vtk",
       head + "ASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS 2 1 1\nPOINT_DATA 2\n"
              "CELL_DATA -1\nSCALARS s float\n1\n",
       {"bad CELL_DATA -1"}},
  };
  for (const Case& c : cases) {
    INFO(c.name);
    write_file(dir / c.name, c.bytes);
    std::string message;
    const test_support::Footprint f = test_support::footprint(
        [&] { message = thrown<FormatError>([&] { read_vtk_legacy(dir / c.name); }); });
    CHECK_THAT(message, Contains(c.name));
    for (const std::string& part : c.message) CHECK_THAT(message, Contains(part));
    CHECK(f.seconds < test_support::kHostileSeconds);
    CHECK(f.peak_growth_kib < test_support::kHostileGrowthKib);
  }
}
