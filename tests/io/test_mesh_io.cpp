#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <catch2/catch.hpp>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "io/hostile_file.h"
#include "orthofront/error.h"
#include "orthofront/io/atomic_file.h"
#include "orthofront/io/base64.h"
#include "orthofront/io/error.h"
#include "orthofront/io/mesh_io.h"
#include "orthofront/mesh/mesh.h"
#include "temp_dir.h"

namespace fs = std::filesystem;
using Catch::Matchers::Contains;
using orthofront::Face;
using orthofront::InvalidArgument;
using orthofront::Mesh;
using orthofront::Vec3;
using orthofront::io::FormatError;
using orthofront::io::IoError;
using orthofront::io::read_mesh;
using orthofront::io::write_mesh;
using test_support::read_text;

namespace {

using test_support::TempDir;

void write_text(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

/// The message of the E that `f` throws; fails the test when it throws nothing.
template <typename E>
std::string thrown(const std::function<void()>& f) {
  try {
    f();
  } catch (const E& e) {
    return e.what();
  }
  FAIL("no exception was thrown");
  return {};
}

/// Quads and triangles over a 4 x 3 vertex grid, with values that need all 64 bits (thirds,
/// sevenths, exponentials) and the extremes: -0, the smallest subnormal, the largest double,
/// the 32-bit integer limits.
Mesh sample_mesh() {
  Mesh mesh;
  constexpr int kNx = 4;
  constexpr int kNy = 3;
  for (int j = 0; j < kNy; ++j) {
    for (int i = 0; i < kNx; ++i) {
      const Vec3 p(i / 3.0 + 1e-3 * std::sin(i * j + 0.1), j / 7.0 - 0.5,
                   std::exp(-i) * std::sqrt(2.0) * (j + 1));
      mesh.add_vertex(p, 0.1 * i + j / 3.0, 1.0 / (1 + i + j), i / 3.0,
                      std::pow(10.0, -i - j) / 7.0, j - 1, i * 1000003 - 7);
    }
  }
  mesh.positions[0] =
      Vec3(-0.0, std::numeric_limits<double>::denorm_min(), std::numeric_limits<double>::max());
  mesh.time[2] = -1e-300;
  mesh.error[1] = std::numeric_limits<double>::denorm_min();
  mesh.front_id[3] = std::numeric_limits<std::int32_t>::min();
  mesh.step[4] = std::numeric_limits<std::int32_t>::max();
  for (int j = 0; j + 1 < kNy; ++j) {
    for (int i = 0; i + 1 < kNx; ++i) {
      const std::int32_t a = j * kNx + i;
      const std::int32_t b = a + 1;
      const std::int32_t c = a + kNx + 1;
      const std::int32_t d = a + kNx;
      if ((i + j) % 2 == 0) {
        mesh.add_quad(a, b, c, d);
      } else {
        mesh.add_triangle(a, b, c);
        mesh.add_triangle(a, c, d);
      }
    }
  }
  return mesh;
}

bool same_bits(double a, double b) {
  return std::bit_cast<std::uint64_t>(a) == std::bit_cast<std::uint64_t>(b);
}

/// Bit-for-bit equality of two value lists (or just equal values: -0 == 0), reporting the
/// first difference.
template <typename T, typename A, typename B>
void require_identical(const std::vector<T, A>& actual, const std::vector<T, B>& expected,
                       const std::string& what, bool bitwise = true) {
  INFO(what);
  REQUIRE(actual.size() == expected.size());
  for (std::size_t i = 0; i < actual.size(); ++i) {
    bool same = false;
    if constexpr (std::is_same_v<T, double>) {
      same = bitwise ? same_bits(actual[i], expected[i]) : actual[i] == expected[i];
    } else {
      same = actual[i] == expected[i];
    }
    if (!same) {
      std::ostringstream values;
      values.precision(17);
      values << "index " << i << ": " << actual[i] << " != " << expected[i];
      FAIL(what + " differ at " + values.str());
    }
  }
}

void require_same_positions(const Mesh& actual, const Mesh& expected, bool bitwise = true) {
  std::vector<double> a;
  std::vector<double> e;
  for (const Vec3& p : actual.positions) a.insert(a.end(), {p.x(), p.y(), p.z()});
  for (const Vec3& p : expected.positions) e.insert(e.end(), {p.x(), p.y(), p.z()});
  require_identical(a, e, "positions", bitwise);
}

void require_same_attributes(const Mesh& actual, const Mesh& expected, bool bitwise = true) {
  require_identical(actual.time, expected.time, "time", bitwise);
  require_identical(actual.alpha, expected.alpha, "alpha", bitwise);
  require_identical(actual.s, expected.s, "s", bitwise);
  require_identical(actual.error, expected.error, "error", bitwise);
  require_identical(actual.front_id, expected.front_id, "front_id");
  require_identical(actual.step, expected.step, "step");
}

bool has_no_attributes(const Mesh& mesh) {
  return mesh.time.empty() && mesh.alpha.empty() && mesh.s.empty() && mesh.error.empty() &&
         mesh.front_id.empty() && mesh.step.empty();
}

}  // namespace

TEST_CASE("meshes round-trip through .ply, .vtp and .obj", "[io][mesh]") {
  const std::string extension = GENERATE(as<std::string>{}, ".ply", ".vtp", ".obj");
  INFO("format " << extension);
  const Mesh mesh = sample_mesh();
  REQUIRE(mesh.faces.size() == 9);
  TempDir dir;
  const fs::path path = dir / ("mesh" + extension);
  write_mesh(mesh, path);
  CHECK(dir.entries() == std::vector<std::string>{"mesh" + extension});

  const Mesh back = read_mesh(path);
  require_same_positions(back, mesh);  // .obj too: the shortest exact decimal text is written
  CHECK(back.faces == mesh.faces);
  if (extension == ".obj") {
    CHECK(has_no_attributes(back));
  } else {
    require_same_attributes(back, mesh);
  }
}

TEST_CASE(".vtp files carry the mesh's notes as field data, read back exactly", "[io][mesh]") {
  Mesh mesh = sample_mesh();
  mesh.notes = {{"source", "data/day*.nc:u,v & \"w\" <tab>\there"},
                {"position_units", "degrees: x longitude east (\u00b0)"}, {"empty", ""}};
  TempDir dir;
  write_mesh(mesh, dir / "noted.vtp");
  const std::string text = read_text(dir / "noted.vtp");
  CHECK(text.find("<FieldData>") < text.find("<Piece"));
  const Mesh back = read_mesh(dir / "noted.vtp");
  CHECK(back.notes == mesh.notes);
  require_same_positions(back, mesh);
  CHECK(back.faces == mesh.faces);
  // Other formats have no room for them; a mesh without notes writes no field data.
  mesh.notes.clear();
  write_mesh(mesh, dir / "plain.vtp");
  CHECK(read_text(dir / "plain.vtp").find("FieldData") == std::string::npos);
}

TEST_CASE("empty meshes and meshes without attributes round-trip", "[io][mesh]") {
  const std::string extension = GENERATE(as<std::string>{}, ".ply", ".vtp", ".obj");
  INFO("format " << extension);
  TempDir dir;
  const Mesh empty;
  write_mesh(empty, dir / ("empty" + extension));
  const Mesh empty_back = read_mesh(dir / ("empty" + extension));
  CHECK(empty_back.positions.empty());
  CHECK(empty_back.faces.empty());

  Mesh bare = sample_mesh();
  bare.time.clear();
  bare.alpha.clear();
  bare.s.clear();
  bare.error.clear();
  bare.step.clear();
  write_mesh(bare, dir / ("bare" + extension));
  const Mesh bare_back = read_mesh(dir / ("bare" + extension));
  require_same_positions(bare_back, bare);
  CHECK(bare_back.faces == bare.faces);
  if (extension != ".obj") require_same_attributes(bare_back, bare);  // front_id only
}

TEST_CASE("ascii PLY with other property types, lists and elements is read", "[io][mesh][ply]") {
  TempDir dir;
  const fs::path path = dir / "hand.ply";
  write_text(path,
             "ply\r\n"
             "format ascii 1.0\r\n"
             "comment written by hand\r\n"
             "element vertex 5\r\n"
             "property float x\r\n"
             "property float32 y\r\n"
             "property double z\r\n"
             "property uchar red\r\n"
             "property list uchar float texcoord\r\n"
             "property double time\r\n"
             "property uint front_id\r\n"
             "property short step\r\n"
             "element face 2\r\n"
             "property uchar flags\r\n"
             "property list uchar uint vertex_index\r\n"
             "element edge 1\r\n"
             "property int vertex1\r\n"
             "property int vertex2\r\n"
             "end_header\r\n"
             "0 0 0 255 2 0.5 0.5 0.25 7 -3\r\n"
             "1 0 0 0 0 1.25 7 -2\r\n"
             "1 1 -2.5 0 1 9 2.5 8 -1\r\n"
             "0 1 0 0 0 3.5 8 0\r\n"
             "0.5 2 +1e-3 0 0 4.5 9 1\r\n"
             "3 4 0 1 2 3\r\n"
             "0 3 2 4 3\r\n"
             "0 1\r\n");
  const Mesh mesh = read_mesh(path);
  REQUIRE(mesh.positions.size() == 5);
  CHECK(mesh.positions[2] == Vec3(1, 1, -2.5));
  CHECK(mesh.positions[4] == Vec3(0.5, 2, 1e-3));
  CHECK(mesh.time == std::vector<double>{0.25, 1.25, 2.5, 3.5, 4.5});
  CHECK(mesh.front_id == std::vector<std::int32_t>{7, 7, 8, 8, 9});
  CHECK(mesh.step == std::vector<std::int32_t>{-3, -2, -1, 0, 1});
  CHECK(mesh.alpha.empty());
  CHECK(mesh.s.empty());
  CHECK(mesh.error.empty());
  REQUIRE(mesh.faces.size() == 2);
  CHECK(mesh.faces[0] == Face{{0, 1, 2, 3}, 4});
  CHECK(mesh.faces[1] == Face{{2, 4, 3, -1}, 3});
}

namespace {

template <typename T>
void put_big_endian(std::string& out, T value) {
  unsigned char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  if constexpr (std::endian::native == std::endian::little) std::reverse(bytes, bytes + sizeof(T));
  out.append(reinterpret_cast<const char*>(bytes), sizeof(T));
}

}  // namespace

TEST_CASE("big-endian binary PLY is read", "[io][mesh][ply]") {
  TempDir dir;
  const fs::path path = dir / "big.ply";
  std::string data =
      "ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nproperty int16 step\nelement face 1\n"
      "property list uint8 uint16 vertex_indices\nend_header\n";
  const float coordinates[3][3] = {{1.5f, -2.0f, 0.25f}, {3.0f, 4.0f, 5.0f}, {-1.0f, 0.0f, 2.0f}};
  for (int i = 0; i < 3; ++i) {
    for (const float c : coordinates[i]) put_big_endian(data, c);
    put_big_endian<std::int16_t>(data, static_cast<std::int16_t>(-300 + i));
  }
  put_big_endian<std::uint8_t>(data, 3);
  for (const std::uint16_t v : {2, 0, 1}) put_big_endian(data, v);
  write_text(path, data);

  const Mesh mesh = read_mesh(path);
  REQUIRE(mesh.positions.size() == 3);
  CHECK(mesh.positions[0] == Vec3(1.5, -2.0, 0.25));
  CHECK(mesh.positions[2] == Vec3(-1.0, 0.0, 2.0));
  CHECK(mesh.step == std::vector<std::int32_t>{-300, -299, -298});
  CHECK(mesh.faces == std::vector<Face>{Face{{2, 0, 1, -1}, 3}});
}

TEST_CASE("truncated binary PLY files are rejected naming the file", "[io][mesh][ply]") {
  TempDir dir;
  const fs::path path = dir / "cut.ply";
  write_mesh(sample_mesh(), path);
  const std::string data = read_text(path);
  const std::size_t body = data.find("end_header\n") + std::string("end_header\n").size();
  constexpr std::size_t kVertexBytes = 3 * 8 + 4 * 8 + 2 * 4;

  write_text(path, data.substr(0, body + 3 * kVertexBytes + 10));
  const std::string in_vertices = thrown<FormatError>([&] { read_mesh(path); });
  CHECK_THAT(in_vertices, Contains("cut.ply") && Contains("vertex count 12") &&
                              Contains("file ends after 3 vertices"));

  write_text(path, data.substr(0, data.size() - 3));
  const std::string in_faces = thrown<FormatError>([&] { read_mesh(path); });
  CHECK_THAT(in_faces, Contains("cut.ply") && Contains("face count 9 but file ends after 8 faces"));

  write_text(path, data.substr(0, body - 5));
  CHECK_THAT(thrown<FormatError>([&] { read_mesh(path); }),
             Contains("cut.ply") && Contains("end_header"));
}

TEST_CASE("a tiny PLY file claiming 2e9 vertices is refused before allocating for them",
          "[io][mesh][ply]") {
  // The reservation is bounded by what the rest of the body can hold, not by the header's count.
  // The same file is in fuzz/regressions/mesh_ply.
  TempDir dir;
  const fs::path path = dir / "huge.ply";
  for (const std::string format : {"binary_little_endian", "ascii"}) {
    INFO(format);
    write_text(path,
               "ply\nformat " + format +
                   " 1.0\nelement vertex 2000000000\nproperty float x\nproperty float y\n"
                   "property float z\nelement face 2000000000\n"
                   "property list uchar int vertex_indices\nend_header\n" +
                   (format == "ascii" ? std::string("0 0 0\n1 0 0\n") : std::string(24, '\0')));
    std::string message;
    const test_support::Footprint f =
        test_support::footprint([&] { message = thrown<FormatError>([&] { read_mesh(path); }); });
    CHECK_THAT(message, Contains("huge.ply") && Contains("vertex count 2000000000") &&
                            Contains("file ends after 2 vertices"));
    CHECK(f.seconds < test_support::kHostileSeconds);
    CHECK(f.peak_growth_kib < test_support::kHostileGrowthKib);
  }
  // An element without properties takes no bytes whatever its count: it is not iterated.
  write_text(path,
             "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
             "property float y\nproperty float z\nelement nothing 18446744073709551615\n"
             "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
             "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  Mesh mesh;
  const test_support::Footprint f = test_support::footprint([&] { mesh = read_mesh(path); });
  CHECK(mesh.positions.size() == 3);
  CHECK(mesh.faces.size() == 1);
  CHECK(f.seconds < test_support::kHostileSeconds);
}

TEST_CASE("faces with more than four vertices are a FormatError", "[io][mesh]") {
  TempDir dir;
  const fs::path ply = dir / "penta.ply";
  write_text(ply,
             "ply\nformat ascii 1.0\nelement vertex 5\nproperty double x\nproperty double y\n"
             "property double z\nelement face 1\nproperty list uchar int vertex_indices\n"
             "end_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0 2 0\n5 0 1 2 3 4\n");
  CHECK_THAT(thrown<FormatError>([&] { read_mesh(ply); }),
             Contains("penta.ply") && Contains("5 vertices"));

  const fs::path obj = dir / "penta.obj";
  write_text(obj, "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 2 0\nf 1 2 3 4 5\n");
  CHECK_THAT(thrown<FormatError>([&] { read_mesh(obj); }),
             Contains("penta.obj") && Contains("line 6") && Contains("5 vertices"));

  const fs::path bad_index = dir / "bad_index.obj";
  write_text(bad_index, "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 4\n");
  CHECK_THAT(thrown<FormatError>([&] { read_mesh(bad_index); }),
             Contains("bad_index.obj") && Contains("refers to vertex 4"));
}

TEST_CASE("OBJ reader takes v and f lines in all their forms", "[io][mesh][obj]") {
  TempDir dir;
  const fs::path path = dir / "forms.obj";
  write_text(path,
             "# a comment\nmtllib forms.mtl\no thing\n"
             "v 0 0 0\nv 1 0 0\nv 1 1 0 1.0\nv 0 1 0 0.5 0.5 0.5\n"
             "vt 0 0\nvn 0 0 1\ng group\ns off\nusemtl red\n"
             "f 1/1/1 2/1/1 3/1/1 4/1/1\r\n"
             "f -4//1 -2//1 -1//1\n"
             "v 2 2 2\n"
             "f 5/1 -4 3\n"
             "l 1 2\n");
  const Mesh mesh = read_mesh(path);
  REQUIRE(mesh.positions.size() == 5);
  CHECK(mesh.positions[4] == Vec3(2, 2, 2));
  CHECK(mesh.faces ==
        std::vector<Face>{Face{{0, 1, 2, 3}, 4}, Face{{0, 2, 3, -1}, 3}, Face{{4, 1, 2, -1}, 3}});
  CHECK(has_no_attributes(mesh));
}

TEST_CASE("ascii VTK XML PolyData in ParaView's layout is read", "[io][mesh][vtp]") {
  TempDir dir;
  const fs::path path = dir / "paraview.vtp";
  write_text(path, R"(<?xml version="1.0"?>
<!-- ascii output as ParaView writes it, with arrays orthofront does not know -->
<VTKFile type="PolyData" version="1.0" byte_order="LittleEndian" header_type="UInt64">
  <PolyData>
    <FieldData>
      <DataArray type="Float64" Name="TimeValue" NumberOfTuples="1" format="ascii">3.5</DataArray>
    </FieldData>
    <Piece NumberOfPoints="5" NumberOfVerts="0" NumberOfLines="0" NumberOfStrips="1" NumberOfPolys="2">
      <PointData Scalars="time">
        <DataArray type="Float32" Name="Velocity" NumberOfComponents="3" format="ascii" RangeMin="0" RangeMax="1">
          1 0 0 1 0 0 1 0 0
          1 0 0 1 0 0
        </DataArray>
        <DataArray type="Float64" Name="time" format="ascii" RangeMin="0" RangeMax="1">
          0 0.25 0.5 0.75 1
        </DataArray>
        <DataArray type="Int64" Name="step" format="ascii">0 1 2 3 4</DataArray>
        <DataArray type="Float64" Name="alpha" NumberOfComponents="2" format="ascii">
          0 0 0 0 0 0 0 0 0 0
        </DataArray>
      </PointData>
      <CellData>
      </CellData>
      <Points>
        <DataArray type="Float32" Name="Points" NumberOfComponents="3" format="ascii" RangeMin="0" RangeMax="2.06">
          0 0 0 1 0 0
          1 1 0 0 1 0
          0.5 2 0
        </DataArray>
      </Points>
      <Verts>
        <DataArray type="Int64" Name="connectivity" format="ascii" RangeMin="1e+299" RangeMax="-1e+299">
        </DataArray>
        <DataArray type="Int64" Name="offsets" format="ascii" RangeMin="1e+299" RangeMax="-1e+299">
        </DataArray>
      </Verts>
      <Lines>
        <DataArray type="Int64" Name="connectivity" format="ascii"/>
        <DataArray type="Int64" Name="offsets" format="ascii"/>
      </Lines>
      <Strips>
        <DataArray type="Int64" Name="connectivity" format="ascii">0 1 3 2</DataArray>
        <DataArray type="Int64" Name="offsets" format="ascii">4</DataArray>
      </Strips>
      <Polys>
        <DataArray type="Int32" Name="connectivity" format="ascii">
          0 1 2 3 2 4 3
        </DataArray>
        <DataArray type="Int32" Name="offsets" format="ascii">
          4 7
        </DataArray>
      </Polys>
    </Piece>
  </PolyData>
</VTKFile>
)");
  const Mesh mesh = read_mesh(path);
  REQUIRE(mesh.positions.size() == 5);
  CHECK(mesh.positions[4] == Vec3(0.5, 2, 0));
  CHECK(mesh.time == std::vector<double>{0, 0.25, 0.5, 0.75, 1});
  CHECK(mesh.step == std::vector<std::int32_t>{0, 1, 2, 3, 4});
  CHECK(mesh.alpha.empty());  // two components: not the attribute
  CHECK(mesh.front_id.empty());
  // Polygons first, then the strip as triangles with alternating orientation.
  CHECK(mesh.faces == std::vector<Face>{Face{{0, 1, 2, 3}, 4}, Face{{2, 4, 3, -1}, 3},
                                        Face{{0, 1, 3, -1}, 3}, Face{{3, 1, 2, -1}, 3}});
}

TEST_CASE("binary VTK XML arrays decode with either header type and split base64",
          "[io][mesh][vtp]") {
  using orthofront::io::detail::base64_decode;
  using orthofront::io::detail::base64_encode;
  for (std::size_t n = 0; n < 12; ++n) {
    std::string bytes;
    for (std::size_t i = 0; i < n; ++i) bytes += static_cast<char>(251 - 37 * i);
    std::string decoded;
    REQUIRE(base64_decode(base64_encode(bytes), decoded));
    CHECK(decoded == bytes);
  }
  std::string decoded;
  CHECK_FALSE(base64_decode("QQ=A", decoded));
  CHECK_FALSE(base64_decode("Q$==", decoded));
  // Whole groups decode four characters at a time; whitespace anywhere, also inside a group
  // (text wrapped at any width), takes the character-by-character path and gives the same bytes.
  std::string bytes;
  for (int i = 0; i < 1000; ++i) bytes += static_cast<char>((i * 7919 + 13) % 256);
  const std::string text = base64_encode(bytes);
  for (const std::size_t width : {1, 3, 4, 5, 76}) {
    std::string wrapped;
    for (std::size_t i = 0; i < text.size(); i += width) wrapped += text.substr(i, width) + "\n ";
    REQUIRE(base64_decode(wrapped, decoded));
    CHECK(decoded == bytes);
  }
  CHECK_FALSE(base64_decode(text.substr(0, 40) + "A$AA" + text.substr(40), decoded));

  // A UInt32 byte count encoded apart from the data (padding inside the text), as some writers do.
  std::string count;
  std::string points;
  const std::uint32_t size = 3 * 8;
  count.append(reinterpret_cast<const char*>(&size), sizeof(size));  // the host is little-endian
  for (const double c : {1.0 / 3.0, -2.5, 1e-310}) {
    points.append(reinterpret_cast<const char*>(&c), sizeof(c));
  }
  REQUIRE(std::endian::native == std::endian::little);
  TempDir dir;
  const fs::path path = dir / "split.vtp";
  write_text(path,
             "<VTKFile type='PolyData' version='0.1' byte_order='LittleEndian'>\n<PolyData>\n"
             "<Piece NumberOfPoints='1' NumberOfPolys='0'>\n<Points>\n"
             "<DataArray type='Float64' NumberOfComponents='3' format='binary'>\n" +
                 base64_encode(count) + base64_encode(points) +
                 "\n</DataArray>\n</Points>\n</Piece>\n</PolyData>\n</VTKFile>\n");
  const Mesh mesh = read_mesh(path);
  REQUIRE(mesh.positions.size() == 1);
  CHECK(same_bits(mesh.positions[0].x(), 1.0 / 3.0));
  CHECK(same_bits(mesh.positions[0].z(), 1e-310));
}

TEST_CASE("damaged or unsupported .vtp files are a FormatError naming the file",
          "[io][mesh][vtp]") {
  TempDir dir;
  const fs::path path = dir / "broken.vtp";
  write_mesh(sample_mesh(), path);
  const std::string data = read_text(path);
  write_text(path, data.substr(0, data.size() / 2));
  CHECK_THAT(thrown<FormatError>([&] { read_mesh(path); }), Contains("broken.vtp"));

  const fs::path appended = dir / "appended.vtp";
  write_text(appended,
             "<VTKFile type=\"PolyData\" version=\"0.1\"><PolyData><Piece NumberOfPoints=\"1\">"
             "<Points><DataArray type=\"Float32\" NumberOfComponents=\"3\" format=\"appended\" "
             "offset=\"0\"/></Points></Piece></PolyData><AppendedData encoding=\"raw\">_<<>>"
             "</AppendedData></VTKFile>");
  CHECK_THAT(thrown<FormatError>([&] { read_mesh(appended); }),
             Contains("appended.vtp") && Contains("appended data"));

  const fs::path grid = dir / "grid.vtp";
  write_text(grid, "<VTKFile type=\"UnstructuredGrid\"><UnstructuredGrid/></VTKFile>");
  CHECK_THAT(thrown<FormatError>([&] { read_mesh(grid); }),
             Contains("grid.vtp") && Contains("UnstructuredGrid"));
}

TEST_CASE("write_mesh rejects unknown extensions and creates nothing", "[io][mesh]") {
  TempDir dir;
  CHECK(orthofront::io::is_mesh_extension("a/b.PLY"));
  CHECK(orthofront::io::is_mesh_extension("b.vtp"));
  CHECK_FALSE(orthofront::io::is_mesh_extension("b.stl"));
  CHECK_FALSE(orthofront::io::is_mesh_extension("ply"));

  const fs::path path = dir / "mesh.stl";
  CHECK_THAT(thrown<InvalidArgument>([&] { write_mesh(sample_mesh(), path); }),
             Contains("mesh.stl") && Contains(".stl"));
  CHECK(dir.entries().empty());
  CHECK_THAT(thrown<InvalidArgument>([&] { read_mesh(path); }), Contains("mesh.stl"));
}

TEST_CASE("write_mesh rejects inconsistent meshes and creates nothing", "[io][mesh]") {
  TempDir dir;
  Mesh bad_face = sample_mesh();
  bad_face.faces[2].v[1] = 12;
  CHECK_THAT(thrown<InvalidArgument>([&] { write_mesh(bad_face, dir / "a.ply"); }),
             Contains("a.ply") && Contains("face 2") && Contains("vertex 12"));
  Mesh bad_attribute = sample_mesh();
  bad_attribute.alpha.pop_back();
  CHECK_THAT(thrown<InvalidArgument>([&] { write_mesh(bad_attribute, dir / "b.vtp"); }),
             Contains("b.vtp") && Contains("alpha"));
  CHECK(dir.entries().empty());
}

TEST_CASE("writing into a missing directory is an IoError and leaves no file", "[io][mesh]") {
  TempDir dir;
  const fs::path path = dir / "missing" / "mesh.ply";
  CHECK_THAT(thrown<IoError>([&] { write_mesh(sample_mesh(), path); }),
             Contains(path.string()) && Contains("does not exist"));
  CHECK_FALSE(fs::exists(dir / "missing"));
  CHECK(dir.entries().empty());

  CHECK_THAT(thrown<IoError>([&] { orthofront::io::check_writable(path); }),
             Contains(path.string()));
  CHECK_NOTHROW(orthofront::io::check_writable(dir / "mesh.ply"));

  CHECK_THAT(thrown<IoError>([&] { read_mesh(dir / "absent.obj"); }),
             Contains("absent.obj") && Contains("No such file"));
}

TEST_CASE("write_atomically never leaves a partial file", "[io][atomic]") {
  TempDir dir;
  const fs::path target = dir / "out.bin";
  const fs::path temp = dir / ("out.bin.tmp-" + std::to_string(::getpid()));
  bool target_expected = false;
  const auto failing = [&](std::ofstream& out) {
    out << "partial content";
    CHECK(fs::exists(temp));  // written under the temporary name ...
    CHECK(fs::exists(target) == target_expected);
    throw std::runtime_error("writer gave up");
  };

  const std::string message =
      thrown<IoError>([&] { orthofront::io::write_atomically(target, failing); });
  CHECK_THAT(message, Contains("out.bin") && Contains("writer gave up"));
  CHECK(dir.entries().empty());  // ... and neither that nor the target remains

  orthofront::io::write_atomically(target, [](std::ofstream& out) { out << "complete"; });
  CHECK(dir.entries() == std::vector<std::string>{"out.bin"});
  target_expected = true;
  CHECK_THROWS_AS(orthofront::io::write_atomically(target, failing), IoError);
  CHECK(dir.entries() == std::vector<std::string>{"out.bin"});
  CHECK(read_text(target) == "complete");  // a failed rewrite keeps the previous file
}

TEST_CASE("AtomicFileSet replaces its files together or not at all", "[io][atomic]") {
  TempDir dir;
  const fs::path mesh = dir / "s.vtp";
  const fs::path report = dir / "s.json";
  const auto writes = [](const std::string& text) {
    return [text](std::ofstream& out) { out << text; };
  };
  {
    orthofront::io::AtomicFileSet files;
    files.add(mesh, writes("mesh 1"));
    files.add(report, writes("report 1"));
    CHECK_FALSE(fs::exists(mesh));  // nothing is replaced before commit
    CHECK(dir.entries().size() == 2);
    files.commit();
  }
  CHECK(dir.entries() == std::vector<std::string>{"s.json", "s.vtp"});
  CHECK(read_text(mesh) == "mesh 1");
  CHECK(read_text(report) == "report 1");
  {
    INFO("the second write fails: the first file is not replaced, no temporary is left");
    orthofront::io::AtomicFileSet files;
    files.add(mesh, writes("mesh 2"));
    const std::string message = thrown<IoError>([&] {
      files.add(report, [](std::ofstream& out) {
        out << "partial";
        throw std::runtime_error("report writer gave up");
      });
    });
    CHECK_THAT(message, Contains("s.json") && Contains("report writer gave up"));
    CHECK(dir.entries() == std::vector<std::string>{"s.json", "s.vtp"});
    files.commit();  // nothing left to commit
    CHECK(read_text(mesh) == "mesh 1");
    CHECK(read_text(report) == "report 1");
  }
  {
    INFO("a set destroyed before commit replaces nothing");
    orthofront::io::AtomicFileSet files;
    files.add(mesh, writes("mesh 3"));
  }
  CHECK(dir.entries() == std::vector<std::string>{"s.json", "s.vtp"});
  CHECK(read_text(mesh) == "mesh 1");
  {
    INFO("one file twice in a set is refused");
    orthofront::io::AtomicFileSet files;
    files.add(mesh, writes("mesh 4"));
    CHECK_THAT(thrown<IoError>([&] { files.add(dir.path() / "." / "s.vtp", writes("x")); }),
               Contains("s.vtp") && Contains("also written"));
    CHECK(dir.entries() == std::vector<std::string>{"s.json", "s.vtp"});
  }
}

namespace {

/// A python interpreter that can import VTK, or "" when there is none.
std::string python_with_vtk() {
  for (const std::string candidate : {"python3", "/usr/bin/python3"}) {
    const std::string command = candidate + " -c 'import vtk' > /dev/null 2>&1";
    if (std::system(command.c_str()) == 0) return candidate;
  }
  return {};
}

/// Reads a .vtp with VTK, reports what VTK saw, and writes VTK's own ascii and binary copies.
constexpr const char* kVtkScript = R"(import sys
import vtk

source, report, ascii_copy, binary32_copy, binary64_copy = sys.argv[1:6]
messages = vtk.vtkStringOutputWindow()
vtk.vtkOutputWindow.SetInstance(messages)
reader = vtk.vtkXMLPolyDataReader()
reader.SetFileName(source)
reader.Update()
mesh = reader.GetOutput()
sizes = [mesh.GetCell(i).GetNumberOfPoints() for i in range(mesh.GetNumberOfCells())]
data = mesh.GetPointData()
with open(report, "w") as out:
    out.write("points %d\n" % mesh.GetNumberOfPoints())
    out.write("polys %d\n" % mesh.GetNumberOfPolys())
    out.write("quads %d\n" % sizes.count(4))
    out.write("triangles %d\n" % sizes.count(3))
    out.write("arrays %s\n" % " ".join(data.GetArrayName(i) for i in range(data.GetNumberOfArrays())))
    out.write("point0 %r %r %r\n" % mesh.GetPoint(0))
    for i in range(data.GetNumberOfArrays()):
        out.write("value3 %s %r\n" % (data.GetArrayName(i), data.GetArray(i).GetTuple1(3)))
    out.write("message_chars %d\n" % len(messages.GetOutput()))
for name, ascii, header in ((ascii_copy, True, 64), (binary32_copy, False, 32), (binary64_copy, False, 64)):
    writer = vtk.vtkXMLPolyDataWriter()
    writer.SetFileName(name)
    writer.SetInputData(mesh)
    writer.SetCompressorTypeToNone()
    if ascii:
        writer.SetDataModeToAscii()
    else:
        writer.SetDataModeToBinary()
    if header == 32:
        writer.SetHeaderTypeToUInt32()
    else:
        writer.SetHeaderTypeToUInt64()
    writer.Write()
)";

/// Python's repr of a float is its shortest exact text, so this gives back the very bits.
double parse_double(const std::string& text) {
  double value = std::numeric_limits<double>::quiet_NaN();
  std::from_chars(text.data(), text.data() + text.size(), value);
  return value;
}

}  // namespace

TEST_CASE("VTK's own reader reads our .vtp and we read VTK's", "[io][mesh][vtp][vtk]") {
  const std::string python = python_with_vtk();
  if (python.empty()) {
    WARN(
        "SKIPPED: no python3 with the vtk module (Debian: python3-vtk9); the independent "
        "VTK reader check did not run");
    SUCCEED("skipped: python3 vtk module not available");
    return;
  }
  TempDir dir;
  const Mesh mesh = sample_mesh();
  write_mesh(mesh, dir / "ours.vtp");
  write_text(dir / "check.py", kVtkScript);
  const std::string command =
      python + " '" + (dir / "check.py").string() + "' '" + (dir / "ours.vtp").string() + "' '" +
      (dir / "report.txt").string() + "' '" + (dir / "vtk_ascii.vtp").string() + "' '" +
      (dir / "vtk_binary32.vtp").string() + "' '" + (dir / "vtk_binary64.vtp").string() + "' > '" +
      (dir / "python.log").string() + "' 2>&1";
  const int status = std::system(command.c_str());
  INFO("python output: " << read_text(dir / "python.log"));
  REQUIRE(status == 0);

  std::map<std::string, std::vector<std::string>> report;
  std::istringstream lines(read_text(dir / "report.txt"));
  for (std::string line; std::getline(lines, line);) {
    std::istringstream words(line);
    std::string key;
    words >> key;
    for (std::string word; words >> word;) report[key].push_back(word);
  }
  INFO("VTK reported: " << read_text(dir / "report.txt"));
  CHECK(report["message_chars"] == std::vector<std::string>{"0"});
  CHECK(report["points"] == std::vector<std::string>{"12"});
  CHECK(report["polys"] == std::vector<std::string>{"9"});
  CHECK(report["quads"] == std::vector<std::string>{"3"});
  CHECK(report["triangles"] == std::vector<std::string>{"6"});
  CHECK(report["arrays"] ==
        std::vector<std::string>{"time", "alpha", "s", "error", "front_id", "step"});
  REQUIRE(report["point0"].size() == 3);
  for (int c = 0; c < 3; ++c) {
    CHECK(same_bits(parse_double(report["point0"][c]), mesh.positions[0][c]));
  }
  const std::map<std::string, double> value3 = {
      {"time", mesh.time[3]},   {"alpha", mesh.alpha[3]},       {"s", mesh.s[3]},
      {"error", mesh.error[3]}, {"front_id", mesh.front_id[3]}, {"step", mesh.step[3]}};
  for (const auto& [name, expected] : value3) {
    const auto it = std::find(report["value3"].begin(), report["value3"].end(), name);
    REQUIRE(it + 1 < report["value3"].end());
    INFO(name << " = " << *(it + 1));
    CHECK(same_bits(parse_double(*(it + 1)), expected));
  }

  // VTK's binary copies carry the same bits; its ascii text is the shortest exact one, but
  // writes -0 as 0, so there values are compared, not bits.
  for (const std::string copy : {"vtk_binary32.vtp", "vtk_binary64.vtp", "vtk_ascii.vtp"}) {
    INFO("reading VTK's " << copy);
    const Mesh back = read_mesh(dir / copy);
    const bool bitwise = copy != "vtk_ascii.vtp";
    require_same_positions(back, mesh, bitwise);
    require_same_attributes(back, mesh, bitwise);
    CHECK(back.faces == mesh.faces);
  }
}

TEST_CASE("a write removes temporary files that killed writers left behind", "[io][atomic]") {
  TempDir dir;
  const fs::path out = dir.path() / "surface.vtp";
  // A process that has exited (reaped): its PID names no running process.
  const pid_t dead = ::fork();
  if (dead == 0) ::_exit(0);
  int status = 0;
  ::waitpid(dead, &status, 0);
  const fs::path stale = out.string() + ".tmp-" + std::to_string(dead);
  const fs::path live = out.string() + ".tmp-1";  // init runs: a writer still at work
  const fs::path other = dir.path() / "other.vtp.tmp-123456789";
  for (const fs::path& p : {stale, live, other}) std::ofstream(p) << "partial";
  orthofront::io::write_atomically(out, [](std::ofstream& o) { o << "complete"; });
  CHECK(fs::exists(out));
  CHECK_FALSE(fs::exists(stale));
  CHECK(fs::exists(live));
  CHECK(fs::exists(other));  // another file's temporaries are not ours to judge
}
