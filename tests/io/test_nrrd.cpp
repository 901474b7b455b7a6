// NRRD reader: raw in both byte orders, gzip, bzip2, hex, ascii, detached data, component axis placement,
// geometry fields; bad files rejected; the square-cylinder data.
#include <cmath>

#include "io/grid_test_support.h"
#include "io/hostile_file.h"
#include "orthofront/io/error.h"
#include "orthofront/io/nrrd_reader.h"
#include "orthofront/io/bzip2_codec.h"
#include "orthofront/io/zlib_codec.h"

using Catch::Matchers::Contains;
using orthofront::Vec3;
using orthofront::VectorGrid;
using orthofront::io::FormatError;
using orthofront::io::read_nrrd;
using namespace grid_test;

namespace {

const std::string kHeader3D =
    "NRRD0004\n# Complete NRRD file format specification at:\n"
    "type: float\ndimension: 4\nspace dimension: 3\nsizes: 3 5 4 3\n"
    "space directions: none (0.5,0,0) (0,0.25,0) (0,0,2)\nkinds: 3-vector space space space\n"
    "space origin: (1,-2,3.5)\nlabel:=ignored key/value\n";

}  // namespace

TEST_CASE("nrrd: synthetic files read back exactly", "[nrrd]") {
  TempDir dir("nrrd");
  const VectorGrid expected = sample_grid(5, 4, 3, 3, true);
  const auto check = [&](const VectorGrid& grid) {
    CHECK(grid.geometry.dimension == 3);
    CHECK(grid.geometry.size == std::array<std::int64_t, 3>{5, 4, 3});
    CHECK(grid.components == 3);
    CHECK(grid.geometry.origin == Vec3(1, -2, 3.5));
    CHECK(grid.geometry.spacing == Vec3(0.5, 0.25, 2));
    CHECK(same_values(grid.values, expected.values));
  };
  SECTION("raw little-endian") {
    write_file(dir / "a.nrrd", kHeader3D + "endian: little\nencoding: raw\n\n" +
                                   float_bytes(expected.values, true));
    check(read_nrrd(dir / "a.nrrd"));
  }
  SECTION("raw big-endian") {
    write_file(dir / "a.nrrd", kHeader3D + "endian: big\nencoding: raw\n\n" +
                                   float_bytes(expected.values, false));
    check(read_nrrd(dir / "a.nrrd"));
  }
  SECTION("gzip") {
    write_file(dir / "a.nrrd", kHeader3D + "endian: little\nencoding: gzip\n\n" +
                                   orthofront::io::detail::gzip_deflate(
                                       float_bytes(expected.values, true)));
    check(read_nrrd(dir / "a.nrrd"));
  }
  SECTION("bzip2 (libbz2), also as two concatenated streams") {
    const std::string bytes = float_bytes(expected.values, true);
    write_file(dir / "a.nrrd", kHeader3D + "endian: little\nencoding: bzip2\n\n" +
                                   orthofront::io::detail::bzip2_compress(bytes));
    check(read_nrrd(dir / "a.nrrd"));
    const std::size_t half = bytes.size() / 2;
    write_file(dir / "b.nrrd",
               kHeader3D + "endian: little\nencoding: bz2\n\n" +
                   orthofront::io::detail::bzip2_compress(bytes.substr(0, half), 1) +
                   orthofront::io::detail::bzip2_compress(bytes.substr(half), 1));
    check(read_nrrd(dir / "b.nrrd"));
  }
  SECTION("hex, with line breaks") {
    const std::string bytes = float_bytes(expected.values, false);
    std::string hex;
    for (std::size_t i = 0; i < bytes.size(); ++i) {
      static const char* const kDigits = "0123456789abcdef";
      const auto b = static_cast<unsigned char>(bytes[i]);
      hex += kDigits[b >> 4];
      hex += kDigits[b & 15];
      if (i % 32 == 31) hex += '\n';
    }
    write_file(dir / "a.nrrd", kHeader3D + "endian: big\nencoding: hex\n\n" + hex);
    check(read_nrrd(dir / "a.nrrd"));
  }
  SECTION("zlib stream under the gzip name") {
    write_file(dir / "a.nrrd", kHeader3D + "endian: little\nencoding: gz\n\n" +
                                   orthofront::io::detail::zlib_deflate(
                                       float_bytes(expected.values, true)));
    check(read_nrrd(dir / "a.nrrd"));
  }
  SECTION("ascii") {
    std::string text;
    for (const float v : expected.values) text += std::to_string(v) + (std::isnan(v) ? " " : "\n");
    // std::to_string prints 6 decimals: every sample value is a multiple of 1/16, exact.
    write_file(dir / "a.nrrd", kHeader3D + "encoding: ascii\n\n" + text);
    check(read_nrrd(dir / "a.nrrd"));
  }
  SECTION("detached data") {
    write_file(dir / "a.raw", float_bytes(expected.values, false));
    write_file(dir / "a.nhdr", kHeader3D + "endian: big\nencoding: raw\ndata file: a.raw\n");
    check(read_nrrd(dir / "a.nhdr"));
  }
  SECTION("byte skip -1 (data at the end of the file)") {
    write_file(dir / "a.nrrd", kHeader3D + "endian: little\nencoding: raw\nbyte skip: -1\n\n" +
                                   "junk" + float_bytes(expected.values, true));
    check(read_nrrd(dir / "a.nrrd"));
  }
  SECTION("byte skip and line skip: bytes around the samples are allowed") {
    write_file(dir / "a.nrrd", kHeader3D + "endian: little\nencoding: raw\nbyte skip: 4\n\n" +
                                   "junk" + float_bytes(expected.values, true) + "trailer");
    check(read_nrrd(dir / "a.nrrd"));
    write_file(dir / "b.raw", "a line of text\n" + float_bytes(expected.values, true) + "trailer");
    write_file(dir / "b.nhdr",
               kHeader3D + "endian: little\nencoding: raw\nline skip: 1\ndata file: b.raw\n");
    check(read_nrrd(dir / "b.nhdr"));
  }
}

TEST_CASE("nrrd: component axis last, spacings and axis mins", "[nrrd]") {
  TempDir dir("nrrd");
  const VectorGrid expected = sample_grid(4, 3, 1, 2);
  // Stored with the component axis last: value (i, j, c) at i + 4 * (j + 3 * c).
  std::vector<float> stored(expected.values.size());
  for (std::size_t p = 0; p < 12; ++p) {
    for (std::size_t c = 0; c < 2; ++c) stored[p + 12 * c] = expected.values[2 * p + c];
  }
  write_file(dir / "b.nrrd", "NRRD0005\ntype: double\ndimension: 3\nsizes: 4 3 2\n"
                             "kinds: space space vector\nspacings: 0.5 2 nan\n"
                             "axis mins: 10 20 nan\ncenters: cell node none\n"
                             "endian: little\nencoding: raw\n\n" + [&] {
                               std::string bytes;
                               for (const float v : stored) put(bytes, static_cast<double>(v), true);
                               return bytes;
                             }());
  const VectorGrid grid = read_nrrd(dir / "b.nrrd");
  CHECK(grid.geometry.dimension == 2);
  CHECK(grid.geometry.size == std::array<std::int64_t, 3>{4, 3, 1});
  CHECK(grid.components == 2);
  CHECK(grid.geometry.spacing[0] == 0.5);
  CHECK(grid.geometry.spacing[1] == 2.0);
  CHECK(grid.geometry.origin[0] == 10.25);  // cell-centred: min + spacing / 2
  CHECK(grid.geometry.origin[1] == 20.0);
  CHECK(same_values(grid.values, expected.values));
}

TEST_CASE("nrrd: bad files are rejected naming the file and the value", "[nrrd]") {
  TempDir dir("nrrd");
  const VectorGrid grid = sample_grid(5, 4, 3);
  const std::string data = float_bytes(grid.values, true);

  SECTION("truncated data") {
    write_file(dir / "short.nrrd",
               kHeader3D + "endian: little\nencoding: raw\n\n" + data.substr(0, 100));
    CHECK_THAT(thrown<FormatError>([&] { read_nrrd(dir / "short.nrrd"); }),
               Contains("short.nrrd") && Contains("truncated") && Contains("100"));
  }
  SECTION("a header that claims fewer samples than the raw data holds") {
    // sizes 3 5 4 2 need 480 bytes; the data holds the 720 of 3 5 4 3.
    std::string header = kHeader3D;
    header.replace(header.find("sizes: 3 5 4 3"), 14, "sizes: 3 5 4 2");
    write_file(dir / "long.nrrd", header + "endian: little\nencoding: raw\n\n" + data);
    CHECK_THAT(thrown<FormatError>([&] { read_nrrd(dir / "long.nrrd"); }),
               Contains("long.nrrd") && Contains("holds 720 data bytes") &&
                   Contains("sizes 3 5 4 2 of float need 480") &&
                   Contains("claims fewer samples than the data holds"));
    // Detached: the data file named too.
    write_file(dir / "long.raw", data);
    write_file(dir / "long.nhdr", header + "endian: little\nencoding: raw\ndata file: long.raw\n");
    CHECK_THAT(thrown<FormatError>([&] { read_nrrd(dir / "long.nhdr"); }),
               Contains("long.nhdr") && Contains("long.raw holds 720 data bytes") &&
                   Contains("sizes 3 5 4 2 of float need 480"));
    // One stray byte after the samples is refused as well.
    write_file(dir / "byte.nrrd", kHeader3D + "endian: little\nencoding: raw\n\n" + data + "\n");
    CHECK_THAT(thrown<FormatError>([&] { read_nrrd(dir / "byte.nrrd"); }),
               Contains("byte.nrrd") && Contains("holds 721 data bytes") && Contains("need 720"));
  }
  SECTION("bad bzip2 and hex data") {
    const std::string bz = orthofront::io::detail::bzip2_compress(data);
    write_file(dir / "short.nrrd", kHeader3D + "endian: little\nencoding: bzip2\n\n" +
                                       bz.substr(0, bz.size() / 2));
    CHECK_THAT(thrown<FormatError>([&] { read_nrrd(dir / "short.nrrd"); }),
               Contains("short.nrrd") && Contains("bzip2"));
    std::string corrupt = bz;
    for (std::size_t i = 10; i < 40; ++i) corrupt[i] = static_cast<char>(corrupt[i] ^ 0x5a);
    write_file(dir / "corrupt.nrrd", kHeader3D + "endian: little\nencoding: bzip2\n\n" + corrupt);
    CHECK_THAT(thrown<FormatError>([&] { read_nrrd(dir / "corrupt.nrrd"); }),
               Contains("corrupt.nrrd") && Contains("bzip2"));
    // More data than the sizes describe: stopped at the sizes, not read to the end.
    std::string header = kHeader3D;
    header.replace(header.find("sizes: 3 5 4 3"), 14, "sizes: 3 5 4 2");
    write_file(dir / "long.nrrd", header + "endian: little\nencoding: bzip2\n\n" + bz);
    CHECK_THAT(thrown<FormatError>([&] { read_nrrd(dir / "long.nrrd"); }),
               Contains("long.nrrd") && Contains("more than the 480 bytes"));
    write_file(dir / "hex.nrrd", kHeader3D + "endian: little\nencoding: hex\n\n" +
                                     std::string(2 * data.size() - 2, '0') + "zz");
    CHECK_THAT(thrown<FormatError>([&] { read_nrrd(dir / "hex.nrrd"); }),
               Contains("hex.nrrd") && Contains("bad hex character 'z'"));
    write_file(dir / "hexshort.nrrd",
               kHeader3D + "endian: little\nencoding: hex\n\n" + std::string(100, 'a'));
    CHECK_THAT(thrown<FormatError>([&] { read_nrrd(dir / "hexshort.nrrd"); }),
               Contains("hexshort.nrrd") && Contains("truncated"));
  }
  SECTION("truncated gzip data") {
    const std::string gz = orthofront::io::detail::gzip_deflate(data);
    write_file(dir / "short.nrrd",
               kHeader3D + "endian: little\nencoding: gzip\n\n" + gz.substr(0, gz.size() / 2));
    CHECK_THAT(thrown<FormatError>([&] { read_nrrd(dir / "short.nrrd"); }),
               Contains("short.nrrd") && Contains("ends early"));
  }
  SECTION("sizes that do not match the dimension") {
    write_file(dir / "dims.nrrd", "NRRD0004\ntype: float\ndimension: 4\nsizes: 3 5 4\n"
                                  "endian: little\nencoding: raw\n\n" + data);
    CHECK_THAT(thrown<FormatError>([&] { read_nrrd(dir / "dims.nrrd"); }),
               Contains("dims.nrrd") && Contains("sizes '3 5 4'") && Contains("dimension 4"));
  }
  SECTION("non-vector data") {
    write_file(dir / "scalar.nrrd", "NRRD0004\ntype: float\ndimension: 3\nsizes: 5 4 3\n"
                                    "kinds: space space space\nendian: little\nencoding: raw\n\n" +
                                        data);
    CHECK_THAT(thrown<FormatError>([&] { read_nrrd(dir / "scalar.nrrd"); }),
               Contains("scalar.nrrd") && Contains("non-vector data"));
    write_file(dir / "four.nrrd", "NRRD0004\ntype: float\ndimension: 3\nsizes: 4 5 3\n"
                                  "endian: little\nencoding: raw\n\n" + data);
    CHECK_THAT(thrown<FormatError>([&] { read_nrrd(dir / "four.nrrd"); }),
               Contains("four.nrrd") && Contains("non-vector data") && Contains("size 4"));
  }
  SECTION("unsupported encoding") {
    write_file(dir / "zz.nrrd", kHeader3D + "endian: little\nencoding: zstd\n\n" + data);
    CHECK_THAT(thrown<FormatError>([&] { read_nrrd(dir / "zz.nrrd"); }),
               Contains("zz.nrrd") && Contains("unsupported encoding 'zstd'"));
  }
  SECTION("no endian for a multi-byte type") {
    write_file(dir / "end.nrrd", kHeader3D + "encoding: raw\n\n" + data);
    CHECK_THAT(thrown<FormatError>([&] { read_nrrd(dir / "end.nrrd"); }),
               Contains("end.nrrd") && Contains("endian"));
  }
  SECTION("rotated space directions") {
    std::string header = kHeader3D;
    header.replace(header.find("(0.5,0,0)"), 9, "(0.5,0.5,0)");
    write_file(dir / "rot.nrrd", header + "endian: little\nencoding: raw\n\n" + data);
    CHECK_THAT(thrown<FormatError>([&] { read_nrrd(dir / "rot.nrrd"); }),
               Contains("rot.nrrd") && Contains("(0.5,0.5,0)") && Contains("axis-aligned"));
  }
  SECTION("huge sizes with little data: refused before allocating the grid") {
    // 3 x 40000 x 40000 floats would be 19 GB; the file holds 96 bytes.
    for (const char* encoding : {"raw", "ascii", "gzip"}) {
      write_file(dir / "huge.nrrd", std::string("NRRD0004\ntype: float\ndimension: 3\n") +
                                        "sizes: 3 40000 40000\nkinds: vector space space\n" +
                                        "endian: little\nencoding: " + encoding + "\n\n" +
                                        data.substr(0, 96));
      CHECK_THAT(thrown<FormatError>([&] { read_nrrd(dir / "huge.nrrd"); }),
                 Contains("huge.nrrd") && Contains("truncated") && Contains("40000"));
    }
  }
  SECTION("ascii data with fewer characters than values and separators need") {
    // 300 values need at least 599 characters (a digit each and a separator between): 300
    // digits without separators were once taken for enough and the values allocated.
    write_file(dir / "dense.nrrd", "NRRD0004\ntype: float\ndimension: 3\nsizes: 3 10 10\n"
                                   "kinds: vector space space\nencoding: ascii\n\n" +
                                       std::string(300, '1'));
    std::string message;
    const test_support::Footprint f = test_support::footprint(
        [&] { message = thrown<FormatError>([&] { read_nrrd(dir / "dense.nrrd"); }); });
    CHECK_THAT(message, Contains("dense.nrrd") && Contains("truncated") &&
                            Contains("holds 300 characters, too few for the 300 values"));
    CHECK(f.seconds < test_support::kHostileSeconds);
    CHECK(f.peak_growth_kib < test_support::kHostileGrowthKib);
  }
  SECTION("a detached data file that is a device") {
    write_file(dir / "zero.nrrd", kHeader3D + "endian: little\nencoding: raw\n"
                                              "data file: /dev/zero\n\n");
    CHECK_THAT(thrown<orthofront::io::IoError>([&] { read_nrrd(dir / "zero.nrrd"); }),
               Contains("/dev/zero") && Contains("not a regular file"));
  }
  SECTION("not NRRD") {
    write_file(dir / "no.nrrd", "P6\n");
    CHECK_THAT(thrown<FormatError>([&] { read_nrrd(dir / "no.nrrd"); }),
               Contains("no.nrrd") && Contains("not a NRRD file"));
  }
}

TEST_CASE("nrrd: the square-cylinder snapshots", "[nrrd][realdata]") {
  const fs::path dir = datasets_dir("square-cylinder-2d");
  if (dir.empty()) return;
  for (const char* name : {"sqflow2D-1608.nrrd", "sqflow2D-3928.nrrd"}) {
    INFO(name);
    const VectorGrid grid = read_nrrd(dir / name);
    REQUIRE(grid.geometry.dimension == 2);
    REQUIRE(grid.geometry.size == std::array<std::int64_t, 3>{192, 64, 1});
    REQUIRE(grid.components == 2);
    CHECK(grid.geometry.origin[0] == Approx(-11.916666666666666));
    CHECK(grid.geometry.origin[1] == Approx(-3.9375));
    CHECK(grid.geometry.spacing[0] == Approx(1.0 / 6.0));
    CHECK(grid.geometry.spacing[1] == Approx(0.125));
    // The channel spans y in [-4, 4) and x from -12 to about 20.
    const auto box = grid.geometry.bounds();
    CHECK(box.hi[1] == Approx(3.9375));
    CHECK(box.hi[0] == Approx(19.916666666666666));
    double hi = 0;
    std::size_t zeros = 0;
    double mean_u = 0;
    for (std::size_t p = 0; p < grid.geometry.point_count(); ++p) {
      const double u = grid.values[2 * p];
      const double v = grid.values[2 * p + 1];
      REQUIRE(std::isfinite(u));
      REQUIRE(std::isfinite(v));
      hi = std::max(hi, std::hypot(u, v));
      if (u == 0 && v == 0) ++zeros;
      mean_u += u;
    }
    mean_u /= static_cast<double>(grid.geometry.point_count());
    CHECK(zeros == 48);            // the square cylinder: solid cells are zero vectors
    CHECK(hi > 1.3);               // peak speed above the inflow's mean
    CHECK(hi < 1.4);
    CHECK(mean_u > 0.5);           // the flow goes along +x
  }
}
