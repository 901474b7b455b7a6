#pragma once
/// OpenVDB (.vdb) vector grids: reading Vec3f / Vec3d grids (or three scalar grids) by name,
/// densely into a VectorGrid or as a time series, and writing VectorGrids (NaN → inactive voxel).
/// For sampling a sparse VDB grid directly, see vdb_field.h.
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "orthofront/field/grid.h"
#include "orthofront/io/time_series.h"

namespace orthofront::io {

/// openvdb::initialize(), once per process (every function here calls it).
void initialize_openvdb();

/// What `orthofront info` shows about one grid of a .vdb file.
struct VdbGridInfo {
  std::string name;
  std::string value_type;  ///< "vec3s", "vec3d", "float", ...
  std::string grid_class;  ///< "unknown", "level set", "fog volume", "staggered"
  Vec3 voxel_size = Vec3::Ones();
  std::array<std::int64_t, 6> index_box{};  ///< active voxels: min x, y, z, max x, y, z
  std::uint64_t active_voxels = 0;
  std::optional<double> time;  ///< the grid's "time" metadata, if any
};

/// The grids of a .vdb file (metadata only; nothing is decompressed).
std::vector<VdbGridInfo> list_vdb_grids(const std::filesystem::path& path);

/// Reads one vector grid densely over its active bounding box (the box it was written with, for
/// files this writer made); inactive voxels are NaN. `selector`: a grid name, "x,y,z" for three
/// scalar grids, or empty for the first vector grid (see vdb_detail.h). Throws IoError /
/// FormatError naming the file and the grid; a rotated or non-linear transform is a FormatError.
VectorGrid read_vdb_grid(const std::filesystem::path& path, const std::string& selector = {});

/// The same from the bytes of a .vdb file.
VectorGrid parse_vdb_grid(std::string_view content, const std::string& file,
                          const std::string& selector = {});

/// One grid to write: `grid` named `name`, with a "time" metadata entry when `time` is set.
struct VdbOutputGrid {
  std::string name;
  const VectorGrid* grid = nullptr;
  std::optional<double> time;
};

/// Writes the grids into one .vdb file atomically (temporary name, then rename). NaN samples
/// become inactive voxels; every other sample (zero included) is active. Throws InvalidArgument
/// for rectilinear grids or duplicate names, IoError naming the path.
void write_vdb(const std::filesystem::path& path, const std::vector<VdbOutputGrid>& grids);

/// One grid named `name`.
void write_vdb(const VectorGrid& grid, const std::filesystem::path& path,
               const std::string& name = "velocity");

/// Collects grids one at a time (each converted to a sparse OpenVDB grid right away, so that the
/// dense samples need not stay in memory) and writes them into one .vdb file on commit(),
/// atomically. Destroying it before commit() writes nothing.
class VdbFileWriter {
 public:
  explicit VdbFileWriter(std::filesystem::path path);
  ~VdbFileWriter();
  VdbFileWriter(const VdbFileWriter&) = delete;
  VdbFileWriter& operator=(const VdbFileWriter&) = delete;
  /// Throws InvalidArgument for rectilinear grids, an empty or duplicate name.
  void add(const std::string& name, const VectorGrid& grid, std::optional<double> time = {});
  std::size_t grids() const;
  void commit();

  struct Impl;  ///< the OpenVDB module's writer (vdb_module.h)

 private:
  std::unique_ptr<Impl> impl_;
};

/// One step of a VDB time series: a file and the grid in it.
struct VdbStep {
  std::filesystem::path file;
  std::string selector;
};

/// A time series of VDB grids, one per step (one file per step, several grids in one file, or a
/// mix). Every step must share the transform; the dense box is the union of the steps' boxes
/// (inactive voxels are NaN). read_raw reads and densifies a step (the bytes come back decoded).
std::unique_ptr<TimeSeries> open_vdb_series(std::vector<VdbStep> steps, std::vector<double> times);

/// The vector grids of one file as a time series, ordered by their "time" metadata (all grids
/// need it), or in file order at times 0, 1, ... when none has it.
std::unique_ptr<TimeSeries> open_vdb_file_series(const std::filesystem::path& path);

}  // namespace orthofront::io
