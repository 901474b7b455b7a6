#pragma once
/// The project's HDF5 layout for steady vector fields and time series of 2D/3D vector fields
/// (docs/hdf5-layout.md): writing (steady, or streamed step by step), describing, reading into a
/// VectorGrid, and reading as an io::TimeSeries whose raw reads return still-compressed chunks
/// so that decompression can run in parallel. Every file gets an XDMF sidecar (.xmf) so ParaView
/// opens it directly.
#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "orthofront/field/grid.h"
#include "orthofront/io/time_series.h"

namespace orthofront::io {

/// How the samples are stored.
enum class Hdf5Storage {
  steady,    ///< one dataset `velocity` [nz][ny][nx][C] (2D: [ny][nx][C])
  chunked,   ///< series: one dataset `velocity` [T][nz][ny][nx][C], chunks of whole z-slices
  per_step,  ///< series: group `steps` with one dataset per step, `steps/000000`, ...
  bricked,   ///< series: one dataset `velocity` [T][nz][ny][nx][C], one chunk per brick and step
};
const char* to_string(Hdf5Storage storage);
/// Series storages that keep all steps in one dataset with a leading step axis.
inline bool has_step_axis(Hdf5Storage storage) {
  return storage == Hdf5Storage::chunked || storage == Hdf5Storage::bricked;
}

/// Chunk compression. lz4 and zstd go through Blosc (HDF5 filter 32001, byte shuffle inside),
/// which h5py/hdf5plugin and other Blosc-aware readers understand.
enum class Hdf5Codec { none, gzip, lz4, zstd };
const char* to_string(Hdf5Codec codec);
/// HDF5's registered id of the Blosc filter.
constexpr int kBloscFilterId = 32001;

/// Unit names, free text (e.g. "m", "s", "m/s"); empty = not stated.
struct Hdf5Units {
  std::string length, time, velocity;
};

struct Hdf5WriteOptions {
  std::string group = "/";  ///< group that holds the field (created with its parents)
  Hdf5Storage storage = Hdf5Storage::bricked;  ///< series only (steady files are `steady`)
  /// Bricked storage: points per brick along each axis (one chunk per brick and step; 32 was the
  /// fastest in `orthofront-bench path --brick-sweep`, see docs/hdf5-layout.md).
  std::int64_t brick_size = 32;
  /// Compression; `none` with gzip_level > 0 means gzip at that level.
  Hdf5Codec codec = Hdf5Codec::none;
  int level = 0;        ///< lz4/zstd: Blosc level 1..9 (0: 5 for lz4, 1 for zstd)
  int gzip_level = 0;   ///< 0: no compression; 1..9: gzip (deflate) at that level
  bool shuffle = true;  ///< with gzip: byte-shuffle filter before deflate (smaller, faster)
  /// Upper bound on one chunk: a step (or steady field) larger than this is split into chunks of
  /// whole z-slices (2D: y-rows); a chunk never spans two steps. 16 MiB lets one step be
  /// compressed and decoded on several cores, where one chunk a step is decoded by one
  /// (`orthofront-bench grid`; docs/hdf5-layout.md); set it >= the step size for one chunk per
  /// step.
  /// HDF5 caps chunks at 4 GiB.
  std::size_t max_chunk_bytes = std::size_t{16} << 20;
  /// Compress chunks in parallel here and store them with H5Dwrite_chunk (default), or let
  /// HDF5's filter pipeline compress serially. Both produce standard deflate/shuffle chunks.
  bool parallel_compression = true;
  Hdf5Units units;
  /// When set, NaN samples are stored as this value and the attribute `fill_value` says so.
  std::optional<float> fill_value;
  /// Written as the attribute `zero_is_no_data` (readers' GridFieldOptions). Real data: true;
  /// sampled analytic fields: false (their zero vectors are critical points, not land).
  bool zero_is_no_data = true;
  /// Write "<file>.xmf" beside the file where ParaView can read it (xdmf_readable); otherwise
  /// a sidecar of that name left from an earlier file is removed.
  bool xdmf = true;
};

/// ParaView's HDF5 decodes deflate but has no Blosc filter: files compressed with lz4 or zstd
/// are not readable through a sidecar, so they get none.
inline bool xdmf_readable(const Hdf5WriteOptions& options) {
  return options.codec == Hdf5Codec::none || options.codec == Hdf5Codec::gzip;
}

/// What a field group holds, as read from its attributes and datasets.
struct Hdf5Description {
  std::filesystem::path file;
  std::string group;  ///< absolute path of the group
  Hdf5Storage storage = Hdf5Storage::steady;
  std::string dataset;  ///< `velocity` dataset, or the `steps` group (per-step)
  GridGeometry geometry;
  int components = 3;
  std::vector<double> times;  ///< empty for steady fields
  Hdf5Units units;
  std::optional<float> fill_value;  ///< from `fill_value` or `_FillValue`
  bool zero_is_no_data = true;
  std::vector<std::string>
      filters;                     ///< filter names in pipeline order, e.g. {"shuffle", "deflate"}
  int gzip_level = 0;              ///< deflate level from the filter parameters (0: none)
  std::int64_t chunk_slices = 0;   ///< z-slices (2D: y-rows) per chunk; 0: contiguous
  std::array<std::int64_t, 3> brick{0, 0, 0};  ///< bricked: points per brick along x, y, z
  std::vector<std::size_t> missing_steps;  ///< per-step storage: steps without a dataset
  std::string stored_type;         ///< e.g. "float32 little-endian"
  std::uint64_t stored_bytes = 0;  ///< bytes the samples occupy in the file (all steps)

  std::size_t step_count() const { return storage == Hdf5Storage::steady ? 1 : times.size(); }
  std::size_t step_bytes() const {
    return geometry.point_count() * static_cast<std::size_t>(components) * sizeof(float);
  }
};

/// Reads the description of the field group at `group` (a group, or the `velocity` dataset in
/// it). Throws IoError (missing or unreadable file) or FormatError naming the file, the dataset
/// or attribute path and the offending value: missing dataset or attribute, last dimension not
/// 2 or 3, ranks or sizes that do not match, an empty time series, times not increasing.
Hdf5Description describe_hdf5(const std::filesystem::path& file, const std::string& group = "/");

/// Writes a steady field as a new file (written under a temporary name and renamed when
/// complete; nothing is left behind on failure), plus its .xmf sidecar.
void write_hdf5_grid(const VectorGrid& grid, const std::filesystem::path& file,
                     const Hdf5WriteOptions& options = {});

/// Reads a steady field (or one step of a series) into a VectorGrid, fill values as NaN.
VectorGrid read_hdf5_grid(const std::filesystem::path& file, const std::string& group = "/",
                          std::size_t step = 0);

/// Streams a time series into a new file one step at a time: memory stays at about one step
/// whatever the series' size. Steps are written in order; commit() closes the file, writes the
/// sidecar and renames it onto `file`. Destroying the writer before commit() removes the
/// temporary file (so an error or interruption never leaves a file that looks complete).
class Hdf5SeriesWriter {
 public:
  /// Throws InvalidArgument for an empty or non-increasing `times`, a geometry or component
  /// count that is not a valid 2D/3D vector grid; IoError when the file cannot be created.
  Hdf5SeriesWriter(const std::filesystem::path& file, const GridGeometry& geometry, int components,
                   std::vector<double> times, const Hdf5WriteOptions& options = {});
  ~Hdf5SeriesWriter();
  Hdf5SeriesWriter(const Hdf5SeriesWriter&) = delete;
  Hdf5SeriesWriter& operator=(const Hdf5SeriesWriter&) = delete;

  /// Writes the next step: point_count * components floats, x fastest, NaN = no data.
  void write_step(std::span<const float> values);
  std::size_t steps_written() const;
  /// Finishes the file. Throws InvalidArgument unless every step was written.
  void commit();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

struct Hdf5ReadOptions {
  /// Read compressed chunks as raw bytes (H5Dread_chunk) and decompress in decode() — serial I/O,
  /// parallel decoding. false: let HDF5 decode in read_raw (the reference path).
  bool raw_chunks = true;
  /// Accept a steady field as a series of one step at time 0 (for tools like `info`).
  bool steady_as_single_step = false;
};

/// A series in the project's layout. read_raw is serial (one thread at a time); decode may run on
/// several threads at once and decodes the chunks of one step in parallel too.
class Hdf5TimeSeries final : public TimeSeries {
 public:
  ~Hdf5TimeSeries() override;
  std::size_t step_count() const override;
  double time(std::size_t step) const override;
  const GridGeometry& geometry() const override;
  int components() const override;
  std::string describe() const override;
  RawStep read_raw(std::size_t step) const override;
  void decode(const RawStep& raw, std::span<float> values) const override;
  /// Bricked storage: the chunks; other storages: one brick, the whole step.
  BrickLayout bricks() const override;
  RawStep read_raw_brick(std::size_t step, std::size_t brick) const override;
  void decode_brick(const RawStep& raw, std::span<float> values) const override;
  bool zero_is_no_data() const override;

  const Hdf5Description& description() const;

 private:
  friend std::unique_ptr<Hdf5TimeSeries> open_hdf5_series(const std::filesystem::path&,
                                                          const std::string&,
                                                          const Hdf5ReadOptions&);
  struct Impl;
  explicit Hdf5TimeSeries(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

/// Opens a series (see describe_hdf5 for the errors; a steady field is an error unless
/// options.steady_as_single_step).
std::unique_ptr<Hdf5TimeSeries> open_hdf5_series(const std::filesystem::path& file,
                                                 const std::string& group = "/",
                                                 const Hdf5ReadOptions& options = {});

/// True when the file starts with the HDF5 signature.
bool is_hdf5_file(const std::filesystem::path& file);

/// The sidecar path: "a/b.h5" -> "a/b.xmf".
std::filesystem::path xdmf_path(const std::filesystem::path& file);

}  // namespace orthofront::io
