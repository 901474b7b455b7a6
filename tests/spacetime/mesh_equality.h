#pragma once
// Byte-for-byte equality of two meshes (positions, times and faces), for tests of "the same
// surface" across caches, backends and routes.
#include <cstring>

#include "orthofront/mesh/mesh.h"

namespace spacetime_test {

inline bool same_mesh(const orthofront::Mesh& a, const orthofront::Mesh& b) {
  if (a.vertex_count() != b.vertex_count() || a.faces.size() != b.faces.size()) return false;
  for (std::size_t i = 0; i < a.vertex_count(); ++i)
    if (std::memcmp(a.positions[i].data(), b.positions[i].data(), 3 * sizeof(double)) != 0 ||
        std::memcmp(&a.time[i], &b.time[i], sizeof(double)) != 0)
      return false;
  for (std::size_t f = 0; f < a.faces.size(); ++f)
    if (a.faces[f].v != b.faces[f].v) return false;
  return true;
}

}  // namespace spacetime_test
