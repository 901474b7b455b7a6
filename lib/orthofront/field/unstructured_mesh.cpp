#include "orthofront/field/unstructured_mesh.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <mutex>

#include "orthofront/error.h"

namespace orthofront {

const char* shape_name(CellShape shape) {
  switch (shape) {
    case CellShape::tetrahedron: return "tetrahedron";
    case CellShape::pyramid: return "pyramid";
    case CellShape::wedge: return "wedge";
    case CellShape::hexahedron: return "hexahedron";
  }
  return "cell";
}

Box<3> UnstructuredMesh::bounds() const {
  Box<3> b;
  b.lo.setConstant(std::numeric_limits<double>::infinity());
  b.hi.setConstant(-std::numeric_limits<double>::infinity());
  for (std::size_t i = 0; i < point_count(); ++i)
    for (int a = 0; a < 3; ++a) {
      b.lo[a] = std::min(b.lo[a], points[3 * i + static_cast<std::size_t>(a)]);
      b.hi[a] = std::max(b.hi[a], points[3 * i + static_cast<std::size_t>(a)]);
    }
  return b;
}

namespace {

// Where the orientation of a cell is checked: the parametric corners (the pyramid's apex, where
// the map is singular by construction, replaced by a point just below it) and the centre.
int orientation_probes(CellShape shape, double xi[9][3]) {
  int n = 0;
  const auto add = [&](double r, double s, double t) {
    xi[n][0] = r, xi[n][1] = s, xi[n][2] = t, ++n;
  };
  switch (shape) {
    case CellShape::tetrahedron:
      add(0, 0, 0), add(1, 0, 0), add(0, 1, 0), add(0, 0, 1);
      break;
    case CellShape::pyramid:
      add(0, 0, 0), add(1, 0, 0), add(1, 1, 0), add(0, 1, 0), add(0.5, 0.5, 0.9);
      break;
    case CellShape::wedge:
      for (double t : {0.0, 1.0}) add(0, 0, t), add(1, 0, t), add(0, 1, t);
      break;
    case CellShape::hexahedron:
      for (double t : {0.0, 1.0})
        for (double s : {0.0, 1.0})
          for (double r : {0.0, 1.0}) add(r, s, t);
      break;
  }
  cell::centre(shape, xi[n]);
  return n + 1;
}

// VTK orders a wedge's first triangle with its normal pointing away from the second, so its
// map's Jacobian is negative where every other shape's is positive.
double expected_sign(CellShape shape) { return shape == CellShape::wedge ? -1.0 : 1.0; }

}  // namespace

void check_mesh(const UnstructuredMesh& mesh, const std::string& what) {
  const std::size_t cells = mesh.cell_count();
  if (mesh.points.size() % 3 != 0)
    throw InvalidArgument(what + ": " + std::to_string(mesh.points.size()) +
                          " point coordinates, not a multiple of 3");
  if (mesh.offsets.size() != cells + 1 || mesh.offsets.front() != 0 ||
      mesh.offsets.back() != static_cast<std::int64_t>(mesh.connectivity.size()))
    throw InvalidArgument(what + ": cell offsets do not match the cells and their points");
  if (cells == 0) throw InvalidArgument(what + ": the mesh has no cells");
  if (mesh.point_count() > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max()))
    throw InvalidArgument(what + ": more than 2^31 points");
  for (std::size_t i = 0; i < mesh.points.size(); ++i)
    if (!std::isfinite(mesh.points[i]))
      throw InvalidArgument(what + ": point " + std::to_string(i / 3) +
                            " has a non-finite coordinate");

  // The first bad cell (lowest index) is reported, whichever thread finds it.
  std::atomic<std::size_t> first_bad{cells};
  std::string reason;
  std::mutex lock;
  const auto fail = [&](std::size_t c, std::string why) {
    const std::lock_guard<std::mutex> hold(lock);
    if (c < first_bad.load()) {
      first_bad = c;
      reason = std::move(why);
    }
  };
  tbb::parallel_for(std::size_t{0}, cells, [&](std::size_t c) {
    if (c > first_bad.load(std::memory_order_relaxed)) return;
    const CellShape shape = mesh.shapes[c];
    const int n = cell::point_count(shape);
    if (mesh.offsets[c + 1] - mesh.offsets[c] != n)
      return fail(c, std::to_string(mesh.offsets[c + 1] - mesh.offsets[c]) + " points, not " +
                         std::to_string(n));
    const std::int32_t* ids = mesh.cell_points(c);
    for (int i = 0; i < n; ++i) {
      if (ids[i] < 0 || static_cast<std::size_t>(ids[i]) >= mesh.point_count())
        return fail(c, "point index " + std::to_string(ids[i]) + " is out of range");
      for (int j = 0; j < i; ++j)
        if (ids[j] == ids[i]) return fail(c, "point " + std::to_string(ids[i]) + " repeats");
    }
    double p[8][3];
    mesh.gather(c, p);
    double xi[9][3];
    const int probes = orientation_probes(shape, xi);
    double scale = 0;
    for (int i = 1; i < n; ++i)
      for (int a = 0; a < 3; ++a) scale = std::max(scale, std::fabs(p[i][a] - p[0][a]));
    const double tiny = 1e-12 * scale * scale * scale;
    for (int k = 0; k < probes; ++k) {
      double x[3], A[3][3];
      cell::map_point(shape, p, xi[k], x, A);
      const double det = cell::determinant(A) * expected_sign(shape);
      if (!(std::fabs(det) > tiny)) return fail(c, "is degenerate (zero volume at a corner)");
      if (det < 0) return fail(c, "is inverted (its points are in the mirrored order or it folds)");
    }
  });
  if (first_bad.load() < cells) {
    const std::size_t c = first_bad.load();
    throw InvalidArgument(what + ": cell " + std::to_string(c) + " (" +
                          shape_name(mesh.shapes[c]) + ") " + reason);
  }
}

CellNeighbours::CellNeighbours(const UnstructuredMesh& mesh) {
  const std::size_t cells = mesh.cell_count();
  across_.assign(6 * cells, -1);
  // Every face as its sorted point ids (-1 padded for triangles) and its (cell, face); matching
  // faces sort next to each other.
  struct FaceKey {
    std::array<std::int32_t, 4> ids;
    std::int64_t where;  // 8 * cell + face
    bool operator<(const FaceKey& o) const {
      return ids != o.ids ? ids < o.ids : where < o.where;
    }
  };
  std::vector<std::int64_t> first(cells + 1, 0);
  for (std::size_t c = 0; c < cells; ++c)
    first[c + 1] = first[c] + cell::face_count(mesh.shapes[c]);
  std::vector<FaceKey> faces(static_cast<std::size_t>(first[cells]));
  tbb::parallel_for(std::size_t{0}, cells, [&](std::size_t c) {
    const std::int32_t* ids = mesh.cell_points(c);
    for (int f = 0; f < cell::face_count(mesh.shapes[c]); ++f) {
      int local[4];
      const int n = cell::face_points(mesh.shapes[c], f, local);
      FaceKey& k = faces[static_cast<std::size_t>(first[c] + f)];
      k.ids = {-1, -1, -1, -1};
      for (int i = 0; i < n; ++i) k.ids[static_cast<std::size_t>(i)] = ids[local[i]];
      std::sort(k.ids.begin(), k.ids.begin() + n);
      k.where = 8 * static_cast<std::int64_t>(c) + f;
    }
  });
  tbb::parallel_sort(faces.begin(), faces.end());
  std::size_t unmatched = 0;
  for (std::size_t i = 0; i < faces.size();) {
    std::size_t j = i + 1;
    while (j < faces.size() && faces[j].ids == faces[i].ids) ++j;
    if (j - i == 2) {
      const std::int64_t a = faces[i].where, b = faces[i + 1].where;
      across_[6 * static_cast<std::size_t>(a / 8) + static_cast<std::size_t>(a % 8)] =
          static_cast<std::int32_t>(b / 8);
      across_[6 * static_cast<std::size_t>(b / 8) + static_cast<std::size_t>(b % 8)] =
          static_cast<std::int32_t>(a / 8);
    } else {
      unmatched += j - i;  // a boundary face, or a face shared by more than two cells
    }
    i = j;
  }
  boundary_faces_ = unmatched;
}

}  // namespace orthofront
