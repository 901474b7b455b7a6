#pragma once
/// Sampling any field onto a uniform grid: analytic fields become grid data (tests, benchmarks,
/// `orthofront generate`).
#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "orthofront/field/field.h"
#include "orthofront/field/grid.h"

namespace orthofront {

struct SampleOptions {
  /// Samples per axis, each >= 2, except resolution[2] == 1: a 2D grid in the plane through the
  /// middle of the box's z range.
  std::array<std::int64_t, 3> resolution{64, 64, 64};
  /// Region sampled (first and last sample on its faces); default: the field's domain.
  std::optional<Box<3>> box;
  /// Floats per point: 2 or 3; 0 chooses 3, or 2 for a 2D grid whose v_z is 0 at every sample.
  int components = 0;
};

/// The uniform geometry SampleOptions describe: origin = box.lo, spacing = extent / (n - 1).
/// Throws InvalidArgument for a resolution below 2 (1 on z only), an empty or non-finite box.
GridGeometry sampling_geometry(const SampleOptions& options, const Box<3>& field_domain);

/// Samples `field` at every point of `geometry` (a uniform or rectilinear grid) into `values`
/// (point_count() * components floats, x fastest); NaN where the field is not `inside`. Sample
/// points are clamped into the geometry's bounds so that rounding in origin + i * spacing never
/// puts the last sample outside the field's domain. Parallel over rows (oneTBB). Throws
/// InvalidArgument when the sizes do not match or components is not 2 or 3.
void sample_field_into(const Field3& field, const GridGeometry& geometry, int components,
                       std::span<float> values);

/// Samples `field` onto the grid of `options` (see SampleOptions).
VectorGrid sample_field(const Field3& field, const SampleOptions& options = {});

}  // namespace orthofront
