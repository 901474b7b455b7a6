#pragma once
/// An unstructured mesh of linear cells (tetrahedra, pyramids, wedges, hexahedra) in VTK's
/// point order, with the face neighbours a point walk steps through. Readers in io/ produce it
/// (polyhedra arrive decomposed); mesh fields in lib/ interpolate point data on it.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "orthofront/field/cell_shape.h"
#include "orthofront/types.h"

namespace orthofront {

struct UnstructuredMesh {
  std::vector<double> points;                ///< x, y, z per point
  std::vector<CellShape> shapes;             ///< one per cell
  std::vector<std::int64_t> offsets{0};      ///< cell c's points: connectivity[offsets[c] ..)
  std::vector<std::int32_t> connectivity;    ///< point indices

  std::size_t point_count() const { return points.size() / 3; }
  std::size_t cell_count() const { return shapes.size(); }
  /// Appends a cell; `ids` holds cell::point_count(shape) point indices.
  void add_cell(CellShape shape, const std::int32_t* ids) {
    shapes.push_back(shape);
    connectivity.insert(connectivity.end(), ids, ids + cell::point_count(shape));
    offsets.push_back(static_cast<std::int64_t>(connectivity.size()));
  }
  const std::int32_t* cell_points(std::size_t c) const {
    return connectivity.data() + offsets[c];
  }
  /// The coordinates of cell c's points, in its order.
  void gather(std::size_t c, double (*p)[3]) const {
    const std::int32_t* ids = cell_points(c);
    for (int i = 0; i < cell::point_count(shapes[c]); ++i)
      for (int a = 0; a < 3; ++a) p[i][a] = points[3 * static_cast<std::size_t>(ids[i]) + a];
  }
  Box<3> bounds() const;
};

/// Checks sizes, point indices, finiteness and every cell's orientation. Throws InvalidArgument
/// naming `what` (a file, for messages), the first bad cell, its shape and the fault: an index out
/// of range, a repeated point, a non-finite coordinate, a map whose Jacobian vanishes or changes
/// sign at a corner (a degenerate or inverted cell). A cell whose every corner Jacobian is
/// negative is inside out (its points listed in the mirrored order); those are refused too, since
/// a reader that produced them read the faces the wrong way round.
void check_mesh(const UnstructuredMesh& mesh, const std::string& what);

/// The shape's name ("hexahedron", ...), for messages.
const char* shape_name(CellShape shape);

/// Face neighbours: neighbour(c, f) is the cell across face f of cell c (face numbering of
/// cell::face_points), or -1 on the boundary and where faces do not match point for point
/// (hanging nodes of refined meshes: a walk then falls back to the locator).
class CellNeighbours {
 public:
  explicit CellNeighbours(const UnstructuredMesh& mesh);
  std::int32_t neighbour(std::size_t c, int f) const { return across_[6 * c + static_cast<std::size_t>(f)]; }
  const std::int32_t* data() const { return across_.data(); }
  /// Faces with no neighbour (the mesh's boundary plus unmatched faces).
  std::size_t boundary_faces() const { return boundary_faces_; }

 private:
  std::vector<std::int32_t> across_;  // 6 per cell, -1 padded
  std::size_t boundary_faces_ = 0;
};

}  // namespace orthofront
