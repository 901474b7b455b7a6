#pragma once
/// A steady field sampled straight from a sparse OpenVDB vector grid (no dense copy).
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>

#include "orthofront/field/field.h"
#include "orthofront/field/grid.h"

namespace orthofront::io {

/// v(x) from a Vec3f / Vec3d OpenVDB grid (or three scalar grids), in world space.
///
/// - Values: OpenVDB's trilinear reconstruction (tools::BoxSampler::trilinearInterpolation on the
///   8 voxels around the index-space point, in double precision); staggered grids
///   (GRID_STAGGERED) per component at the half-voxel-shifted point, as
///   tools::StaggeredBoxSampler does. Linear fields are reproduced exactly up to the float
///   rounding of the voxels.
/// - Jacobian: the exact derivative of that trilinear cell (not finite differences), mapped to
///   world space by the inverse of the grid's linear transform (rotations and non-uniform voxels
///   included).
/// - Status: `outside` beyond the box of active voxels (joined with the box the grid was written
///   with, for files orthofront wrote); `no_data` when one of the 8 voxels is inactive or NaN, so
///   sparse domains work. A point on the last voxel layer belongs to the last cell.
/// - Single-layer grids (one voxel thick in z) are planar: bilinear in x and y, independent of z,
///   with a domain of ± half the larger x/y extent around the layer.
/// - 2-component grids (written from a 2-component VectorGrid): v_z = 0.
///
/// Immutable and thread-safe (an unregistered accessor per evaluation). The OpenVDB module
/// (vdb_module.h) makes it: this is its interface.
class VdbField : public Field3 {
 public:
  /// Reads the grid `selector` of `path` ("NAME", "X,Y,Z" scalar grids, or empty: the first vector
  /// grid). Throws IoError / FormatError naming the file and the grid.
  static std::unique_ptr<VdbField> open(const std::filesystem::path& path,
                                        const std::string& selector = {});
  /// From samples in memory (NaN → inactive), e.g. for tests. Throws InvalidArgument for
  /// rectilinear grids.
  static std::unique_ptr<VdbField> from_grid(const VectorGrid& grid, const std::string& name = "velocity");

  virtual bool staggered() const = 0;
  virtual const std::string& grid_name() const = 0;
  virtual std::uint64_t active_voxels() const = 0;
};

}  // namespace orthofront::io
