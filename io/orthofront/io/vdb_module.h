#pragma once
/// The OpenVDB readers and writers (vdb_grid.h, vdb_field.h) live in a module of their own,
/// liborthofront_vdb.so, which orthofront_io loads on first use: libopenvdb is bound eagerly
/// (tens of thousands of symbol relocations), which every process that links it pays for at
/// start, whether it reads a .vdb file or not (docs/benchmarks/measurements.md, "The OpenVDB
/// module"). The module hands back this table; the functions of
/// vdb_grid.h and vdb_field.h forward to it.
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "orthofront/io/vdb_field.h"
#include "orthofront/io/vdb_grid.h"

namespace orthofront::io {

/// What a VdbFileWriter holds: the module's writer.
struct VdbFileWriter::Impl {
  virtual ~Impl() = default;
  virtual void add(const std::string& name, const VectorGrid& grid, std::optional<double> time) = 0;
  virtual std::size_t grids() const = 0;
  virtual void commit() = 0;
};

struct VdbModule {
  void (*initialize)();
  std::vector<VdbGridInfo> (*list_grids)(const std::filesystem::path& path);
  VectorGrid (*read_grid)(const std::filesystem::path& path, const std::string& selector);
  VectorGrid (*parse_grid)(std::string_view content, const std::string& file,
                           const std::string& selector);
  std::unique_ptr<VdbFileWriter::Impl> (*open_writer)(const std::filesystem::path& path);
  std::unique_ptr<TimeSeries> (*open_series)(std::vector<VdbStep> steps, std::vector<double> times);
  std::unique_ptr<TimeSeries> (*open_file_series)(const std::filesystem::path& path);
  std::unique_ptr<VdbField> (*open_field)(const std::filesystem::path& path,
                                          const std::string& selector);
  std::unique_ptr<VdbField> (*field_from_grid)(const VectorGrid& grid, const std::string& name);
};

/// The module's table: loaded on the first call (from beside liborthofront_io.so, else by name
/// through the library search path). Throws IoError saying what could not be loaded.
const VdbModule& vdb_module();

}  // namespace orthofront::io

/// The module's one entry point (liborthofront_vdb.so).
extern "C" const orthofront::io::VdbModule* orthofront_vdb_module();
