#pragma once
/// Point location in an unstructured mesh: a two-level grid of uniform bins (the scheme of
/// Viskores' CellLocatorTwoLevel: coarse bins over the mesh, each split into as many leaf bins as
/// its cell count asks for, each leaf listing the cells whose bounding boxes touch it) and a walk
/// across faces from a cell the caller already knows (a particle's last cell: particles move a
/// fraction of a cell per step, so the walk usually ends where it starts or next door).
///
/// The queries are one body for the CPU and CUDA (ORTHOFRONT_HD, plain arrays in a
/// CellLocatorView); the build runs on TBB, deterministically (the same mesh gives the same bins
/// and the same answers, whatever the thread count).
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "orthofront/advect/host_device.h"
#include "orthofront/field/cell_shape.h"
#include "orthofront/field/unstructured_mesh.h"

namespace orthofront {

/// Parametric slack of "inside a cell": points on a face shared by two cells belong to both, and
/// the first found wins; rounding must not leave a gap between them.
inline constexpr double kInsideSlack = 1e-9;

/// Everything a query reads, as raw pointers into a CellLocator and its mesh (valid while both
/// live; copyable to a device as is once the arrays are).
struct CellLocatorView {
  const double* points = nullptr;
  const std::int32_t* connectivity = nullptr;
  const std::int64_t* offsets = nullptr;
  const CellShape* shapes = nullptr;
  const std::int32_t* neighbours = nullptr;  // 6 per cell, -1 where none
  double origin[3] = {0, 0, 0};              // lower corner of the top-level grid
  double bin[3] = {1, 1, 1};                 // top-level bin size per axis
  int top[3] = {1, 1, 1};                    // top-level bins per axis
  const std::int32_t* leaf_dims = nullptr;   // 3 per top-level bin
  const std::int64_t* leaf_first = nullptr;  // first leaf of each top-level bin
  const std::int64_t* leaf_cells_first = nullptr;  // per leaf, into leaf_cells; leaves + 1
  const std::int32_t* leaf_cells = nullptr;
};

namespace locate {

/// Whether x lies in cell c (within kInsideSlack); ξ gets its parametric coordinates either way
/// (the last Newton iterate when the map could not be inverted). `face` gets the face a walk
/// should leave through when x is outside.
ORTHOFRONT_HD inline bool in_cell(const CellLocatorView& m, std::int32_t c, const double x[3],
                                  double xi[3], int& face) {
  const CellShape shape = m.shapes[c];
  const std::int32_t* ids = m.connectivity + m.offsets[c];
  double p[8][3];
  for (int i = 0; i < cell::point_count(shape); ++i)
    for (int a = 0; a < 3; ++a) p[i][a] = m.points[3 * static_cast<std::int64_t>(ids[i]) + a];
  const bool converged = cell::invert(shape, p, x, xi);
  double violation;
  face = cell::outside_face(shape, xi, violation);
  return converged && violation <= kInsideSlack;
}

/// The cell containing x found through the bins, or -1 when no cell does.
ORTHOFRONT_HD inline std::int32_t find_cell(const CellLocatorView& m, const double x[3],
                                            double xi[3]) {
  int b[3];
  double local[3];
  for (int a = 0; a < 3; ++a) {
    const double u = (x[a] - m.origin[a]) / m.bin[a];
    if (!(u >= 0) || u > m.top[a]) return -1;  // outside the mesh's box, or NaN
    b[a] = u >= m.top[a] ? m.top[a] - 1 : static_cast<int>(u);
    local[a] = u - b[a];
  }
  const std::int64_t top = b[0] + static_cast<std::int64_t>(m.top[0]) * (b[1] + static_cast<std::int64_t>(m.top[1]) * b[2]);
  const std::int32_t* d = m.leaf_dims + 3 * top;
  int l[3];
  for (int a = 0; a < 3; ++a) {
    l[a] = static_cast<int>(local[a] * d[a]);
    if (l[a] >= d[a]) l[a] = d[a] - 1;
  }
  const std::int64_t leaf =
      m.leaf_first[top] + l[0] + static_cast<std::int64_t>(d[0]) * (l[1] + static_cast<std::int64_t>(d[1]) * l[2]);
  for (std::int64_t k = m.leaf_cells_first[leaf]; k < m.leaf_cells_first[leaf + 1]; ++k) {
    int face;
    if (in_cell(m, m.leaf_cells[k], x, xi, face)) return m.leaf_cells[k];
  }
  return -1;
}

/// Walks from cell `start` towards x across faces, at most `steps` cells. Returns the cell
/// containing x, or -1 when the walk reaches a face without a neighbour (the boundary, or a
/// face that does not match) or runs out of steps: the caller then asks the bins.
ORTHOFRONT_HD inline std::int32_t walk(const CellLocatorView& m, std::int32_t start,
                                       const double x[3], double xi[3], int steps = 32) {
  std::int32_t c = start;
  for (int k = 0; k < steps; ++k) {
    int face;
    if (in_cell(m, c, x, xi, face)) return c;
    const std::int32_t next = m.neighbours[6 * static_cast<std::int64_t>(c) + face];
    if (next < 0) return -1;
    c = next;
  }
  return -1;
}

/// The cell containing x: by a walk from `hint` when it is a cell, else (or when the walk gives
/// up) through the bins; -1 outside the mesh.
ORTHOFRONT_HD inline std::int32_t cell_of(const CellLocatorView& m, const double x[3],
                                          std::int32_t hint, double xi[3]) {
  if (hint >= 0) {
    const std::int32_t c = walk(m, hint, x, xi);
    if (c >= 0) return c;
  }
  return find_cell(m, x, xi);
}

}  // namespace locate

/// Owns the bins of a mesh and its face neighbours. Immutable after construction, thread-safe.
class CellLocator {
 public:
  struct Options {
    double cells_per_top_bin = 32;  ///< Viskores' density of the first level
    double cells_per_leaf = 2;      ///< and of the second
  };
  /// Non-owning: `mesh` must outlive the locator and stay unchanged.
  explicit CellLocator(const UnstructuredMesh& mesh) : CellLocator(mesh, Options{}) {}
  CellLocator(const UnstructuredMesh& mesh, const Options& options);

  const CellLocatorView& view() const { return view_; }
  const CellNeighbours& neighbours() const { return neighbours_; }
  /// Leaf bins and their cell references, for benchmarks.
  std::size_t leaf_count() const { return leaf_cells_first_.size() - 1; }
  std::size_t bytes() const;

 private:
  CellNeighbours neighbours_;
  std::vector<std::int32_t> leaf_dims_;
  std::vector<std::int64_t> leaf_first_;
  std::vector<std::int64_t> leaf_cells_first_;
  std::vector<std::int32_t> leaf_cells_;
  CellLocatorView view_;
};

}  // namespace orthofront
