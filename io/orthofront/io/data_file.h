#pragma once
/// Gridded data files on the command line: "FILE.ext[:SELECTOR]" dispatched on the extension to
/// a format's opener. `--field` (field_source) and `info` both go through this table; a format
/// is one entry in data_file_formats() (data_file.cpp).
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "orthofront/field/grid.h"
#include "orthofront/io/time_series.h"

namespace orthofront::io {

/// A file and what to read in it (an HDF5 group, an array name, ...; empty: the default).
struct DataFileSpec {
  std::filesystem::path path;
  std::string selector;
};

/// A data file opened for reading or inspection.
struct DataFile {
  std::string format;  ///< e.g. "HDF5 (orthofront layout 1)"
  /// Facts worth printing, in order: storage, compression, units, ... (`info` shows them).
  std::vector<std::pair<std::string, std::string>> details;
  /// The samples; a steady file is a series of one step at time 0.
  std::unique_ptr<TimeSeries> series;
  bool steady = true;
  /// Whether a zero vector means "no data" in this file (GridFieldOptions::zero_is_no_data).
  bool zero_is_no_data = true;
  /// Bytes the samples occupy on disk (0: unknown).
  std::uint64_t stored_bytes = 0;
};

struct DataFileFormat {
  const char* name;                     ///< for messages: "HDF5"
  std::vector<std::string> extensions;  ///< lower case with the dot: ".h5"
  DataFile (*open)(const DataFileSpec& spec);
};

/// Every format, in a stable order.
const std::vector<DataFileFormat>& data_file_formats();

/// ".h5, .hdf5, .hdf" (for messages).
std::string data_file_extensions();

/// Splits "FILE.ext" / "FILE.ext:SELECTOR" when ext (case-insensitive) is a known data-file
/// extension, and returns the format; nullopt otherwise. The first ':' that follows a known
/// extension separates the selector.
std::optional<std::pair<DataFileSpec, const DataFileFormat*>> find_data_file(
    const std::string& spec);

/// True when `spec` looks like a file name (has a '/' or an extension before any ':') rather than
/// an analytic field name.
bool looks_like_file(const std::string& spec);

/// Opens `spec`; throws InvalidArgument for an unknown extension, IoError / FormatError from the
/// reader otherwise.
DataFile open_data_file(const std::string& spec);

/// A NetCDF series: `spec.path` is a file, a glob or a comma-separated list of them; the selector
/// names the variables and options (parse_netcdf_selector). Throws InvalidArgument when the
/// build has no NetCDF.
std::unique_ptr<TimeSeries> open_netcdf_series(const DataFileSpec& spec);

/// A series of one grid held in memory (for formats whose readers produce a VectorGrid), with
/// its file's rule for zero vectors.
std::unique_ptr<TimeSeries> single_grid_series(VectorGrid grid, std::string description,
                                               bool zero_is_no_data);

}  // namespace orthofront::io
