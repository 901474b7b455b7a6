#pragma once
/// Polygon surface mesh (quads and triangles kept as such) with per-vertex attributes.
#include <Eigen/Geometry>  // cross products
#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "orthofront/huge_pages.h"
#include "orthofront/types.h"

namespace orthofront {

/// One face: 3 or 4 vertex indices, counter-clockwise seen from the surface normal side.
struct Face {
  std::array<std::int32_t, 4> v{-1, -1, -1, -1};
  std::uint8_t size = 0;  ///< 3 (triangle) or 4 (quad)
  bool is_quad() const { return size == 4; }
  bool operator==(const Face&) const = default;
};

/// Surface mesh. Positions are 3D (for N = 4 engines: the first three coordinates).
/// All attribute arrays have one entry per vertex. The arrays grow on huge pages once large: a
/// surface of millions of vertices is built by push_back, and in 4 KiB pages its first writes
/// and each growth's copies fault every 4 KiB (half the stitch stage of a Lorenz run).
struct Mesh {
  template <class T>
  using Array = HugePageVector<T>;
  Array<Vec3> positions;                  ///< world units
  Array<Face> faces;
  Array<double> time;                     ///< integration time in v since the seed (or physical time)
  Array<double> alpha;                    ///< α used on the step that produced the vertex (0 on the seed)
  Array<double> s;                        ///< seed-curve parameter of the stream line, in [0, 1]
  Array<double> error;                    ///< orthogonality error |cos(front tangent, v)| at the vertex
  Array<std::int32_t> front_id;           ///< front the vertex belonged to when created
  Array<std::int32_t> step;               ///< front step that created the vertex (0 = seed)
  // Streak surfaces (empty elsewhere): each vertex is a particle released from the seed curve.
  Array<double> release_time;             ///< time the particle left the seed curve
  Array<double> age;                      ///< observation time - release_time
  Array<double> speed;                    ///< |v| at the vertex at the observation time
  Array<std::int32_t> particle_id;        ///< stable id of the particle across frames
  /// 1: the particle lies on the path of its label (release_time, s); 0: it was placed by
  /// interpolation, so its label is approximate. Empty where not recorded.
  Array<std::int32_t> on_path;
  /// What the mesh means, as (name, text) pairs: what it is, the data it came from, what its
  /// positions and times are in. Written where the format has room for them (.vtp field data).
  std::vector<std::pair<std::string, std::string>> notes;

  std::size_t vertex_count() const { return positions.size(); }
  std::size_t face_count() const { return faces.size(); }

  /// Appends a vertex with its attributes; returns its index.
  std::int32_t add_vertex(const Vec3& p, double t, double a, double s_param, double err,
                          std::int32_t front, std::int32_t step_index) {
    positions.push_back(p);
    time.push_back(t);
    alpha.push_back(a);
    s.push_back(s_param);
    error.push_back(err);
    front_id.push_back(front);
    step.push_back(step_index);
    return static_cast<std::int32_t>(positions.size() - 1);
  }
  void add_triangle(std::int32_t a, std::int32_t b, std::int32_t c) {
    faces.push_back(Face{{a, b, c, -1}, 3});
  }
  void add_quad(std::int32_t a, std::int32_t b, std::int32_t c, std::int32_t d) {
    faces.push_back(Face{{a, b, c, d}, 4});
  }
  /// Drops the vertices and faces added after there were `vertices` and `faces` (a step
  /// undone). Streak attributes are not touched (the engines that undo steps do not fill them).
  void truncate(std::size_t vertices, std::size_t kept_faces) {
    positions.resize(vertices);
    time.resize(vertices);
    alpha.resize(vertices);
    s.resize(vertices);
    error.resize(vertices);
    front_id.resize(vertices);
    step.resize(vertices);
    faces.resize(kept_faces);
  }
  /// Removes the vertices no face uses, keeping the others' order.
  void remove_unused_vertices() {
    std::vector<std::int32_t> index(positions.size(), -1);
    for (const Face& f : faces)
      for (std::size_t k = 0; k < f.size; ++k) index[static_cast<std::size_t>(f.v[k])] = 0;
    std::int32_t kept = 0;
    for (std::size_t v = 0; v < index.size(); ++v) {
      if (index[v] < 0) continue;
      const auto to = static_cast<std::size_t>(kept);
      index[v] = kept++;
      positions[to] = positions[v];
      time[to] = time[v];
      alpha[to] = alpha[v];
      s[to] = s[v];
      error[to] = error[v];
      front_id[to] = front_id[v];
      step[to] = step[v];
    }
    truncate(static_cast<std::size_t>(kept), faces.size());
    for (Face& f : faces)
      for (std::size_t k = 0; k < f.size; ++k) f.v[k] = index[static_cast<std::size_t>(f.v[k])];
  }
};

/// Area vector of a face (normal times area): half the cross product of the diagonals for a
/// quad, of two edges for a triangle.
/// (From the positions array itself: for a reader beside a thread that appends to the mesh.)
inline Vec3 area_vector(const Vec3* positions, const Face& face) {
  const auto at = [&](std::size_t k) -> const Vec3& {
    return positions[static_cast<std::size_t>(face.v[k])];
  };
  if (face.is_quad()) return 0.5 * (at(2) - at(0)).cross(at(3) - at(1));
  return 0.5 * (at(1) - at(0)).cross(at(2) - at(0));
}
inline Vec3 area_vector(const Mesh& mesh, const Face& face) {
  return area_vector(mesh.positions.data(), face);
}

/// Unit normal of a face; zero for a face without area (no orientation to compare).
inline Vec3 unit_normal(const Mesh& mesh, const Face& face) {
  const Vec3 area = area_vector(mesh, face);
  const double norm = area.norm();
  return norm > 0 ? Vec3(area / norm) : Vec3::Zero();
}

}  // namespace orthofront
