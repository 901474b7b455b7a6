#pragma once
/// A steady field that interpolates vector samples on a structured grid (uniform or
/// rectilinear, 2D or 3D): trilinear in 3D, bilinear in 2D, in double precision.
#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "orthofront/field/field.h"
#include "orthofront/field/grid.h"

namespace orthofront {

struct GridFieldOptions {
  /// A cell with a corner whose vector is exactly (0, 0, 0) has no data: real data marks land and
  /// solid cells that way. Turn it off for sampled analytic fields, whose zero vectors are genuine
  /// critical points. (A cell with a NaN corner has no data whatever this says.)
  bool zero_is_no_data = true;
  /// 2D grids only: the field does not depend on z, and its domain spans
  /// z_plane ± slab_half_thickness, where z_plane is the grid's z coordinate (origin.z, or
  /// axes[2][0] for rectilinear grids). 0 selects half the larger of the x and y extents, so the
  /// domain box has the proportions of the data and seeds may be tilted out of the plane.
  double slab_half_thickness = 0;
};

/// v(x) interpolated from a VectorGrid.
///
/// - Cell lookup: by division for uniform grids, by binary search for rectilinear ones. A point on
///   the last sample of an axis belongs to the last cell.
/// - Values: multilinear interpolation of the cell's 8 (3D) or 4 (2D) corners; J is the exact
///   derivative of that interpolant inside the cell, so linear fields are reproduced exactly
///   (values and Jacobian) up to the float rounding of the samples.
/// - Status: `outside` beyond the grid's bounds; `no_data` in a cell with a NaN corner (or a zero
///   corner, see GridFieldOptions), so NaN never reaches a caller.
/// - 2 components: v_z = 0 (and the last row of J is 0). 2D grids: v and J do not depend on z
///   (the last column of J is 0); see GridFieldOptions::slab_half_thickness for the domain.
///
/// Shares its grid; immutable and thread-safe; no allocation per evaluation.
class GridField final : public Field3 {
 public:
  /// Throws InvalidArgument naming the first inconsistency: dimension not 2 or 3, components not
  /// 2 or 3, fewer than two samples on an axis of the grid, a value count that does not match,
  /// non-positive or non-finite spacing, axis coordinates that do not increase strictly.
  explicit GridField(std::shared_ptr<const VectorGrid> grid, const GridFieldOptions& options = {});

  FieldStatus velocity(const Vec3& x, Vec3& v) const override;
  FieldStatus velocity_jacobian(const Vec3& x, Vec3& v, Mat3& J) const override;
  Box<3> domain() const override { return domain_; }
  std::string describe() const override;
  /// The cell faces inside the grid (the interpolant is smooth within a cell only).
  double next_kink(const Vec3& x, const Vec3& w, double after, double before) const override;

  const VectorGrid& grid() const { return *grid_; }
  const std::shared_ptr<const VectorGrid>& shared_grid() const { return grid_; }
  const GridFieldOptions& options() const { return options_; }

 private:
  // The evaluation, compiled once per kind of grid (2D/3D, 2/3 components, uniform/rectilinear)
  // so that the per-axis and per-component loops unroll.
  template <int Axes, int Components, bool Rectilinear, bool WithJacobian>
  FieldStatus evaluate(const Vec3& x, Vec3& v, Mat3* J) const;
  template <bool WithJacobian>
  FieldStatus dispatch(const Vec3& x, Vec3& v, Mat3* J) const;
  // Marks the cells with a non-finite corner (or a zero corner, see the options).
  void build_no_data_mask();

  std::shared_ptr<const VectorGrid> grid_;
  GridFieldOptions options_;
  Box<3> domain_;
  int axes_ = 3;  // axes interpolated: the grid's dimension
  int components_ = 3;
  int kind_ = 0;  // 4 * (axes == 3) + 2 * (components == 3) + rectilinear
  const float* values_ = nullptr;
  std::array<std::int64_t, 3> cells_{};       // cells per axis (0 on the z axis of 2D grids)
  std::array<std::size_t, 3> stride_{};       // floats between neighbours along each axis
  std::array<std::size_t, 3> cell_stride_{};  // cell index step along each axis
  bool rectilinear_ = false;
  std::array<double, 3> origin_{};                    // uniform: first sample; rectilinear: unused
  std::array<double, 3> inverse_spacing_{};           // uniform
  std::array<std::vector<double>, 3> inverse_width_;  // rectilinear: 1 / cell width per cell
  std::vector<std::uint64_t> no_data_cells_;          // a bit per cell; empty: every cell has data
};

}  // namespace orthofront
