// AmiraMesh reader: both binary byte orders, ASCII, HxZip, rectilinear coordinates, skipping of
// other data sections; bad files rejected; the bubble-chamber data.
#include <cmath>

#include "io/grid_test_support.h"
#include "io/hostile_file.h"
#include "orthofront/io/amira_reader.h"
#include "orthofront/io/error.h"
#include "orthofront/io/zlib_codec.h"

using Catch::Matchers::Contains;
using orthofront::Vec3;
using orthofront::VectorGrid;
using orthofront::io::FormatError;
using orthofront::io::read_amira;
using namespace grid_test;

namespace {

enum class Encoding { kBig, kLittle, kAscii, kZip };

std::string number_text(const std::vector<float>& values) {
  std::string text;
  for (std::size_t i = 0; i < values.size(); ++i) {
    char buffer[32];
    std::snprintf(buffer, sizeof(buffer), "%.9g", static_cast<double>(values[i]));
    text += buffer;
    text += (i % 3 == 2) ? '\n' : ' ';
  }
  return text;
}

/// An AmiraMesh file with a scalar section @1 (to be skipped) and the vectors @2.
std::string amira_file(Encoding encoding, const VectorGrid& grid, const std::string& bbox) {
  const auto& n = grid.geometry.size;
  std::vector<float> pressure(grid.geometry.point_count());
  for (std::size_t i = 0; i < pressure.size(); ++i) pressure[i] = static_cast<float>(i) * 0.25f;
  const bool little = encoding != Encoding::kBig;
  std::string first = "# AmiraMesh BINARY-LITTLE-ENDIAN 2.1\n";
  if (encoding == Encoding::kBig) first = "# AmiraMesh 3D BINARY 2.0\n";
  if (encoding == Encoding::kAscii) first = "# AmiraMesh 3D ASCII 2.0\n";
  const std::string velocity_bytes = float_bytes(grid.values, little);
  std::string velocity_decl = "Lattice { float[" + std::to_string(grid.components) + "] Velocity } @2";
  std::string velocity_data = velocity_bytes;
  if (encoding == Encoding::kZip) {
    velocity_data = orthofront::io::detail::zlib_deflate(velocity_bytes);
    velocity_decl += "(HxZip," + std::to_string(velocity_data.size()) + ")";
  }
  std::string text = first + "\n# CreationDate: today\n\n\ndefine Lattice " + std::to_string(n[0]) +
                     " " + std::to_string(n[1]) + " " + std::to_string(n[2]) +
                     "\n\nParameters {\n    Units {\n        Coordinates \"m\"\n    }\n"
                     "    BoundingBox " + bbox + ",\n    CoordType \"uniform\"\n}\n\n"
                     "Lattice { float Pressure } @1\n" + velocity_decl +
                     "\n\n# Data section follows\n@1\n";
  if (encoding == Encoding::kAscii) {
    text += number_text(pressure) + "\n@2\n" + number_text(grid.values) + "\n";
  } else {
    text += float_bytes(pressure, little) + "\n@2\n" + velocity_data + "\n";
  }
  return text;
}

}  // namespace

TEST_CASE("amira: synthetic files read back exactly in every encoding", "[amira]") {
  TempDir dir("amira");
  const VectorGrid expected = sample_grid(5, 4, 3, 3, true);
  const auto [name, encoding] = GENERATE(table<std::string, Encoding>({
      {"big-endian BINARY 2.0", Encoding::kBig},
      {"BINARY-LITTLE-ENDIAN 2.1", Encoding::kLittle},
      {"ASCII", Encoding::kAscii},
      {"HxZip", Encoding::kZip},
  }));
  INFO(name);
  write_file(dir / "a.am", amira_file(encoding, expected, "-1 1 0 3 2 6"));
  const VectorGrid grid = read_amira(dir / "a.am");
  CHECK(grid.geometry.size == std::array<std::int64_t, 3>{5, 4, 3});
  CHECK(grid.geometry.dimension == 3);
  CHECK(grid.components == 3);
  // Point (i, j, k) = bbmin + (i, j, k) * (bbmax - bbmin) / (n - 1).
  CHECK(grid.geometry.origin == Vec3(-1, 0, 2));
  CHECK(grid.geometry.spacing == Vec3(0.5, 1, 2));
  CHECK(same_values(grid.values, expected.values));
  CHECK(std::isnan(grid.values[3]));
  // By field name.
  CHECK(same_values(read_amira(dir / "a.am", "Velocity").values, expected.values));
  CHECK_THAT(thrown<FormatError>([&] { read_amira(dir / "a.am", "Pressure"); }),
             Contains("a.am") && Contains("Pressure") && Contains("not vector data"));
}

TEST_CASE("amira: 2D lattices and rectilinear coordinates", "[amira]") {
  TempDir dir("amira");
  SECTION("a 2D lattice of 2-vectors") {
    const VectorGrid expected = sample_grid(4, 3, 1, 2);
    write_file(dir / "flat.am", "# AmiraMesh BINARY-LITTLE-ENDIAN 2.1\ndefine Lattice 4 3\n"
                                "Parameters { BoundingBox 0 3 0 1 0 0, CoordType \"uniform\" }\n"
                                "Lattice { float[2] Data } @1\n# Data section follows\n@1\n" +
                                    float_bytes(expected.values, true) + "\n");
    const VectorGrid grid = read_amira(dir / "flat.am");
    CHECK(grid.geometry.dimension == 2);
    CHECK(grid.geometry.size == std::array<std::int64_t, 3>{4, 3, 1});
    CHECK(grid.components == 2);
    CHECK(grid.geometry.spacing[0] == 1.0);
    CHECK(grid.geometry.spacing[1] == 0.5);
    CHECK(same_values(grid.values, expected.values));
  }
  SECTION("rectilinear") {
    const VectorGrid expected = sample_grid(3, 2, 2);
    const std::vector<float> xyz{0, 1, 3, -1, 1, 10, 20};
    write_file(dir / "rect.am", "# AmiraMesh BINARY 2.0\ndefine Lattice 3 2 2\ndefine Coordinates 7\n"
                                "Parameters { CoordType \"rectilinear\" }\n"
                                "Lattice { float[3] Data } @1\nCoordinates { float xyz } @2\n"
                                "# Data section follows\n@1\n" +
                                    float_bytes(expected.values, false) + "\n@2\n" +
                                    float_bytes(xyz, false) + "\n");
    const VectorGrid grid = read_amira(dir / "rect.am");
    REQUIRE(grid.geometry.rectilinear());
    CHECK(grid.geometry.axes[0] == std::vector<double>{0, 1, 3});
    CHECK(grid.geometry.axes[1] == std::vector<double>{-1, 1});
    CHECK(grid.geometry.axes[2] == std::vector<double>{10, 20});
    CHECK(same_values(grid.values, expected.values));
  }
}

TEST_CASE("amira: bad files are rejected naming the file and the value", "[amira]") {
  TempDir dir("amira");
  const VectorGrid grid = sample_grid(5, 4, 3);
  const std::string good = amira_file(Encoding::kBig, grid, "-1 1 0 3 2 6");

  SECTION("truncated data") {
    write_file(dir / "short.am", good.substr(0, good.size() - 20));
    CHECK_THAT(thrown<FormatError>([&] { read_amira(dir / "short.am"); }),
               Contains("short.am") && Contains("truncated") && Contains("@2"));
  }
  SECTION("a component count that does not match the data") {
    std::string bad = good;
    bad.replace(bad.find("float[3] Velocity"), 17, "float[2] Velocity");
    write_file(dir / "two.am", bad);
    CHECK_THAT(thrown<FormatError>([&] { read_amira(dir / "two.am"); }),
               Contains("two.am") && Contains("float[2] Velocity") &&
                   Contains("belong to no section"));
  }
  SECTION("truncated header") {
    write_file(dir / "head.am", good.substr(0, 80));
    CHECK_THAT(thrown<FormatError>([&] { read_amira(dir / "head.am"); }),
               Contains("head.am") && Contains("Data section follows"));
  }
  SECTION("wrong lattice size") {
    std::string bad = good;
    bad.replace(bad.find("define Lattice 5 4 3"), 20, "define Lattice 5 4 0");
    write_file(dir / "dims.am", bad);
    CHECK_THAT(thrown<FormatError>([&] { read_amira(dir / "dims.am"); }),
               Contains("dims.am") && Contains("bad size '0'"));
    bad = good;
    bad.replace(bad.find("define Lattice 5 4 3"), 20, "define Lattice 5 4 9");
    write_file(dir / "big.am", bad);
    CHECK_THAT(thrown<FormatError>([&] { read_amira(dir / "big.am"); }),
               Contains("big.am") && Contains("sizes in the header match the data"));
  }
  SECTION("non-vector data") {
    write_file(dir / "scalar.am", "# AmiraMesh BINARY-LITTLE-ENDIAN 2.1\ndefine Lattice 2 2 2\n"
                                  "Lattice { float Data } @1\n# Data section follows\n@1\n" +
                                      std::string(32, '\0') + "\n");
    CHECK_THAT(thrown<FormatError>([&] { read_amira(dir / "scalar.am"); }),
               Contains("scalar.am") && Contains("no vector data") &&
                   Contains("Lattice { float Data } @1"));
  }
  SECTION("unsupported encodings") {
    std::string bad = good;
    bad.replace(0, bad.find('\n'), "# AmiraMesh 3D ZIP 2.0");
    write_file(dir / "zip.am", bad);
    CHECK_THAT(thrown<FormatError>([&] { read_amira(dir / "zip.am"); }),
               Contains("zip.am") && Contains("unsupported AmiraMesh encoding 'ZIP'"));
    bad = good;
    bad.replace(bad.find("Velocity } @2"), 13, "Velocity } @2(HxByteRLE,100)");
    write_file(dir / "rle.am", bad);
    CHECK_THAT(thrown<FormatError>([&] { read_amira(dir / "rle.am"); }),
               Contains("rle.am") && Contains("HxByteRLE"));
  }
  SECTION("a reversed bounding box") {
    write_file(dir / "box.am", amira_file(Encoding::kBig, grid, "1 -1 0 3 2 6"));
    CHECK_THAT(thrown<FormatError>([&] { read_amira(dir / "box.am"); }),
               Contains("box.am") && Contains("BoundingBox"));
  }
  SECTION("not AmiraMesh") {
    write_file(dir / "other.am", "# HyperSurface 0.1 BINARY\n");
    CHECK_THAT(thrown<FormatError>([&] { read_amira(dir / "other.am"); }),
               Contains("other.am") && Contains("not an AmiraMesh file"));
  }
}

TEST_CASE("amira: a tiny file whose header claims a huge lattice is refused before allocating",
          "[amira]") {
  // Each file is a few hundred bytes; its header claims up to 768 GB. The same files are in
  // fuzz/regressions/grid_am.
  TempDir dir("amira");
  const std::string binary_head =
      "# AmiraMesh BINARY-LITTLE-ENDIAN 2.1\ndefine Lattice 4000 4000 4000\n"
      "Lattice { float[3] Velocity } @1\n# Data section follows\n@1\n";
  struct Case {
    const char* name;
    std::string bytes;
    std::vector<std::string> message;
  };
  const std::vector<Case> cases = {
      {"binary.am", binary_head + std::string(16, '\x3f'),
       {"truncated", "data section @1 (Lattice { float[3] Velocity } @1)",
        "needs 768000000000 bytes, the file holds 16"}},
      {"ascii.am",
       "# AmiraMesh 3D ASCII 2.0\ndefine Lattice 4000 4000 4000\n"
       "Lattice { float[3] Velocity } @1\n# Data section follows\n@1\n1 2 3\n4 5 6\n",
       {"truncated", "Velocity", "holds 6 of 192000000000 values"}},
      // 12 compressed bytes cannot inflate to the 1.2 GB of a 1000 x 1000 x 100 float[3] lattice.
      {"zip.am",
       "# AmiraMesh BINARY-LITTLE-ENDIAN 2.1\ndefine Lattice 1000 1000 100\n"
       "Lattice { float[3] Velocity } @1(HxZip,12)\n# Data section follows\n@1\n" +
           std::string(12, '\x78'),
       {"Velocity", "12 compressed bytes cannot hold the expected 1200000000 bytes"}},
      // Rectilinear coordinates: 10^11 floats (400 GB) declared, 8 bytes present.
      {"coordinates.am",
       "# AmiraMesh BINARY-LITTLE-ENDIAN 2.1\ndefine Lattice 2 2 2\n"
       "define Coordinates 100000000000\nParameters {\n    CoordType \"rectilinear\"\n}\n"
       "Lattice { float[3] Velocity } @1\nCoordinates { float xyz } @2\n"
       "# Data section follows\n@2\n" + std::string(8, '\0'),
       {"truncated", "Coordinates { float xyz } @2", "needs 400000000000 bytes, the file holds 8"}},
      // A component count beyond int once escaped as std::out_of_range from std::stoi.
      {"components.am",
       "# AmiraMesh BINARY-LITTLE-ENDIAN 2.1\ndefine Lattice 2 2 2\n"
       "Lattice { float[99999999999] Velocity } @1\n# Data section follows\n@1\n0123",
       {"bad component count '99999999999' of Velocity"}},
  };
  for (const Case& c : cases) {
    INFO(c.name);
    write_file(dir / c.name, c.bytes);
    std::string message;
    const test_support::Footprint f = test_support::footprint(
        [&] { message = thrown<FormatError>([&] { read_amira(dir / c.name); }); });
    CHECK_THAT(message, Contains(c.name));
    for (const std::string& part : c.message) CHECK_THAT(message, Contains(part));
    CHECK(f.seconds < test_support::kHostileSeconds);
    CHECK(f.peak_growth_kib < test_support::kHostileGrowthKib);
  }
}

TEST_CASE("amira: the bubble-chamber data", "[amira][realdata]") {
  const fs::path dir = datasets_dir("bubble-chamber");
  if (dir.empty()) return;
  const fs::path file = dir / "BubbleChamber_11x11x10_T0.am";
  const VectorGrid grid = read_amira(file);
  REQUIRE(grid.geometry.size == std::array<std::int64_t, 3>{11, 11, 10});
  REQUIRE(grid.components == 3);
  // BoundingBox -0.052 0.052 -0.052 0.052 0 0.0936.
  CHECK(grid.geometry.origin[0] == Approx(-0.052));
  CHECK(grid.geometry.origin[2] == 0.0);
  CHECK(grid.geometry.spacing[0] == Approx(0.0104));
  CHECK(grid.geometry.spacing[2] == Approx(0.0104));
  CHECK(grid.geometry.bounds().hi[2] == Approx(0.0936));
  // Big-endian floats, decoded independently here: the last vector of the file.
  const std::string bytes = read_file(file);
  const auto be_float = [&](std::size_t offset) {
    std::uint32_t u = 0;
    for (int b = 0; b < 4; ++b) u = u << 8 | static_cast<unsigned char>(bytes[offset + b]);
    float f = 0;
    std::memcpy(&f, &u, 4);
    return f;
  };
  const std::size_t begin = bytes.find("\n@1\n", bytes.find("# Data section follows")) + 4;
  const std::size_t end = begin + 11 * 11 * 10 * 3 * 4;
  REQUIRE(end <= bytes.size());
  for (int c = 0; c < 3; ++c) {
    CHECK(grid.values[c] == be_float(begin + 4 * c));
    CHECK(grid.values[grid.values.size() - 3 + c] == be_float(end - 12 + 4 * c));
  }
  // Plausible speeds (a wrong byte order gives huge or tiny garbage); walls are zero vectors.
  double hi = 0;
  std::size_t zeros = 0;
  for (std::size_t p = 0; p < grid.geometry.point_count(); ++p) {
    const double m = std::hypot(grid.values[3 * p], grid.values[3 * p + 1], grid.values[3 * p + 2]);
    REQUIRE(std::isfinite(m));
    hi = std::max(hi, m);
    if (m == 0) ++zeros;
  }
  CHECK(hi == Approx(0.0682931).epsilon(1e-5));
  CHECK(zeros == 400);
}
