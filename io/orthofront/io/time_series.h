#pragma once
/// A time series of vector grids on disk, read one step at a time. The reading is split in two
/// so a pipeline can run the I/O serially and the decoding (decompression, conversion) in
/// parallel: read(step) = decode(read_raw(step)).
#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
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
  std::size_t brick = 0;          ///< brick reads: which brick of the step
  std::uint32_t filter_mask = 0;  ///< brick reads: filters skipped for this chunk (HDF5's mask)
};

/// How a series splits each step into spatial bricks, the unit of partial reads. Brick (bi, bj,
/// bk) holds the points [bi·size[0], (bi+1)·size[0]) × ... of the grid, clipped to it; in memory a
/// brick is always size[0]·size[1]·size[2] points (x fastest, components interleaved), edge bricks
/// padded past the grid. A series without bricks has one brick: the whole step.
struct BrickLayout {
  std::array<std::int64_t, 3> size{1, 1, 1};   ///< points per brick along each axis
  std::array<std::int64_t, 3> count{1, 1, 1};  ///< bricks along each axis

  std::size_t bricks() const { return static_cast<std::size_t>(count[0] * count[1] * count[2]); }
  std::size_t brick_points() const { return static_cast<std::size_t>(size[0] * size[1] * size[2]); }
  std::size_t brick_index(std::int64_t bi, std::int64_t bj, std::int64_t bk) const {
    return static_cast<std::size_t>(bi + count[0] * (bj + count[1] * bk));
  }
  /// The layout of one brick per step.
  static BrickLayout whole(const GridGeometry& g) {
    BrickLayout b;
    b.size = g.size;
    return b;
  }
  /// Bricks of `edge` points per axis (axes of a 2D grid beyond y keep one brick of one point).
  static BrickLayout cubes(const GridGeometry& g, std::int64_t edge) {
    BrickLayout b;
    for (std::size_t a = 0; a < 3; ++a) {
      b.size[a] = std::min(edge, g.size[a]);
      b.count[a] = (g.size[a] + b.size[a] - 1) / b.size[a];
    }
    return b;
  }
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

  /// The brick layout of partial reads (default: one brick, the whole step).
  virtual BrickLayout bricks() const { return BrickLayout::whole(geometry()); }
  /// I/O of one brick of one step (same threading rules as read_raw). The default, for series
  /// without bricks, reads the whole step (brick 0).
  virtual RawStep read_raw_brick(std::size_t step, std::size_t brick) const {
    RawStep raw = read_raw(step);
    raw.brick = brick;
    return raw;
  }
  /// Turns a brick's raw bytes into brick_floats() floats (NaN where there is no data; padding
  /// past the grid is unspecified). Thread-safe. The default decodes a whole step.
  virtual void decode_brick(const RawStep& raw, std::span<float> values) const {
    decode(raw, values);
  }
  /// Whether a zero vector marks a point without data (land, solid cells) rather than a
  /// stagnation point: true for measured and simulated data, false for sampled analytic fields.
  virtual bool zero_is_no_data() const { return false; }

  std::size_t brick_floats() const {
    return bricks().brick_points() * static_cast<std::size_t>(components());
  }
  std::size_t step_floats() const {
    return geometry().point_count() * static_cast<std::size_t>(components());
  }
  std::size_t step_bytes() const { return step_floats() * sizeof(float); }
  /// read_raw + decode into `values` (step_floats() entries).
  void read(std::size_t step, std::span<float> values) const { decode(read_raw(step), values); }
};

}  // namespace orthofront::io
