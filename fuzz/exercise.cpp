#include "exercise.h"

#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <cstddef>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "cli/batch_checkpoint.h"
#include "cli/batch_job.h"
#include "jobs/seed_spec.h"
#include "orthofront/error.h"
#include "orthofront/field/analytic.h"
#include "orthofront/field/unsteady.h"
#include "orthofront/io/grid_file.h"
#include "orthofront/io/hdf5_layout.h"
#include "orthofront/io/obj_codec.h"
#include "orthofront/io/open_field.h"
#include "orthofront/io/ply_codec.h"
#include "orthofront/io/state_codec.h"
#include "orthofront/io/vdb_grid.h"
#include "orthofront/io/vtp_codec.h"
#include "orthofront/spacetime/brick_cache.h"

namespace orthofront::fuzz {

namespace {

/// Where inputs are written for readers that take a path (HDF5, OpenVDB's File): /dev/shm when
/// there is one.
std::filesystem::path scratch_base() {
  const std::filesystem::path shm = "/dev/shm";
  return std::filesystem::is_directory(shm) ? shm : std::filesystem::temp_directory_path();
}

/// The input in a file of this process's own, rewritten for every input.
std::filesystem::path scratch_file(const std::string& extension, std::string_view input) {
  const std::filesystem::path file =
      scratch_base() / ("orthofront-fuzz-" + std::to_string(::getpid()) + extension);
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  out.write(input.data(), static_cast<std::streamsize>(input.size()));
  return file;
}

/// Runs `parse`, swallowing the project's own errors only.
template <class Parse>
bool expect_clean(Parse&& parse) {
  try {
    return parse();
  } catch (const orthofront::Error&) {
    return true;
  }
}

bool grid_is_whole(const VectorGrid& grid) {
  return grid.values.size() ==
         grid.geometry.point_count() * static_cast<std::size_t>(grid.components);
}

bool grid(const std::string& extension, std::string_view input) {
  // Detached data files (NRRD "data file:") resolve against this folder, which holds nothing.
  static const std::filesystem::path path =
      std::filesystem::temp_directory_path() / "orthofront-fuzz-no-folder" / "input";
  return expect_clean([&] {
    return grid_is_whole(io::parse_vector_grid(input, path.string() + extension));
  });
}

/// As `info`, `convert` and `stream --field F.vdb` open a file: the grid list, then the vector
/// grid through OpenVDB's File (memory-mapped, delayed loading).
bool vdb_file(std::string_view input) {
  const auto file = scratch_file(".vdb", input);
  bool ok = expect_clean([&] {
    (void)io::list_vdb_grids(file);
    return true;
  });
  ok = expect_clean([&] { return grid_is_whole(io::read_vector_grid(file)); }) && ok;
  std::filesystem::remove(file);
  return ok;
}

/// As `info`, `convert` and `path --field F.h5` open a file: the description, a steady read, then
/// the series with the bricks of its first steps read and decoded (the brick cache's path), with
/// raw chunk reads and with HDF5's own decoding.
bool hdf5(std::string_view input) {
  const auto file = scratch_file(".h5", input);
  bool ok = expect_clean([&] {
    (void)io::describe_hdf5(file);
    return true;
  });
  ok = expect_clean([&] { return grid_is_whole(io::read_hdf5_grid(file)); }) && ok;
  for (const bool raw_chunks : {true, false}) {
    ok = expect_clean([&] {
      io::Hdf5ReadOptions options;
      options.raw_chunks = raw_chunks;
      options.steady_as_single_step = true;
      const auto series = io::open_hdf5_series(file, "/", options);
      const io::BrickLayout layout = series->bricks();
      const std::size_t steps = std::min<std::size_t>(series->step_count(), 2);
      for (std::size_t step = 0; step < steps; ++step) {
        for (std::size_t brick = 0; brick < std::min<std::size_t>(layout.bricks(), 64); ++brick) {
          const io::RawStep raw = series->read_raw_brick(step, brick);
          std::vector<float> values(series->brick_floats());
          series->decode_brick(raw, values);
        }
      }
      return true;
    }) && ok;
  }
  std::filesystem::remove(file);
  return ok;
}

bool mesh(const std::string& extension, std::string_view input) {
  return expect_clean([&] {
    const Mesh m = extension == ".vtp"   ? io::detail::read_vtp(input, "input.vtp")
                   : extension == ".ply" ? io::detail::read_ply(input, "input.ply")
                                         : io::detail::read_obj(input, "input.obj");
    // Every face a reader returns is a triangle or quad of vertices it returned.
    for (const Face& face : m.faces) {
      if (face.size != 3 && face.size != 4) return false;
      for (std::size_t i = 0; i < face.size; ++i) {
        if (face.v[i] < 0 || static_cast<std::size_t>(face.v[i]) >= m.vertex_count()) return false;
      }
    }
    return true;
  });
}

bool parse_seed(const std::string& text) {
  // "file:" specs read a file; the fuzzer must not wander the file system.
  if (text.find("file") != std::string::npos) return true;
  return expect_clean([&] {
    const SeedCurve curve = jobs::parse_seed(text);
    for (const double s : curve.sample(16)) (void)curve.point(s);
    return true;
  });
}

bool parse_field(const std::string& text) {
  bool ok = expect_clean([&] {
    const auto field = make_analytic_field(text);
    const Box<3> box = field->domain();
    Vec3 v;
    (void)field->velocity(0.5 * (box.lo + box.hi), v);
    return true;
  });
  ok = expect_clean([&] { return make_unsteady_field(text) != nullptr; }) && ok;
  return ok;
}

bool parse_bytes(const std::string& text) {
  (void)io::parse_grid_source(text);
  return expect_clean([&] {
    (void)spacetime::parse_bytes(text);
    return true;
  });
}

/// A folder of this process's own, for inputs of several files.
std::filesystem::path scratch_folder() {
  const std::filesystem::path folder =
      scratch_base() / ("orthofront-fuzz-" + std::to_string(::getpid()) + "-folder");
  std::filesystem::create_directories(folder);
  return folder;
}

void write_bytes(const std::filesystem::path& file, std::string_view bytes) {
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

/// A time series as `path --field SPEC` opens it, with its first steps read.
bool series(const std::string& spec) {
  return expect_clean([&] {
    const auto opened = io::open_time_series(spec, "time series");
    std::vector<float> values(opened->step_floats());
    for (std::size_t step = 0; step < std::min<std::size_t>(opened->step_count(), 2); ++step)
      opened->read(step, values);
    return true;
  });
}

/// NetCDF (3 and 4) as `info` and `path --field F.nc` read it: by CF time, and with a step given.
bool netcdf(std::string_view input) {
  const auto file = scratch_file(".nc", input);
  bool ok = series(file.string());
  ok = series(file.string() + ":dt=1") && ok;
  std::filesystem::remove(file);
  return ok;
}

/// A ParaView collection: the input is the .pvd, beside two small .vti steps it may name
/// (a.vti, b.vti) and nothing else.
bool pvd(std::string_view input) {
  const std::filesystem::path folder = scratch_folder();
  static const std::string step =
      "<VTKFile type=\"ImageData\" version=\"1.0\"><ImageData WholeExtent=\"0 1 0 1 0 0\" "
      "Origin=\"0 0 0\" Spacing=\"1 1 1\"><Piece Extent=\"0 1 0 1 0 0\"><PointData "
      "Vectors=\"U\"><DataArray type=\"Float32\" Name=\"U\" NumberOfComponents=\"2\" "
      "format=\"ascii\">1 0 1 0 1 0 1 0</DataArray></PointData></Piece></ImageData></VTKFile>";
  write_bytes(folder / "a.vti", step);
  write_bytes(folder / "b.vti", step);
  write_bytes(folder / "input.pvd", input);
  const bool ok = series((folder / "input.pvd").string());
  std::filesystem::remove_all(folder);
  return ok;
}

/// A detached NRRD header (.nhdr) and its data file: the input up to its first NUL byte is the
/// header, the rest the bytes of data.raw beside it.
bool grid_nhdr(std::string_view input) {
  const std::filesystem::path folder = scratch_folder();
  const std::size_t nul = input.find('\0');
  write_bytes(folder / "input.nhdr", input.substr(0, nul));
  write_bytes(folder / "data.raw", nul == std::string_view::npos ? "" : input.substr(nul + 1));
  const bool ok = expect_clean(
      [&] { return grid_is_whole(io::read_vector_grid(folder / "input.nhdr")); });
  std::filesystem::remove_all(folder);
  return ok;
}

/// A batch job file, read as TOML and as JSON.
bool job_file(std::string_view input) {
  const std::filesystem::path folder = scratch_folder();
  bool ok = true;
  for (const char* name : {"job.toml", "job.json"}) {
    write_bytes(folder / name, input);
    ok = expect_clean([&] {
      (void)cli::read_batch_job(folder / name);
      return true;
    }) && ok;
  }
  std::filesystem::remove_all(folder);
  return ok;
}

/// A batch checkpoint's state file, as `batch --resume` loads it. The input is the state after
/// the file's magic and before its CRC-32, which are added here (a mutated checksum would stop
/// every input at the first check); the job digest is taken from the input too.
bool checkpoint(std::string_view payload) {
  const std::filesystem::path folder = scratch_folder();
  std::uint64_t digest = 0;
  try {
    io::ByteReader in(payload, "input");
    (void)in.text();  // the version
    digest = in.u64();
  } catch (const orthofront::Error&) {
  }
  std::string bytes = "orthofront-checkpoint\n" + std::string(payload);
  const auto crc = static_cast<std::uint32_t>(::crc32(
      0L, reinterpret_cast<const Bytef*>(payload.data()), static_cast<uInt>(payload.size())));
  for (int k = 0; k < 4; ++k) bytes.push_back(static_cast<char>(crc >> (8 * k) & 0xff));
  write_bytes(folder / "s.state", bytes);
  const bool ok = expect_clean([&] {
    (void)cli::CheckpointFolder(folder, digest).load_state("s");
    return true;
  });
  std::filesystem::remove_all(folder);
  return ok;
}

}  // namespace

bool exercise(std::string_view target, std::string_view input) {
  const std::string name(target);
  if (name == "grid_nhdr") return grid_nhdr(input);
  if (name.rfind("grid_", 0) == 0) return grid("." + name.substr(5), input);
  if (name == "vdb_file") return vdb_file(input);
  if (name == "hdf5") return hdf5(input);
  if (name.rfind("mesh_", 0) == 0) return mesh("." + name.substr(5), input);
  if (name == "parse_seed") return parse_seed(std::string(input));
  if (name == "parse_field") return parse_field(std::string(input));
  if (name == "parse_bytes") return parse_bytes(std::string(input));
  if (name == "netcdf") return netcdf(input);
  if (name == "pvd") return pvd(input);
  if (name == "job_file") return job_file(input);
  if (name == "checkpoint") return checkpoint(input);
  throw std::invalid_argument("no fuzz target '" + name + "'");
}

}  // namespace orthofront::fuzz
