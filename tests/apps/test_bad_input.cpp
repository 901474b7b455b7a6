// Bad input on the command line, one case per row of docs/bad-input.md: the message names the
// file or value at fault, the exit status is 2 (docs/user-guide.md, exit status; 3 is for
// internal errors), and what is left on disk is checked (no output file, a partial mesh marked
// incomplete, or a temporary that the next run removes).
#include <hdf5.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <thread>

#include "apps/cli_run.h"
#include "io/grid_test_support.h"
#include "orthofront/io/hdf5_layout.h"
#include "orthofront/io/mesh_io.h"
#include "orthofront/io/vdb_grid.h"

using Catch::Matchers::Contains;
using cli_test::quoted;
using cli_test::Run;
using orthofront::VectorGrid;
using namespace grid_test;

namespace {

std::string lower(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return text;
}

/// `orthofront ARGS` with stdin closed (no terminal: no progress bar).
Run run(const std::string& args) {
  return cli_test::run(args + " < /dev/null");
}

nlohmann::json read_json(const fs::path& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

/// A uniform 6 x 6 x 6 grid over [0, 5]^3 of a steady flow along +y that turns slowly.
VectorGrid flow_grid() {
  VectorGrid grid;
  grid.geometry.dimension = 3;
  grid.geometry.size = {6, 6, 6};
  for (std::int64_t k = 0; k < 6; ++k) {
    for (std::int64_t j = 0; j < 6; ++j) {
      for (std::int64_t i = 0; i < 6; ++i) {
        grid.values.push_back(0.05f * static_cast<float>(k));
        grid.values.push_back(1.0f);
        grid.values.push_back(0.0f);
      }
    }
  }
  return grid;
}

std::string sizes(const VectorGrid& g, const char* separator) {
  const auto& n = g.geometry.size;
  return std::to_string(n[0]) + separator + std::to_string(n[1]) + separator + std::to_string(n[2]);
}

// Writers of every grid format the readers take, origin 0, spacing 1. `claimed` replaces the
// sizes written in the header (wrong dimensions); empty: the grid's own.

void write_vec(const fs::path& path, const VectorGrid& g, const std::string& claimed = {}) {
  std::string bytes;
  std::array<std::int32_t, 3> n{};
  for (int a = 0; a < 3; ++a) n[a] = static_cast<std::int32_t>(g.geometry.size[a]);
  if (!claimed.empty()) n[2] = std::stoi(claimed);  // claimed: nz
  for (const auto v : n) put(bytes, v, true);
  write_file(path, bytes + float_bytes(g.values, true));
}

void write_am(const fs::path& path, const VectorGrid& g, const std::string& claimed = {}) {
  const auto& n = g.geometry.size;
  const std::string lattice = claimed.empty() ? sizes(g, " ") : claimed;
  write_file(path, "# AmiraMesh BINARY-LITTLE-ENDIAN 2.1\n\ndefine Lattice " + lattice +
                       "\n\nParameters {\n    BoundingBox 0 " + std::to_string(n[0] - 1) + " 0 " +
                       std::to_string(n[1] - 1) + " 0 " + std::to_string(n[2] - 1) +
                       ",\n    CoordType \"uniform\"\n}\n\nLattice { float[3] Velocity } @1\n\n"
                       "# Data section follows\n@1\n" +
                       float_bytes(g.values, true) + "\n");
}

std::string nrrd_header(const VectorGrid& g, const std::string& claimed) {
  return "NRRD0004\ntype: float\ndimension: 4\nspace dimension: 3\nsizes: 3 " +
         (claimed.empty() ? sizes(g, " ") : claimed) +
         "\nspace directions: none (1,0,0) (0,1,0) (0,0,1)\nkinds: 3-vector space space space\n"
         "space origin: (0,0,0)\nendian: little\nencoding: raw\n";
}

void write_nrrd(const fs::path& path, const VectorGrid& g, const std::string& claimed = {}) {
  write_file(path, nrrd_header(g, claimed) + "\n" + float_bytes(g.values, true));
}

/// A detached header: the data lie in "<path>.raw".
void write_nhdr(const fs::path& path, const VectorGrid& g, const std::string& claimed = {}) {
  write_file(path, nrrd_header(g, claimed) + "data file: " + path.filename().string() + ".raw\n");
  write_file(path.string() + ".raw", float_bytes(g.values, true));
}

void write_vti(const fs::path& path, const VectorGrid& g, const std::string& claimed = {}) {
  const auto& n = g.geometry.size;
  const std::string extent = claimed.empty()
                                 ? "0 " + std::to_string(n[0] - 1) + " 0 " +
                                       std::to_string(n[1] - 1) + " 0 " + std::to_string(n[2] - 1)
                                 : claimed;
  const std::string data = float_bytes(g.values, true);
  std::string size;
  put(size, static_cast<std::uint32_t>(data.size()), true);
  write_file(path,
             "<?xml version=\"1.0\"?>\n<VTKFile type=\"ImageData\" version=\"1.0\" "
             "byte_order=\"LittleEndian\" header_type=\"UInt32\">\n  <ImageData WholeExtent=\"" +
                 extent + "\" Origin=\"0 0 0\" Spacing=\"1 1 1\">\n    <Piece Extent=\"" + extent +
                 "\">\n      <PointData Vectors=\"velocity\">\n        <DataArray "
                 "type=\"Float32\" Name=\"velocity\" NumberOfComponents=\"3\" "
                 "format=\"appended\" offset=\"0\"/>\n      </PointData>\n    </Piece>\n  "
                 "</ImageData>\n  <AppendedData encoding=\"raw\">\n   _" +
                 size + data + "\n  </AppendedData>\n</VTKFile>\n");
}

void write_vtk(const fs::path& path, const VectorGrid& g, const std::string& claimed = {}) {
  write_file(path,
             "# vtk DataFile Version 3.0\nbad-input test\nBINARY\nDATASET STRUCTURED_POINTS\n"
             "DIMENSIONS " +
                 (claimed.empty() ? sizes(g, " ") : claimed) +
                 "\nSPACING 1 1 1\nORIGIN 0 0 0\nPOINT_DATA " +
                 std::to_string(g.geometry.point_count()) + "\nVECTORS velocity float\n" +
                 float_bytes(g.values, false) + "\n");
}

void write_vdb(const fs::path& path, const VectorGrid& g, const std::string& = {}) {
  orthofront::io::write_vdb(g, path);
}

void write_h5(const fs::path& path, const VectorGrid& g, const std::string& = {}) {
  orthofront::io::Hdf5WriteOptions o;
  o.xdmf = false;
  orthofront::io::write_hdf5_grid(g, path, o);
}

struct Format {
  const char* extension;
  std::function<void(const fs::path&, const VectorGrid&, const std::string&)> write;
  /// Key words of the message for an empty file and for a truncated one (lower case).
  const char* empty_words;
  const char* truncated_words;
};

const std::vector<Format>& formats() {
  static const std::vector<Format> all{
      {".vec", write_vec, "truncated", "truncated"},
      {".am", write_am, "not an amiramesh file", "truncated"},
      {".nrrd", write_nrrd, "not a nrrd file", "truncated"},
      {".nhdr", write_nhdr, "not a nrrd file", "truncated"},
      {".vti", write_vti, "not a vtk xml file", "truncated"},
      {".vtk", write_vtk, "truncated", "truncated"},
      {".vdb", write_vdb, "not a readable openvdb file", "not a readable openvdb file"},
      {".h5", write_h5, "not an hdf5 file", "truncated: the file has"},
  };
  return all;
}

/// The file that holds the samples (the .raw of a detached NRRD header).
fs::path data_file_of(const fs::path& path) {
  return path.extension() == ".nhdr" ? fs::path(path.string() + ".raw") : path;
}

void truncate_to(const fs::path& path, double share) {
  fs::resize_file(path,
                  static_cast<std::uintmax_t>(static_cast<double>(fs::file_size(path)) * share));
}

/// A tmpfs mounted at `at` for the scope (needs root); `mounted` says whether mount succeeded.
struct Tmpfs {
  Tmpfs(const fs::path& where, const std::string& options) : at(where) {
    mounted =
        std::system(
            ("mount -t tmpfs -o " + options + " tmpfs " + quoted(at) + " 2>/dev/null").c_str()) ==
        0;
  }
  ~Tmpfs() {
    if (mounted && std::system(("umount " + quoted(at)).c_str()) != 0)
      WARN("could not unmount " << at);
  }
  Tmpfs(const Tmpfs&) = delete;
  Tmpfs& operator=(const Tmpfs&) = delete;
  fs::path at;
  bool mounted = false;
};

const std::string kSeed = " --seed line:1,1,2.5:4,1,2.5 --seed-count 8 --edge 0.5 --steps 4";

/// `stream` on `field`, writing into the empty folder `out`.
Run stream_into(const fs::path& field, const fs::path& out) {
  return run("stream --field " + quoted(field) + kSeed + " --out " + quoted(out / "s.vtp") +
             " --report " + quoted(out / "s.json"));
}

/// The words a truncated OpenVDB file's refusal has. OpenVDB's Blosc reader sizes a buffer from a
/// length the truncated stream never set (stack garbage): in a sanitizer build the child then
/// stops at allocation-size-too-big (exit 1, "the reader failed") when that garbage is huge; in a
/// release build the reader throws, or meets the child's memory cap when the garbage is large
/// ("needs more than N MiB of memory"). All are refusals; which one depends on the stack (what
/// the binary links changes it).
std::string truncated_vdb_words(const std::string& output, const std::string& words) {
#ifdef __SANITIZE_ADDRESS__
  if (lower(output).find("the reader failed (exit status 1)") != std::string::npos)
    return "the reader failed";
#endif
  if (lower(output).find("corrupt or unreadable openvdb file: reading it needs more than") !=
      std::string::npos)
    return "sizes in the file that its length cannot hold";
  return words;
}

/// Empties `out` for the next case: whatever the last run wrote there.
void clear(const TempDir& out) {
  for (const std::string& name : out.entries()) fs::remove_all(out / name);
}

/// Checks the refusal of a case: exit status 2, the message names `file` and has `words`, and
/// `out` stays empty.
void check_refused(const Run& r, const std::string& file, const std::string& words,
                   const TempDir& out) {
  INFO(r.output);
  CHECK(r.status == 2);
  CHECK_THAT(r.output, Contains("orthofront: error:"));
  CHECK_THAT(r.output, Contains(file));
  CHECK_THAT(lower(r.output), Contains(words));
  CHECK(out.entries().empty());
  clear(out);
}

// The output and report options of a run writing into out.
std::string outputs_in(const TempDir& out) {
  return " --out " + quoted(out / "s.vtp") + " --report " + quoted(out / "s.json");
}

}  // namespace

TEST_CASE("bad input: missing, empty and truncated grid files of every format",
          "[apps][bad-input]") {
  TempDir dir("bad-input-files");
  TempDir out("bad-input-out");
  const VectorGrid grid = flow_grid();
  for (const Format& f : formats()) {
    const std::string ext = f.extension;
    INFO("format " << ext);
    // The intact file works: the refusals below are about the damage, not the writer.
    const fs::path good = dir / ("good" + ext);
    f.write(good, grid, {});
    const Run ok = stream_into(good, out.path());
    INFO(ok.output);
    REQUIRE(ok.status == 0);
    REQUIRE(orthofront::io::read_mesh(out / "s.vtp").face_count() > 0);
    clear(out);

    {
      INFO("missing");
      check_refused(stream_into(dir / ("missing" + ext), out.path()), "missing" + ext,
                    "no such file", out);
    }
    {
      INFO("empty");
      write_file(dir / ("empty" + ext), "");
      check_refused(stream_into(dir / ("empty" + ext), out.path()), "empty" + ext, f.empty_words,
                    out);
    }
    {
      INFO("truncated to 60%");
      const fs::path cut = dir / ("cut" + ext);
      f.write(cut, grid, {});
      truncate_to(data_file_of(cut), 0.6);
      const Run r = stream_into(cut, out.path());
      check_refused(r, data_file_of(cut).filename().string(),
                    ext == ".vdb" ? truncated_vdb_words(r.output, f.truncated_words)
                                  : std::string(f.truncated_words),
                    out);
    }
  }
  // A detached NRRD header whose data file is gone.
  write_nhdr(dir / "orphan.nhdr", grid);
  fs::remove(dir / "orphan.nhdr.raw");
  check_refused(stream_into(dir / "orphan.nhdr", out.path()), "orphan.nhdr.raw", "no such file",
                out);
}

TEST_CASE("bad input: missing, empty and truncated time series for `path`", "[apps][bad-input]") {
  TempDir dir("bad-input-series");
  TempDir out("bad-input-out");
  const auto path_into = [&](const fs::path& field) {
    return run("path --field " + quoted(field) +
               " --seed line:0.3,0.25,0:0.9,0.7,0 --seed-count 8 --t1 2 --edge 0.05 --out " +
               quoted(out / "p.vtp") + " --report " + quoted(out / "p.json"));
  };
  const Run g = run("generate --field double-gyre --resolution 41,21 --steps 21 --t1 2 --out " +
                    quoted(dir / "gyre.h5"));
  INFO(g.output);
  REQUIRE(g.status == 0);
  const Run c = run("convert " + quoted(dir / "gyre.h5") + " --out " + quoted(dir / "gyre.vdb"));
  INFO(c.output);
  REQUIRE(c.status == 0);
  for (const char* ext : {".h5", ".vdb"}) {
    INFO("format " << ext);
    const Run ok = path_into(dir / (std::string("gyre") + ext));
    INFO(ok.output);
    REQUIRE(ok.status == 0);
    clear(out);
    {
      INFO("missing");
      const Run r = path_into(dir / (std::string("missing") + ext));
      check_refused(r, std::string("missing") + ext, "neither an unsteady field name", out);
    }
    {
      INFO("empty");
      write_file(dir / (std::string("empty") + ext), "");
      const Run r = path_into(dir / (std::string("empty") + ext));
      const bool h5 = ext == std::string(".h5");
      check_refused(r, std::string("empty") + ext,
                    h5 ? "this file is none of them" : "not a readable openvdb file", out);
    }
    {
      INFO("truncated to 60%");
      const fs::path cut = dir / (std::string("cut") + ext);
      fs::copy_file(dir / (std::string("gyre") + ext), cut);
      truncate_to(cut, 0.6);
      const Run r = path_into(cut);
      check_refused(r, std::string("cut") + ext,
                    ext == std::string(".h5")
                        ? std::string("truncated: the file has")
                        : truncated_vdb_words(r.output, "not a readable openvdb file"),
                    out);
    }
  }
}

TEST_CASE("bad input: command-line syntax errors exit 2 naming the option", "[apps][bad-input]") {
  struct Case {
    const char* args;
    const char* words;
  };
  const Case cases[] = {
      {"stream --field saddle --seed line:0,0,0:1,1,0 --edge abc", "--edge"},
      {"stream --field saddle", "--seed"},
      {"stream --field saddle --seed line:0,0,0:1,1,0 --out s.vtp --no-such-option",
       "--no-such-option"},
      {"path --field double-gyre --seed line:0.1,0.5,0:0.6,0.5,0 --cache-unit foo", "--cache-unit"},
      {"no-such-command", "subcommand"},
  };
  for (const Case& c : cases) {
    const Run r = run(c.args);
    INFO(c.args << "\n" << r.output);
    CHECK(r.status == 2);
    CHECK_THAT(r.output, Contains("orthofront: error:"));
    CHECK_THAT(r.output, Contains(c.words));
    CHECK_THAT(r.output, Contains("--help"));
  }
  // Help and version still succeed.
  CHECK(run("--version").status == 0);
  CHECK(run("stream --help").status == 0);
}

TEST_CASE("bad input: corrupt HDF5 and OpenVDB files that crash or hang or flood their libraries",
          "[apps][bad-input]") {
  // Inputs found by fuzzing (fuzz/regressions): each made libhdf5 or libopenvdb overflow a buffer,
  // abort, loop or allocate gigabytes in this process. Now the first read runs in a child.
  struct Case {
    const char* file;
    const char* ext;
    const char* info_words;    // what `info` says
    const char* stream_words;  // what `stream --field` says
  };
  const Case cases[] = {
      // H5Dread copied past a buffer: the dataset claims more bytes than the file holds.
      {"hdf5/crash-caa26d86077d0807e03da9a4293dbe666c965f37", ".h5", "bytes of samples in a file",
       "bytes of samples in a file"},
      // H5Aexists overflowed reading a damaged attribute message.
      // (In a sanitizer build the child stops at the overflow: "the reader failed".)
      {"hdf5/crash-288fca76bd7d53fddabc8556c1614b507ab3c313", ".h5", "", ""},
      // Whether OpenVDB crashes on this one or throws first depends on its heap's layout (the
      // file's path length, the libraries loaded): contained either way.
      {"vdb_file/crash-ff1de5cd7d629500057d850528d7abdb5ae2e9f3", ".vdb",
       "crashed|not a readable openvdb file", "crashed|not a readable openvdb file"},
      {"vdb_file/crash-e3a67af30de8a21fd049cd0801885394e5008e4d", ".vdb", "did not finish",
       "did not finish"},
      // Two voxels 10^4 apart: a dense copy (info) would need 124 GB; sampled sparsely (stream),
      // the seed finds no data.
      {"grid_vdb/crash-e424375d92825105a624e054ddf92bc7e418e75f", ".vdb", "dense copy",
       "has no data"},
  };
  const fs::path regressions = fs::path(ORTHOFRONT_SOURCE_DIR) / "fuzz" / "regressions";
  TempDir dir("corrupt");
  TempDir out("corrupt-out");
  for (const Case& c : cases) {
    const fs::path file = dir / (std::string("bad") + c.ext);
    fs::copy_file(regressions / c.file, file, fs::copy_options::overwrite_existing);
    // The looping file: 2 s, not 10. The others keep the default limit: under a sanitizer on a
    // loaded machine, reading the sparse one above can take more than 2 s of CPU time.
    if (std::string(c.stream_words) == "did not finish")
      ::setenv("ORTHOFRONT_READ_TIMEOUT", "2", 1);
    else
      ::unsetenv("ORTHOFRONT_READ_TIMEOUT");
    const std::pair<std::string, const char*> commands[] = {
        {"info '" + file.string() + "'", c.info_words},
        {"stream --field '" + file.string() + "' --seed line:1,1,1:2,2,1 --out '" +
             (out / "s.vtp").string() + "'",
         c.stream_words}};
    for (const auto& [command, words] : commands) {
      const Run r = run(command);
      INFO(c.file << ": " << command << "\n" << r.output);
      CHECK(r.status == 2);
      CHECK_THAT(r.output, Contains("orthofront: error:"));
      CHECK_THAT(r.output, Contains(file.string()));
      std::string expected = words;
#ifdef __SANITIZE_ADDRESS__
      // In a sanitizer build the child's sanitizer stops it at the first bad access, before any
      // crash, loop or flood: it exits 1 and the message says the reader failed.
      if (expected.starts_with("crashed") || expected == "did not finish") expected = "reader";
#endif
      // (Alternatives are separated by '|'.)
      bool said = false;
      for (std::size_t from = 0; !said && from <= expected.size();) {
        const std::size_t bar = std::min(expected.find('|', from), expected.size());
        said = lower(r.output).find(expected.substr(from, bar - from)) != std::string::npos;
        from = bar + 1;
      }
      CHECK(said);
      CHECK(out.entries().empty());
    }
  }
}

TEST_CASE("bad input: header dimensions that do not match the data", "[apps][bad-input]") {
  TempDir dir("bad-input-dims");
  TempDir out("bad-input-out");
  const VectorGrid grid = flow_grid();  // 6 x 6 x 6 points
  struct Case {
    const char* file;
    std::function<void(const fs::path&, const VectorGrid&, const std::string&)> write;
    std::string claimed;  // what the header says instead
    const char* words;    // key words of the message (lower case)
  };
  const Case cases[] = {
      {"dims.vec", write_vec, "5", "6 x 6 x 5"},
      {"dims.am", write_am, "6 6 5", "do the type and sizes in the header match the data"},
      // NRRD: a header claiming more than the data ...
      {"dims.nrrd", write_nrrd, "6 6 7", "sizes 3 6 6 7 of float need 3024"},
      {"dims.nhdr", write_nhdr, "6 6 7", "sizes 3 6 6 7 of float need 3024"},
      // ... and one claiming fewer (raw data without skips must be the samples alone).
      {"fewer.nrrd", write_nrrd, "6 6 5",
       "holds 2592 data bytes but sizes 3 6 6 5 of float need 2160"},
      {"fewer.nhdr", write_nhdr, "6 6 5", "fewer.nhdr.raw holds 2592 data bytes but sizes 3 6 6 5"},
      {"dims.vti", write_vti, "0 5 0 5 0 4", "the extent needs 540"},
      {"dims.vtk", write_vtk, "6 6 5", "point_data 216 does not match dimensions 6 x 6 x 5"},
  };
  for (const Case& c : cases) {
    INFO(c.file);
    c.write(dir / c.file, grid, c.claimed);
    check_refused(stream_into(dir / c.file, out.path()), c.file, c.words, out);
  }
  // HDF5: the 'dimension' attribute says 2D over 3D data.
  write_h5(dir / "dims.h5", grid);
  {
    const hid_t f = H5Fopen((dir / "dims.h5").c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    REQUIRE(f >= 0);
    REQUIRE(H5Adelete(f, "dimension") >= 0);
    const hid_t space = H5Screate(H5S_SCALAR);
    const hid_t a = H5Acreate2(f, "dimension", H5T_NATIVE_INT, space, H5P_DEFAULT, H5P_DEFAULT);
    const int two = 2;
    REQUIRE(H5Awrite(a, H5T_NATIVE_INT, &two) >= 0);
    H5Aclose(a);
    H5Sclose(space);
    H5Fclose(f);
  }
  check_refused(stream_into(dir / "dims.h5", out.path()), "dims.h5", "attribute 'dimension' is 2",
                out);
}

namespace {

/// 11 x 11 x 11 points over [0, 10]^3, flow (0, 1, 0.05 x), no data (NaN) where y >= 6.
VectorGrid nan_grid() {
  VectorGrid grid;
  grid.geometry.dimension = 3;
  grid.geometry.size = {11, 11, 11};
  for (std::int64_t k = 0; k < 11; ++k) {
    for (std::int64_t j = 0; j < 11; ++j) {
      for (std::int64_t i = 0; i < 11; ++i) {
        const bool hole = j >= 6;
        grid.values.push_back(hole ? NAN : 0.0f);
        grid.values.push_back(hole ? NAN : 1.0f);
        grid.values.push_back(hole ? NAN : 0.05f * static_cast<float>(i));
      }
    }
  }
  return grid;
}

}  // namespace

TEST_CASE("bad input: NaN regions and fill values are no data", "[apps][bad-input]") {
  TempDir dir("bad-input-nan");
  TempDir out("bad-input-out");
  const VectorGrid grid = nan_grid();
  write_vec(dir / "nan.vec", grid);  // NaN stored as NaN
  orthofront::io::Hdf5WriteOptions o;
  o.fill_value = -9999.0f;  // NaN stored as -9999, with the attribute fill_value
  o.xdmf = false;
  orthofront::io::write_hdf5_grid(grid, dir / "fill.h5", o);
  for (const char* file : {"nan.vec", "fill.h5"}) {
    INFO(file);
    const std::string field = " --field " + quoted(dir / file);
    const std::string outputs = outputs_in(out);
    {
      INFO("a seed wholly in the region without data is refused");
      const Run r = run("stream" + field + " --seed line:1,8,5:9,8,5" + outputs);
      check_refused(r, "line:1,8,5:9,8,5", "has no data", out);
      CHECK_THAT(r.output, Contains(file) && Contains("(1, 8, 5)"));
      CHECK_THAT(r.output, !Contains("outside"));
    }
    for (const char* seed : {"line:1,1,5:9,1,5", "line:1,2,5:9,9,5"}) {
      // Flowing into the region, and a seed half in it: the surface is built where there is
      // data and stops at the region.
      INFO("seed " << seed);
      const Run r = run("stream" + field + " --seed " + seed + " --edge 0.5 --steps 200" + outputs);
      INFO(r.output);
      CHECK(r.status == 0);
      const orthofront::Mesh mesh = orthofront::io::read_mesh(out / "s.vtp");
      CHECK(mesh.face_count() > 20);
      double y_max = 0;
      for (const auto& p : mesh.positions) {
        REQUIRE(p.allFinite());
        y_max = std::max(y_max, p.y());
      }
      CHECK(y_max <= 5.0);  // nothing in the cells that touch the region without data (y > 5)
      CHECK(y_max > 4.0);   // the surface reaches it
      const auto report = read_json(out / "s.json");
      CHECK(report["counts"]["no_data_hits"].get<std::size_t>() > 0);
      CHECK(report["complete"] == true);
      clear(out);
    }
  }
}

TEST_CASE("bad input: seeds outside, half outside, of zero length, in still flow",
          "[apps][bad-input]") {
  TempDir out("bad-input-out");
  const std::string outputs = " --out " + quoted(out / "s.vtp");
  const std::string stream = "stream --field saddle3d --steps 20 --seed ";
  const std::string path = "path --field double-gyre --t1 1 --edge 0.05 --seed ";
  struct Refused {
    std::string args;
    std::string named;  // the value, as the message names it
    std::string words;  // key words (lower case)
  };
  const Refused refused[] = {
      {stream + "line:50,50,50:60,60,60", "line:50,50,50:60,60,60",
       "lies outside the domain of field 'saddle3d'"},
      {stream + "line:3.99,2,0.1:8,2,0.1", "line:3.99,2,0.1:8,2,0.1",
       "1 of 20 seed vertices inside, at least 2 needed"},
      {path + "line:5,5,0:6,6,0", "line:5,5,0:6,6,0",
       "lies outside the domain of field 'double-gyre' at t0 = 0 (0 of 20 seed vertices inside, "
       "at least 2 needed; e.g. the point (5, 5) is outside the domain [0, 2] x [0, 1]"},
      {path + "line:1.99,0.5,0:3,0.5,0", "line:1.99,0.5,0:3,0.5,0",
       "1 of 20 seed vertices inside, at least 2 needed"},
      {stream + "line:1,1,1:1,1,1", "line:1,1,1:1,1,1", "the two ends coincide"},
      {path + "line:1,0.5,0:1,0.5,0", "line:1,0.5,0:1,0.5,0", "the two ends coincide"},
      {stream + "circle:1,1,1:0,0,1:0", "circle:1,1,1:0,0,1:0", "radius 0 is not positive"},
      {"stream --field repelling-node-saddle:l1=0,l2=0,l3=0 --seed line:0,1,0:1,1,0",
       "line:0,1,0:1,1,0", "has zero velocity at every vertex"},
      {stream + "line:-1,2,0.1:1,2,0.1 --seed-count 0", "--seed-count", "at least 2, got 0"},
      {path + "line:0.3,0.25,0:0.9,0.7,0 --seed-count 1", "--seed-count", "at least 2, got 1"},
  };
  for (const Refused& c : refused) {
    INFO(c.args);
    check_refused(run(c.args + outputs), c.named, c.words, out);
  }
  // Half outside: the surface grows from the part inside (stream and path).
  for (const std::string& args : {stream + "line:0,2,0.1:8,2,0.1", path + "line:1,0.5,0:3,0.5,0"}) {
    INFO(args);
    const Run r = run(args + outputs);
    INFO(r.output);
    CHECK(r.status == 0);
    const orthofront::Mesh mesh = orthofront::io::read_mesh(out / "s.vtp");
    CHECK(mesh.face_count() > 10);
    for (const auto& p : mesh.positions) CHECK(p.x() <= (args[0] == 's' ? 4.0 : 2.0) + 1e-9);
    clear(out);
  }
  // A path surface in still flow is the seed curve carried through time: a valid surface.
  const Run still =
      run("path --field double-gyre:A=0 --seed line:0.2,0.5,0:0.8,0.5,0 --t1 1"
          " --spacetime-out" +
          outputs);
  INFO(still.output);
  CHECK(still.status == 0);
  const orthofront::Mesh mesh = orthofront::io::read_mesh(out / "s.vtp");
  CHECK(mesh.face_count() > 10);
  for (const auto& p : mesh.positions) CHECK(p.y() == Approx(0.5).margin(1e-12));
}

TEST_CASE("bad input: options that exclude each other", "[apps][bad-input]") {
  TempDir out("bad-input-out");
  const std::string outputs = outputs_in(out);
  // 2D path positions are written pressed flat or in space-time, not both.
  check_refused(run("path --field double-gyre --seed line:0.3,0.25,0:0.9,0.7,0 --flat "
                    "--spacetime-out" +
                    outputs),
                "--flat and --spacetime-out", "exclude each other", out);
}

TEST_CASE("bad input: vertex budgets too small", "[apps][bad-input]") {
  TempDir out("bad-input-out");
  const std::string outputs = outputs_in(out);
  // Refused up front: the seed alone exceeds the budget.
  check_refused(run("stream --field saddle3d --seed line:-1,2,0.1:1,2,0.1 --seed-count 50 "
                    "--max-vertices 10" +
                    outputs),
                "--seed-count 50", "exceeds the vertex budget of 10", out);
  check_refused(run("path --field double-gyre --seed line:0.3,0.25,0:0.9,0.7,0 --seed-count 50 "
                    "--max-vertices 10" +
                    outputs),
                "--seed-count 50", "exceeds the vertex budget of 10", out);
  {
    // Reached by a path surface before t1: the surface so far, marked incomplete, and status 2.
    const Run r =
        run("path --field double-gyre --seed line:0.3,0.25,0:0.9,0.7,0 --t1 4 "
            "--edge 0.05 --max-vertices 300" +
            outputs);
    INFO(r.output);
    CHECK(r.status == 2);
    CHECK_THAT(r.output, Contains("orthofront: error: stopped at t = ") &&
                             Contains("--max-vertices") && Contains("marked incomplete"));
    const orthofront::Mesh mesh = orthofront::io::read_mesh(out / "s.vtp");
    CHECK(mesh.face_count() > 100);
    const auto report = read_json(out / "s.json");
    CHECK(report["complete"] == false);
    CHECK(report["stop_reason"] == "vertex_budget");
  }
}

TEST_CASE("bad input: output folders that cannot be written", "[apps][bad-input]") {
  TempDir dir("bad-input-unwritable");
  const std::string stream = "stream --field saddle3d --seed line:-1,2,0.1:1,2,0.1 --steps 5";
  const std::string path = "path --field double-gyre --seed line:0.3,0.25,0:0.9,0.7,0 --t1 1";
  const auto nothing_written = [&] {
    for (const auto& entry : fs::recursive_directory_iterator(dir.path()))
      if (entry.is_regular_file() && entry.path().filename() != "plain") return false;
    return true;
  };
  struct Case {
    std::string args;
    std::string named;
    std::string words;
  };
  fs::create_directories(dir / "folder.vtp");
  write_file(dir / "plain", "a file, not a folder");
  const Case cases[] = {
      {stream + " --out /nonexistent/dir/s.vtp", "/nonexistent/dir", "does not exist"},
      {path + " --out /nonexistent/dir/s.vtp", "/nonexistent/dir", "does not exist"},
      {stream + " --out " + quoted(dir / "folder.vtp"), "folder.vtp", "it is a directory"},
      {stream + " --out " + quoted(dir / "plain" / "s.vtp"), "plain", "is not a directory"},
      // The report's folder is checked before the surface is built: no mesh without its report.
      {stream + " --out " + quoted(dir / "s.vtp") + " --report /nonexistent/dir/s.json",
       "/nonexistent/dir/s.json", "does not exist"},
      {path + " --out " + quoted(dir / "s.vtp") + " --report /nonexistent/dir/s.json",
       "/nonexistent/dir/s.json", "does not exist"},
  };
  for (const Case& c : cases) {
    const Run r = run(c.args);
    INFO(c.args << "\n" << r.output);
    CHECK(r.status == 2);
    CHECK_THAT(r.output, Contains("orthofront: error: cannot write") && Contains(c.named));
    CHECK_THAT(lower(r.output), Contains(c.words));
    CHECK(nothing_written());
  }

  // A read-only folder: permissions for a user; root ignores them, so as root a read-only tmpfs.
  const fs::path locked = dir / "locked";
  fs::create_directories(locked);
  std::unique_ptr<Tmpfs> read_only;
  if (::geteuid() == 0) {
    read_only = std::make_unique<Tmpfs>(locked, "ro,size=64k");
    if (!read_only->mounted) {
      WARN("SKIPPED: the read-only folder case needs a read-only tmpfs as root (mount refused)");
      return;
    }
  } else {
    fs::permissions(locked, fs::perms::owner_read | fs::perms::owner_exec);
  }
  for (const std::string& command : {stream, path}) {
    const Run r = run(command + " --out " + quoted(locked / "s.vtp"));
    INFO(command << "\n" << r.output);
    CHECK(r.status == 2);
    CHECK_THAT(r.output, Contains("cannot write " + (locked / "s.vtp").string()) &&
                             Contains("is not writable"));
    CHECK(fs::is_empty(locked));
  }
  read_only.reset();
  fs::permissions(locked, fs::perms::owner_all);
}

TEST_CASE("bad input: a full disk leaves no temporary, and no mesh or report cut short",
          "[apps][bad-input][diskfull]") {
  TempDir dir("bad-input-diskfull");
  const fs::path small = dir / "small";
  fs::create_directories(small);
  const auto entries = [&] {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(small))
      names.push_back(e.path().filename().string());
    return names;
  };
  {
    // The mesh itself does not fit in 64 KiB.
    const Tmpfs disk(small, "size=64k");
    if (!disk.mounted) {
      // Needs root (CAP_SYS_ADMIN) for the small tmpfs: said and skipped otherwise.
      WARN("SKIPPED: cannot mount a small tmpfs here (needs root): disk-full cases not run");
      return;
    }
    const Run r =
        run("stream --field saddle3d --seed line:-1,2,0.1:1,2,0.1 --seed-count 40 "
            "--steps 200 --out " +
            quoted(small / "s.vtp") + " --report " + quoted(small / "s.json"));
    INFO(r.output);
    CHECK(r.status == 2);
    CHECK_THAT(r.output, Contains("cannot write " + (small / "s.vtp").string()) &&
                             Contains("No space left on device"));
    CHECK(entries().empty());
  }
  {
    // The mesh fits, its report does not: sizes measured on a roomy disk first. The two are
    // replaced as a pair: neither is, and the message gives the cause. Once with no earlier
    // outputs, once over an earlier mesh and report of the same names.
    const std::string args =
        "stream --field saddle3d --seed line:-1,2,0.1:1,2,0.1 --seed-count 4 "
        "--steps 3 --out ";
    const Run roomy = run(args + quoted(dir / "s.ply") + " --report " + quoted(dir / "s.json"));
    REQUIRE(roomy.status == 0);
    const std::uintmax_t page = 4096;
    const std::uintmax_t mesh_pages = (fs::file_size(dir / "s.ply") + page - 1) / page;
    REQUIRE(fs::file_size(dir / "s.json") > page);  // the report needs more than the page left
    for (const bool earlier : {false, true}) {
      INFO((earlier ? "over an earlier mesh and report" : "no earlier outputs"));
      // One page each for the earlier mesh and report, the new mesh, one page to spare.
      const Tmpfs disk(small, "size=" + std::to_string((mesh_pages + (earlier ? 3 : 1)) * page));
      REQUIRE(disk.mounted);
      if (earlier) {
        std::ofstream(small / "s.ply") << "earlier mesh";
        std::ofstream(small / "s.json") << "earlier report";
      }
      const Run r = run(args + quoted(small / "s.ply") + " --report " + quoted(small / "s.json"));
      INFO(r.output);
      CHECK(r.status == 2);
      CHECK_THAT(r.output, Contains("cannot write " + (small / "s.json").string()) &&
                               Contains("No space left on device") && Contains("bytes free in"));
      CHECK_THAT(r.output, !Contains("stream error"));
      if (earlier) {
        CHECK(entries().size() == 2);
        CHECK(read_file(small / "s.ply") == "earlier mesh");
        CHECK(read_file(small / "s.json") == "earlier report");
      } else {
        CHECK(entries().empty());  // no mesh, no report, no temporary
      }
      for (const std::string& name : entries()) CHECK(name.find(".tmp-") == std::string::npos);
    }
  }
}

namespace {

/// The Lorenz band to 10^6 steps: runs far longer than any test waits.
std::vector<std::string> long_stream(const TempDir& dir,
                                     const std::vector<std::string>& extra = {}) {
  std::vector<std::string> args{"stream",
                                "--field",
                                "lorenz:reverse=1",
                                "--seed",
                                "circle:0,0,0:1.283,1,0:1",
                                "--seed-count",
                                "10",
                                "--edge",
                                "0.5",
                                "--steps",
                                "1000000",
                                "--max-vertices",
                                "100000000",
                                "--out",
                                (dir / "s.vtp").string(),
                                "--report",
                                (dir / "s.json").string()};
  args.insert(args.end(), extra.begin(), extra.end());
  return args;
}

}  // namespace

TEST_CASE("bad input: SIGKILL leaves no finished-looking file, and a rerun removes its temporary",
          "[apps][bad-input][signals]") {
  TempDir dir("bad-input-sigkill");
  TempDir logs("bad-input-log");
  {
    INFO("killed while building: nothing is written");
    const pid_t pid = cli_test::start(long_stream(dir), (logs / "log.txt").string());
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
    ::kill(pid, SIGKILL);
    int status = 0;
    ::waitpid(pid, &status, 0);
    CHECK(WIFSIGNALED(status));
    CHECK(dir.entries().empty());
  }
  {
    INFO("killed while writing the mesh: only its temporary is left");
    // A time budget stops the run by itself after 0.5 s; the mesh (tens of MB) is then written.
    const pid_t pid =
        cli_test::start(long_stream(dir, {"--time-budget", "0.5"}), (logs / "log.txt").string());
    std::string temporary;
    int status = 0;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (temporary.empty() && std::chrono::steady_clock::now() < deadline) {
      for (const std::string& name : dir.entries())
        if (name.rfind("s.vtp.tmp-", 0) == 0) temporary = name;
      if (temporary.empty()) {
        if (::waitpid(pid, &status, WNOHANG) == pid) break;  // finished before it was seen
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
      }
    }
    if (!temporary.empty()) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, &status, 0);
    }
    REQUIRE_FALSE(temporary.empty());
    CHECK(temporary == "s.vtp.tmp-" + std::to_string(pid));
    CHECK(dir.entries() == std::vector<std::string>{temporary});  // no s.vtp, no s.json
  }
  {
    INFO("a rerun writing the same outputs removes the dead process's temporary");
    const Run r =
        run("stream --field saddle3d --seed line:-1,2,0.1:1,2,0.1 --steps 5 --quiet --out " +
            quoted(dir / "s.vtp") + " --report " + quoted(dir / "s.json"));
    INFO(r.output);
    CHECK(r.status == 0);
    CHECK(dir.entries() == std::vector<std::string>{"s.json", "s.vtp"});
    CHECK(orthofront::io::read_mesh(dir / "s.vtp").face_count() > 0);
  }
}

TEST_CASE("bad input: SIGINT stops `path` with the surface so far, marked incomplete",
          "[apps][bad-input][signals]") {
  TempDir dir("bad-input-sigint-path");
  TempDir logs("bad-input-log");
  const pid_t pid =
      cli_test::start({"path", "--field", "double-gyre", "--seed", "line:0.1,0.5,0:0.6,0.5,0",
                       "--t1", "1000000", "--edge", "0.01", "--max-vertices", "100000000", "--out",
                       (dir / "p.vtp").string(), "--report", (dir / "p.json").string()},
                      (logs / "log.txt").string());
  std::this_thread::sleep_for(std::chrono::milliseconds(1000));
  ::kill(pid, SIGINT);
  int status = 0;
  ::waitpid(pid, &status, 0);
  const std::string text = read_file(logs / "log.txt");
  INFO(text);
  REQUIRE(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 2);
  CHECK_THAT(text, Contains("interrupted: the surface built so far was written"));
  CHECK(dir.entries() == std::vector<std::string>{"p.json", "p.vtp"});
  const orthofront::Mesh mesh = orthofront::io::read_mesh(dir / "p.vtp");
  CHECK(mesh.vertex_count() > 100);
  CHECK(mesh.face_count() > 100);
  const auto report = read_json(dir / "p.json");
  CHECK(report["complete"] == false);
  CHECK(report["counts"]["vertices"].get<std::size_t>() == mesh.vertex_count());
}
