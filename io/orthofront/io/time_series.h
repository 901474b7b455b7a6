#pragma once
/// A time series of vector grids on disk, read one step at a time. The reading is split in two
/// so a pipeline can run the I/O serially and the decoding (decompression, conversion) in
/// parallel: read(step) = decode(read_raw(step)).
#include <cstddef>
#include <algorithm>
#include <cstring>
#include <span>
#include <string>
#include <vector>

#include "orthofront/field/grid.h"

namespace orthofront::io {

/// The bytes of one step as they came off the disk (still compressed or in file layout when
/// `encoded` is true; otherwise already the step's floats).
struct RawStep {
  std::size_t step = 0;
  std::vector<std::byte> bytes;
  bool encoded = false;
};

class TimeSeries {
 public:
  virtual ~TimeSeries() = default;
  virtual std::size_t step_count() const = 0;
  /// Physical time of a step; strictly increasing with the step index.
  virtual double time(std::size_t step) const = 0;
  /// Every step shares this geometry (readers check it and throw FormatError otherwise).
  virtual const GridGeometry& geometry() const = 0;
  /// Floats per grid point (2 or 3).
  virtual int components() const = 0;
  /// File, dataset and layout in words, for messages and reports.
  virtual std::string describe() const = 0;

  /// I/O only. Called from one thread at a time. Throws IoError / FormatError naming the file,
  /// the dataset and the step.
  virtual RawStep read_raw(std::size_t step) const = 0;
  /// Turns raw bytes into step_floats() floats (NaN where there is no data). Safe to call from
  /// several threads at once. The default copies unencoded bytes.
  virtual void decode(const RawStep& raw, std::span<float> values) const {
    std::memcpy(values.data(), raw.bytes.data(), std::min(raw.bytes.size(), values.size_bytes()));
  }

  std::size_t step_floats() const {
    return geometry().point_count() * static_cast<std::size_t>(components());
  }
  std::size_t step_bytes() const { return step_floats() * sizeof(float); }
  /// read_raw + decode into `values` (step_floats() entries).
  void read(std::size_t step, std::span<float> values) const { decode(read_raw(step), values); }
};

}  // namespace orthofront::io
