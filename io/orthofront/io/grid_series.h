#pragma once
/// Time series made of one vector-grid file per step (any format grid_file reads: a list of .vti,
/// .vec, .am, .nrrd, .vtk or .vdb files), or described by a ParaView .pvd collection.
#include <cstring>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "orthofront/io/time_series.h"

namespace orthofront::io {

/// One grid held in memory, seen as a series of one step (time 0): lets a steady grid go where a
/// time series is expected (convert, info).
class SingleGridSeries final : public TimeSeries {
 public:
  SingleGridSeries(VectorGrid grid, std::string description, bool zero_is_no_data)
      : grid_(std::move(grid)), description_(std::move(description)),
        zero_is_no_data_(zero_is_no_data) {}
  bool zero_is_no_data() const override { return zero_is_no_data_; }
  std::size_t step_count() const override { return 1; }
  double time(std::size_t) const override { return 0.0; }
  const GridGeometry& geometry() const override { return grid_.geometry; }
  int components() const override { return grid_.components; }
  std::string describe() const override { return description_; }
  RawStep read_raw(std::size_t step) const override {
    RawStep raw{step, std::vector<std::byte>(grid_.bytes()), false};
    std::memcpy(raw.bytes.data(), grid_.values.data(), grid_.bytes());
    return raw;
  }

 private:
  VectorGrid grid_;
  std::string description_;
  bool zero_is_no_data_;
};

/// Steps held in memory (arrays handed over by Python or ParaView), each at its time: a series
/// the brick cache streams like a file's, so a surface from memory equals the one from disk.
class MemorySeries final : public TimeSeries {
 public:
  /// `steps[i]` holds geometry.point_count() * components floats at `times[i]`. Throws
  /// InvalidArgument for no step, a step of another size, or times that do not increase.
  MemorySeries(GridGeometry geometry, int components, std::vector<std::vector<float>> steps,
               std::vector<double> times, std::string description, bool zero_is_no_data = false);
  bool zero_is_no_data() const override { return zero_is_no_data_; }
  std::size_t step_count() const override { return steps_.size(); }
  double time(std::size_t step) const override { return times_.at(step); }
  const GridGeometry& geometry() const override { return geometry_; }
  int components() const override { return components_; }
  std::string describe() const override { return description_; }
  RawStep read_raw(std::size_t step) const override {
    const std::vector<float>& values = steps_.at(step);
    RawStep raw{step, std::vector<std::byte>(values.size() * sizeof(float)), false};
    std::memcpy(raw.bytes.data(), values.data(), raw.bytes.size());
    return raw;
  }

 private:
  GridGeometry geometry_;
  int components_;
  std::vector<std::vector<float>> steps_;
  std::vector<double> times_;
  std::string description_;
  bool zero_is_no_data_;
};

/// One file per step. The first file is read when the series is opened (geometry and component
/// count); every step must match it, or decode throws FormatError naming the file and the step.
/// read_raw reads the file's bytes (encoded); decode parses them (thread-safe).
class GridFileSeries final : public TimeSeries {
 public:
  /// `files[i]` holds the step at `times[i]`. Throws InvalidArgument when the counts differ, a
  /// list is empty or the times are not strictly increasing; IoError / FormatError from reading
  /// the first file. `selector` picks the array / grid in each file (see grid_file.h).
  GridFileSeries(std::vector<std::filesystem::path> files, std::vector<double> times,
                 std::string selector = {});

  std::size_t step_count() const override { return files_.size(); }
  double time(std::size_t step) const override { return times_.at(step); }
  const GridGeometry& geometry() const override { return geometry_; }
  int components() const override { return components_; }
  /// Grid files (.vti, .nhdr, .vec, ... and ParaView's collections of them) mark solid cells and
  /// land with zero vectors (ParaView's resampling writes 0 outside the fluid): no data, as for
  /// a single grid file.
  bool zero_is_no_data() const override { return true; }
  std::string describe() const override;
  RawStep read_raw(std::size_t step) const override;
  void decode(const RawStep& raw, std::span<float> values) const override;

  const std::vector<std::filesystem::path>& files() const { return files_; }

 private:
  std::vector<std::filesystem::path> files_;
  std::vector<double> times_;
  std::string selector_;
  GridGeometry geometry_;
  int components_ = 3;
};

/// A ParaView collection: the <DataSet timestep="..." file="..."/> entries of a .pvd file
/// (relative files are relative to the .pvd's folder), sorted by time. Several parts per time
/// step are rejected. Throws IoError / FormatError naming the .pvd and the bad entry.
std::unique_ptr<GridFileSeries> open_pvd(const std::filesystem::path& path,
                                         const std::string& selector = {});

/// Times t0, t0 + dt, ... for `count` steps.
std::vector<double> evenly_spaced_times(std::size_t count, double t0, double dt);

/// Natural file order for the steps of a series: "a2.vec" < "a10.vec" (digit runs compare as
/// numbers, leading zeros ignored).
bool natural_less(const std::string& a, const std::string& b);

/// True for the NetCDF extensions (.nc, .nc4, .cdf; any case).
bool is_netcdf_path(const std::filesystem::path& path);

/// The files a pattern names: a comma-separated list of paths, each of which may hold the glob
/// characters * ? [ ] (expanded and sorted in natural order: "d2" before "d10"). Throws
/// InvalidArgument naming a pattern that matches nothing.
std::vector<std::filesystem::path> expand_file_pattern(const std::string& pattern);

}  // namespace orthofront::io
