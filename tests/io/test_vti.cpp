// VTK XML ImageData reader: ascii, inline binary, appended raw and base64 data, zlib blocks,
// UInt32 and UInt64 headers, both byte orders, several pieces; bad files rejected; the tornado
// step 1 as .vti and as .vec gives the same values.
#include <cmath>
#include <sstream>

#include "io/grid_test_support.h"
#include "io/hostile_file.h"
#include "orthofront/io/base64.h"
#include "orthofront/io/error.h"
#include "orthofront/io/vec_reader.h"
#include "orthofront/io/vti_reader.h"
#include "orthofront/io/vtk_xml.h"
#include "orthofront/io/zlib_codec.h"

using Catch::Matchers::Contains;
using orthofront::Vec3;
using orthofront::VectorGrid;
using orthofront::io::FormatError;
using orthofront::io::read_vti;
using namespace grid_test;
namespace detail = orthofront::io::detail;

namespace {

enum class Mode { kAscii, kBinary, kAppendedRaw, kAppendedBase64 };

struct VtiOptions {
  Mode mode = Mode::kBinary;
  bool compressed = false;
  bool uint64_header = false;
  bool little_endian = true;
  bool float64 = false;
  std::size_t block_size = 100;  // small, so that the data spans several zlib blocks
  int pieces = 1;                // split along z
};

/// One binary block as VTK writes it: byte count + data, or block table + zlib blocks.
std::pair<std::string, std::string> vtk_block(const std::string& data, const VtiOptions& o) {
  const auto header_value = [&](std::string& out, std::uint64_t v) {
    if (o.uint64_header) {
      put(out, v, o.little_endian);
    } else {
      put(out, static_cast<std::uint32_t>(v), o.little_endian);
    }
  };
  std::string header;
  if (!o.compressed) {
    header_value(header, data.size());
    return {header, data};
  }
  std::vector<std::string> blocks;
  for (std::size_t at = 0; at < data.size(); at += o.block_size)
    blocks.push_back(detail::zlib_deflate(data.substr(at, o.block_size)));
  header_value(header, blocks.size());
  header_value(header, o.block_size);
  header_value(header, data.size() % o.block_size);
  std::string body;
  for (const std::string& b : blocks) {
    header_value(header, b.size());
    body += b;
  }
  return {header, body};
}

std::string typed_bytes(const std::vector<float>& values, const VtiOptions& o) {
  std::string bytes;
  for (const float v : values) {
    if (o.float64) {
      put(bytes, static_cast<double>(v), o.little_endian);
    } else {
      put(bytes, v, o.little_endian);
    }
  }
  return bytes;
}

/// A .vti with a scalar array "p" and the vector array "velocity" per piece.
std::string vti_file(const VectorGrid& grid, const VtiOptions& o, const std::string& extra_attributes = "") {
  const auto& n = grid.geometry.size;
  const auto nc = static_cast<std::size_t>(grid.components);
  std::ostringstream xml;
  xml << "<?xml version=\"1.0\"?>\n<!-- written by the test -->\n<VTKFile type=\"ImageData\" version=\"1.0\" byte_order=\""
      << (o.little_endian ? "LittleEndian" : "BigEndian") << "\" header_type=\""
      << (o.uint64_header ? "UInt64" : "UInt32") << "\""
      << (o.compressed ? " compressor=\"vtkZLibDataCompressor\"" : "") << extra_attributes << ">\n";
  xml << "  <ImageData WholeExtent=\"2 " << n[0] + 1 << " 0 " << n[1] - 1 << " -1 " << n[2] - 2
      << "\" Origin=\"1 2 3\" Spacing=\"0.5 0.25 2\" Direction=\"1 0 0 0 1 0 0 0 1\">\n";
  std::string appended;
  const auto array = [&](const std::string& name, std::size_t components,
                         const std::vector<float>& values) {
    xml << "        <DataArray type=\"" << (o.float64 ? "Float64" : "Float32") << "\" Name=\"" << name
        << "\" NumberOfComponents=\"" << components << "\" format=\"";
    if (o.mode == Mode::kAscii) {
      xml << "ascii\">\n";
      for (const float v : values) xml << std::to_string(v) << " ";
      xml << "\n        </DataArray>\n";
      return;
    }
    const auto [header, body] = vtk_block(typed_bytes(values, o), o);
    if (o.mode == Mode::kBinary) {
      // Header and data encoded separately, as VTK does.
      xml << "binary\">\n          " << detail::base64_encode(header) << detail::base64_encode(body)
          << "\n        </DataArray>\n";
      return;
    }
    xml << "appended\" offset=\"" << appended.size() << "\"/>\n";
    if (o.mode == Mode::kAppendedRaw) {
      appended += header + body;
    } else {
      appended += detail::base64_encode(header) + detail::base64_encode(body);
    }
  };
  const std::int64_t per_piece = (n[2] + o.pieces - 1) / o.pieces;
  for (int p = 0; p < o.pieces; ++p) {
    const std::int64_t k0 = p * per_piece;
    const std::int64_t k1 = std::min(n[2] - 1, k0 + per_piece - 1);
    xml << "    <Piece Extent=\"2 " << n[0] + 1 << " 0 " << n[1] - 1 << " " << k0 - 1 << " " << k1 - 1
        << "\">\n      <PointData Scalars=\"p\" Vectors=\"velocity\">\n";
    std::vector<float> p_values;
    std::vector<float> v_values;
    for (std::int64_t k = k0; k <= k1; ++k) {
      for (std::int64_t j = 0; j < n[1]; ++j) {
        for (std::int64_t i = 0; i < n[0]; ++i) {
          const std::size_t at = grid.geometry.index(i, j, k);
          p_values.push_back(static_cast<float>(at));
          for (std::size_t c = 0; c < nc; ++c) v_values.push_back(grid.values[at * nc + c]);
        }
      }
    }
    array("p", 1, p_values);
    array("velocity", nc, v_values);
    xml << "      </PointData>\n      <CellData>\n      </CellData>\n    </Piece>\n";
  }
  xml << "  </ImageData>\n";
  if (o.mode == Mode::kAppendedRaw || o.mode == Mode::kAppendedBase64) {
    xml << "  <AppendedData encoding=\"" << (o.mode == Mode::kAppendedRaw ? "raw" : "base64")
        << "\">\n   _" << appended << "\n  </AppendedData>\n";
  }
  xml << "</VTKFile>\n";
  return xml.str();
}

}  // namespace

TEST_CASE("vti: synthetic files read back exactly in every layout", "[vti]") {
  TempDir dir("vti");
  const VectorGrid expected = sample_grid(5, 4, 3, 3, true);
  const Mode mode = GENERATE(Mode::kAscii, Mode::kBinary, Mode::kAppendedRaw, Mode::kAppendedBase64);
  const bool compressed = GENERATE(false, true);
  const bool uint64_header = GENERATE(false, true);
  const bool little = GENERATE(true, false);
  const bool float64 = GENERATE(false, true);
  const int pieces = GENERATE(1, 2);
  if (mode == Mode::kAscii && (compressed || uint64_header || !little)) return;  // no binary
  VtiOptions o;
  o.mode = mode;
  o.compressed = compressed;
  o.uint64_header = uint64_header;
  o.little_endian = little;
  o.float64 = float64;
  o.pieces = pieces;
  INFO("mode " << static_cast<int>(mode) << " compressed " << compressed << " UInt64 " << uint64_header
               << " little " << little << " Float64 " << float64 << " pieces " << pieces);
  write_file(dir / "a.vti", vti_file(expected, o));
  const VectorGrid grid = read_vti(dir / "a.vti");
  CHECK(grid.geometry.dimension == 3);
  CHECK(grid.geometry.size == std::array<std::int64_t, 3>{5, 4, 3});
  CHECK(grid.components == 3);
  // Origin + WholeExtent start * Spacing.
  CHECK(grid.geometry.origin == Vec3(2, 2, 1));
  CHECK(grid.geometry.spacing == Vec3(0.5, 0.25, 2));
  CHECK(same_values(grid.values, expected.values));
  CHECK(std::isnan(grid.values[3]));
}

TEST_CASE("vti: choosing the array and 2D images", "[vti]") {
  TempDir dir("vti");
  const VectorGrid expected = sample_grid(4, 3, 1, 2);
  VtiOptions o;
  o.compressed = true;
  std::string text = vti_file(expected, o);
  // No Vectors attribute: the first array with 2 or 3 components is taken.
  text.replace(text.find(" Vectors=\"velocity\""), 19, "");
  write_file(dir / "flat.vti", text);
  const VectorGrid grid = read_vti(dir / "flat.vti");
  CHECK(grid.geometry.dimension == 2);
  CHECK(grid.components == 2);
  CHECK(same_values(grid.values, expected.values));
  CHECK_THAT(thrown<FormatError>([&] { read_vti(dir / "flat.vti", "p"); }),
             Contains("flat.vti") && Contains("'p'") && Contains("not vector data"));
  CHECK_THAT(thrown<FormatError>([&] { read_vti(dir / "flat.vti", "nothing"); }),
             Contains("flat.vti") && Contains("no point data array named 'nothing'") &&
                 Contains("velocity (2 components)"));
}

TEST_CASE("vti: points ParaView marks invalid (vtkValidPointMask = 0) are no data", "[vti]") {
  // As ResampleToImage writes a slice: one z plane of spacing 0, Int8 mask, values where the mask
  // is 0 that are not zero.
  TempDir dir("vti");
  write_file(dir / "masked.vti",
             "<VTKFile type=\"ImageData\" version=\"1.0\" byte_order=\"LittleEndian\">\n"
             "<ImageData WholeExtent=\"0 2 0 1 0 0\" Origin=\"0 0 0\" Spacing=\"1 1 0\">\n"
             "<Piece Extent=\"0 2 0 1 0 0\"><PointData Vectors=\"U\">\n"
             "<DataArray type=\"Float32\" Name=\"U\" NumberOfComponents=\"2\" "
             "format=\"ascii\">1 0 2 0 3 0 4 0 5 0 6 0</DataArray>\n"
             "<DataArray type=\"Int8\" Name=\"vtkValidPointMask\" format=\"ascii\">1 1 0 1 0 1"
             "</DataArray>\n</PointData></Piece></ImageData></VTKFile>\n");
  const VectorGrid grid = read_vti(dir / "masked.vti");
  REQUIRE(grid.values.size() == 12);
  for (std::size_t p = 0; p < 6; ++p) {
    INFO("point " << p);
    if (p == 2 || p == 4) {
      CHECK(std::isnan(grid.values[2 * p]));
      CHECK(std::isnan(grid.values[2 * p + 1]));
    } else {
      CHECK(grid.values[2 * p] == static_cast<float>(p + 1));
      CHECK(grid.values[2 * p + 1] == 0.0f);
    }
  }
}

TEST_CASE("vti: bad files are rejected naming the file and the value", "[vti]") {
  TempDir dir("vti");
  const VectorGrid grid = sample_grid(5, 4, 3);
  VtiOptions o;

  SECTION("truncated appended data") {
    o.mode = Mode::kAppendedRaw;
    o.compressed = GENERATE(false, true);
    const std::string text = vti_file(grid, o);
    write_file(dir / "short.vti", text.substr(0, text.size() - 200));
    CHECK_THAT(thrown<FormatError>([&] { read_vti(dir / "short.vti"); }),
               Contains("short.vti") && Contains("velocity") && Contains("truncated"));
  }
  SECTION("damaged compressed data") {
    o.mode = Mode::kAppendedRaw;
    o.compressed = true;
    std::string text = vti_file(grid, o);
    const std::size_t at = text.rfind("</AppendedData>") - 300;
    for (std::size_t i = 0; i < 40; ++i) text[at + i] = static_cast<char>(text[at + i] ^ 0x5a);
    write_file(dir / "bad.vti", text);
    CHECK_THAT(thrown<FormatError>([&] { read_vti(dir / "bad.vti"); }),
               Contains("bad.vti") && Contains("velocity") && Contains("block"));
  }
  SECTION("an extent that does not match the data") {
    std::string text = vti_file(grid, o);
    const std::string from = "Extent=\"2 6 0 3 -1 1\"";
    REQUIRE(text.find(from) != std::string::npos);
    text.replace(text.find("WholeExtent=\"2 6 0 3 -1 1\""), 26, "WholeExtent=\"2 6 0 3 -1 2\"");
    text.replace(text.find("<Piece " + from), 7 + from.size(), "<Piece Extent=\"2 6 0 3 -1 2\"");
    write_file(dir / "dims.vti", text);
    CHECK_THAT(thrown<FormatError>([&] { read_vti(dir / "dims.vti"); }),
               Contains("dims.vti") && Contains("velocity") &&
                   Contains("holds 180 values; the extent needs 240"));
  }
  SECTION("non-vector data") {
    std::string text = vti_file(grid, o);
    const std::size_t a = text.find("        <DataArray type=\"Float32\" Name=\"velocity\"");
    const std::size_t b = text.find("</DataArray>", a) + 13;
    text.erase(a, b - a);
    write_file(dir / "scalar.vti", text);
    CHECK_THAT(thrown<FormatError>([&] { read_vti(dir / "scalar.vti"); }),
               Contains("scalar.vti") && Contains("no vector point data") &&
                   Contains("p (1 components)"));
  }
  SECTION("unsupported compressor and format") {
    o.compressed = true;
    std::string text = vti_file(grid, o);
    text.replace(text.find("vtkZLibDataCompressor"), 21, "vtkLZ4DataCompressor");
    write_file(dir / "lz4.vti", text);
    CHECK_THAT(thrown<FormatError>([&] { read_vti(dir / "lz4.vti"); }),
               Contains("lz4.vti") && Contains("unsupported compressor 'vtkLZ4DataCompressor'"));
    text = vti_file(grid, VtiOptions{});
    text.replace(text.find("format=\"binary\""), 15, "format=\"hex\"");
    write_file(dir / "hex.vti", text);
    CHECK_THAT(thrown<FormatError>([&] { read_vti(dir / "hex.vti"); }),
               Contains("hex.vti") && Contains("unsupported format 'hex'"));
  }
  SECTION("not image data") {
    write_file(dir / "poly.vti", "<VTKFile type=\"PolyData\"><PolyData/></VTKFile>");
    CHECK_THAT(thrown<FormatError>([&] { read_vti(dir / "poly.vti"); }),
               Contains("poly.vti") && Contains("expected ImageData"));
  }
  SECTION("a rotated image") {
    std::string text = vti_file(grid, o);
    text.replace(text.find("Direction=\"1 0 0 0 1 0 0 0 1\""), 29, "Direction=\"0 1 0 1 0 0 0 0 1\"");
    write_file(dir / "rot.vti", text);
    CHECK_THAT(thrown<FormatError>([&] { read_vti(dir / "rot.vti"); }),
               Contains("rot.vti") && Contains("Direction"));
  }
}

TEST_CASE("vti: tornado step 1 as .vti and as .vec gives identical values", "[vti][realdata]") {
  const fs::path dir = datasets_dir("tornado");
  if (dir.empty()) return;
  const VectorGrid vti = read_vti(dir / "1.vti");
  const VectorGrid vec = orthofront::io::read_vec(dir / "1.vec");
  CHECK(vti.geometry.size == vec.geometry.size);
  CHECK(vti.geometry.origin == vec.geometry.origin);
  CHECK(vti.geometry.spacing == vec.geometry.spacing);
  CHECK(vti.components == 3);
  CHECK(vti.values == vec.values);  // bit for bit
}

TEST_CASE("vti: a compression header claiming 4 GiB is refused before allocating", "[vti]") {
  const std::string payload = orthofront::io::detail::zlib_deflate(std::string(16, 'x'));
  std::string block;
  const auto put = [&](std::uint32_t v) { block.append(reinterpret_cast<const char*>(&v), 4); };
  put(1);            // one block
  put(0xffffffffu);  // block size
  put(0);            // the last block is full: 4 GiB claimed
  put(static_cast<std::uint32_t>(payload.size()));
  block += payload;
  orthofront::io::detail::VtkLayout layout;
  layout.compressor = "vtkZLibDataCompressor";
  CHECK_THAT(thrown<FormatError>([&] {
               orthofront::io::detail::decode_vtk_block(block, layout, "big.vti: velocity");
             }),
             Contains("big.vti") && Contains("4294967295") && Contains("more than deflate"));
}

TEST_CASE("vti: compressed block sizes that wrap around 2^64 are refused", "[vti]") {
  // Two block sizes whose sum wraps around to fit once sent the second block's start past the end
  // of the data (std::out_of_range from substr). The same file is in fuzz/regressions/grid_vti.
  const std::string payload = orthofront::io::detail::zlib_deflate(std::string(12, 'x'));
  std::string block;
  const auto put = [&](std::uint64_t v) { block.append(reinterpret_cast<const char*>(&v), 8); };
  put(2);   // two blocks
  put(12);  // of 12 bytes
  put(0);   // the last one full
  put(payload.size() + 100);
  put(std::uint64_t{0} - 100);
  block += payload;
  orthofront::io::detail::VtkLayout layout;
  layout.header_size = 8;
  layout.compressor = "vtkZLibDataCompressor";
  CHECK_THAT(thrown<FormatError>([&] {
               orthofront::io::detail::decode_vtk_block(block, layout, "wrap.vti: velocity");
             }),
             Contains("wrap.vti: velocity declares more than 2^64 compressed bytes") &&
                 Contains("truncated"));
}

TEST_CASE("vti: a tiny file whose WholeExtent claims a huge image is refused before allocating",
          "[vti]") {
  // The grid is filled before the pieces are read: a WholeExtent beyond what the file's bytes can
  // hold (one ascii character and a separator per value, the scalar's bytes per binary value, at
  // most 1032 times that when compressed) is refused first. The same files are in
  // fuzz/regressions/grid_vti.
  TempDir dir("vti");
  const auto file = [](const std::string& whole, const std::string& compressor,
                       const std::string& array) {
    return "<VTKFile type=\"ImageData\" version=\"1.0\" byte_order=\"LittleEndian\"" +
           compressor + ">\n<ImageData WholeExtent=\"" + whole +
           "\" Origin=\"0 0 0\" Spacing=\"1 1 1\">\n<Piece Extent=\"0 0 0 0 0 0\">\n"
           "<PointData Vectors=\"velocity\">\n<DataArray type=\"Float32\" Name=\"velocity\" "
           "NumberOfComponents=\"3\" " + array + "</DataArray>\n</PointData>\n</Piece>\n"
           "</ImageData>\n</VTKFile>\n";
  };
  struct Case {
    const char* name;
    std::string bytes;
    std::vector<std::string> message;
  };
  const std::vector<Case> cases = {
      {"ascii.vti", file("0 3999 0 3999 0 3999", "", "format=\"ascii\">1 2 3"),
       {"truncated: WholeExtent 4000 x 4000 x 4000 needs 192000000000 values of point data "
        "'velocity'"}},
      // 12 bytes "\x0c\0\0\0" + 3 floats, base64.
      {"binary.vti", file("0 3999 0 3999 0 3999", "", "format=\"binary\">DAAAAAAAgD8AAABAAABAQA=="),
       {"truncated: WholeExtent 4000 x 4000 x 4000 needs 192000000000 values"}},
      {"zlib.vti",
       file("0 999 0 999 0 999", " compressor=\"vtkZLibDataCompressor\"",
            "format=\"binary\">AQAAAAwAAAAMAAAAEgAAAHicY2BosGdgYHAAIgcACUMBgA=="),
       {"truncated: WholeExtent 1000 x 1000 x 1000 needs 3000000000 values"}},
  };
  for (const Case& c : cases) {
    INFO(c.name);
    write_file(dir / c.name, c.bytes);
    std::string message;
    const test_support::Footprint f = test_support::footprint(
        [&] { message = thrown<FormatError>([&] { read_vti(dir / c.name); }); });
    CHECK_THAT(message, Contains(c.name));
    for (const std::string& part : c.message) CHECK_THAT(message, Contains(part));
    CHECK_THAT(message, Contains("bytes hold at most"));
    CHECK(f.seconds < test_support::kHostileSeconds);
    CHECK(f.peak_growth_kib < test_support::kHostileGrowthKib);
  }
  // The same pieces under their own extent read back.
  for (const Case& c : cases) {
    std::string bytes = c.bytes;
    const std::size_t at = bytes.find("WholeExtent=\"") + 13;
    bytes.replace(at, bytes.find('"', at) - at, "0 0 0 0 0 0");
    write_file(dir / "one.vti", bytes);
    INFO(c.name);
    const VectorGrid grid = read_vti(dir / "one.vti");
    CHECK(grid.values == std::vector<float>{1, 2, 3});
  }
}
