#pragma once
// Unstructured test meshes over a box: hexahedra, each cube split into six tetrahedra (Kuhn's
// subdivision, conforming across cubes), and a mixed mesh of all four shapes; interior points
// jittered so that no cell is a parallelepiped.
#include <array>
#include <cstdint>
#include <random>
#include <vector>

#include "orthofront/field/cell_shape.h"
#include "orthofront/field/unstructured_mesh.h"

namespace orthofront::test_support {

enum class BoxCells { hexahedra, tetrahedra, mixed };

// n[a] cells along each axis of [lo, hi]; interior points moved by up to `jitter` cell widths.
inline UnstructuredMesh box_mesh(const Vec3& lo, const Vec3& hi, std::array<int, 3> n,
                                 BoxCells kind, double jitter = 0, unsigned seed = 1) {
  UnstructuredMesh m;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> wobble(-jitter, jitter);
  const auto id = [&](int i, int j, int k) {
    return static_cast<std::int32_t>(i + (n[0] + 1) * (j + (n[1] + 1) * k));
  };
  for (int k = 0; k <= n[2]; ++k)
    for (int j = 0; j <= n[1]; ++j)
      for (int i = 0; i <= n[0]; ++i) {
        const int ijk[3] = {i, j, k};
        for (int a = 0; a < 3; ++a) {
          const double h = (hi[a] - lo[a]) / n[static_cast<std::size_t>(a)];
          const bool interior = ijk[a] > 0 && ijk[a] < n[static_cast<std::size_t>(a)];
          m.points.push_back(lo[a] + h * (ijk[a] + (interior ? wobble(rng) : 0.0)));
        }
      }
  // A cube's corners in VTK hexahedron order.
  const auto corners = [&](int i, int j, int k, std::int32_t c[8]) {
    const int d[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                         {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
    for (int q = 0; q < 8; ++q) c[q] = id(i + d[q][0], j + d[q][1], k + d[q][2]);
  };
  const auto add_tet = [&](std::int32_t a, std::int32_t b, std::int32_t c, std::int32_t d) {
    // Ordered so that (a, b, c) faces d (VTK's orientation).
    const auto p = [&](std::int32_t q) {
      return Vec3(m.points[3 * static_cast<std::size_t>(q)], m.points[3 * static_cast<std::size_t>(q) + 1],
                  m.points[3 * static_cast<std::size_t>(q) + 2]);
    };
    const double det = (p(b) - p(a)).cross(p(c) - p(a)).dot(p(d) - p(a));
    const std::int32_t ids[4] = {a, det > 0 ? b : c, det > 0 ? c : b, d};
    m.add_cell(CellShape::tetrahedron, ids);
  };
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i) {
        std::int32_t c[8];
        corners(i, j, k, c);
        BoxCells cube = kind;
        if (kind == BoxCells::mixed) cube = (i + j + k) % 3 == 0 ? BoxCells::tetrahedra : BoxCells::hexahedra;
        if (kind == BoxCells::mixed && (i + 2 * j + k) % 5 == 1) {
          // Two wedges sharing the cube's diagonal plane through edges 0-4 and 2-6: the cut
          // faces (bottom and top) become triangles, so these cubes do not match their
          // neighbours face for face there (the walk falls back to the bins).
          const std::int32_t w1[6] = {c[0], c[1], c[2], c[4], c[5], c[6]};
          const std::int32_t w2[6] = {c[0], c[2], c[3], c[4], c[6], c[7]};
          // VTK wedges list the first triangle with its normal away from the second.
          const std::int32_t w1v[6] = {w1[0], w1[2], w1[1], w1[3], w1[5], w1[4]};
          const std::int32_t w2v[6] = {w2[0], w2[2], w2[1], w2[3], w2[5], w2[4]};
          m.add_cell(CellShape::wedge, w1v);
          m.add_cell(CellShape::wedge, w2v);
          continue;
        }
        if (kind == BoxCells::mixed && (i + j + 2 * k) % 7 == 3) {
          // Six pyramids, one a face, their apex at a new point at the cube's centre.
          Vec3 centre = Vec3::Zero();
          for (int q = 0; q < 8; ++q)
            for (int a = 0; a < 3; ++a) centre[a] += m.points[3 * static_cast<std::size_t>(c[q]) + static_cast<std::size_t>(a)] / 8;
          const auto apex = static_cast<std::int32_t>(m.point_count());
          for (int a = 0; a < 3; ++a) m.points.push_back(centre[a]);
          // Faces listed with their normal pointing into the cube (towards the apex).
          const int faces[6][4] = {{0, 1, 2, 3}, {4, 7, 6, 5}, {0, 4, 5, 1},
                                   {3, 2, 6, 7}, {0, 3, 7, 4}, {1, 5, 6, 2}};
          for (const auto& f : faces) {
            const std::int32_t ids[5] = {c[f[0]], c[f[1]], c[f[2]], c[f[3]], apex};
            m.add_cell(CellShape::pyramid, ids);
          }
          continue;
        }
        if (cube == BoxCells::hexahedra) {
          m.add_cell(CellShape::hexahedron, c);
          continue;
        }
        // Kuhn: one tetrahedron per order of the axes, along the path 000 → 111.
        const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
        for (const auto& p : perms) {
          int at[3] = {0, 0, 0};
          std::int32_t path[4];
          path[0] = id(i, j, k);
          for (int s = 0; s < 3; ++s) {
            at[p[s]] = 1;
            path[s + 1] = id(i + at[0], j + at[1], k + at[2]);
          }
          add_tet(path[0], path[1], path[2], path[3]);
        }
      }
  return m;
}

}  // namespace orthofront::test_support
