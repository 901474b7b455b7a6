#include "orthofront/engine/fold_guard.h"

#include <algorithm>

namespace orthofront {

namespace {

std::uint64_t edge_key(std::int32_t a, std::int32_t b) {
  const auto lo = static_cast<std::uint64_t>(std::min(a, b));
  const auto hi = static_cast<std::uint64_t>(std::max(a, b));
  return lo << 32 | hi;
}

/// Unit normal of a face; zero for a face without area (no orientation to compare).
Vec3 unit_normal(const Mesh& mesh, const Face& face) {
  const Vec3 area = area_vector(mesh, face);
  const double norm = area.norm();
  return norm > 0 ? Vec3(area / norm) : Vec3::Zero();
}

/// Calls visit(a, b) for each edge of a face that joins two different vertices.
template <class Visit>
void for_each_edge(const Face& face, Visit&& visit) {
  for (std::size_t k = 0; k < face.size; ++k) {
    const std::int32_t a = face.v[k], b = face.v[(k + 1) % face.size];
    if (a != b) visit(a, b);
  }
}

}  // namespace

void FoldGuard::rebuild(const Mesh& mesh) {
  open_.clear();
  accept(mesh, 0);
}

void FoldGuard::accept(const Mesh& mesh, std::size_t first_face) {
  for (std::size_t f = first_face; f < mesh.faces.size(); ++f)
    for_each_edge(mesh.faces[f], [&](std::int32_t a, std::int32_t b) {
      const auto [it, added] =
          open_.try_emplace(edge_key(a, b), EdgeFace{static_cast<std::uint32_t>(f), a < b});
      if (!added) open_.erase(it);  // its second face: inside the surface now
    });
}

std::vector<std::int32_t> FoldGuard::folded_vertices(const Mesh& mesh, std::size_t first_face,
                                                     std::size_t first_new_vertex) {
  std::vector<std::int32_t> out;
  const std::size_t end = mesh.faces.size();
  if (first_face >= end) return out;
  strip_.clear();
  for (std::size_t f = first_face; f < end; ++f)
    for_each_edge(mesh.faces[f], [&](std::int32_t a, std::int32_t b) {
      strip_.emplace(edge_key(a, b), EdgeFace{static_cast<std::uint32_t>(f), a < b});
    });
  const auto is_new = [&](std::int32_t v) {
    return v >= 0 && static_cast<std::size_t>(v) >= first_new_vertex;
  };
  for (std::size_t f = first_face; f < end; ++f) {
    const Face& face = mesh.faces[f];
    const Vec3 n0 = unit_normal(mesh, face);
    if (n0.squaredNorm() == 0) continue;
    for_each_edge(face, [&](std::int32_t a, std::int32_t b) {
      const std::uint64_t key = edge_key(a, b);
      const auto folds_over = [&](const EdgeFace& other) {
        if (other.face == f) return false;
        const Vec3 n1 = unit_normal(mesh, mesh.faces[other.face]);
        // Consistent neighbours walk the edge in opposite directions; undo a flip so that only
        // geometry decides, as the quality measure does.
        const double dot = other.forward == (a < b) ? -n0.dot(n1) : n0.dot(n1);
        return n1.squaredNorm() > 0 && dot < 0;
      };
      bool folded = false;
      const auto [lo, hi] = strip_.equal_range(key);
      for (auto it = lo; it != hi && !folded; ++it) folded = folds_over(it->second);
      if (const auto it = open_.find(key); !folded && it != open_.end())
        folded = folds_over(it->second);
      if (!folded) return;
      const std::size_t before = out.size();
      for (const std::int32_t v : {a, b})
        if (is_new(v)) out.push_back(v);
      if (out.size() == before)
        for (std::size_t c = 0; c < face.size; ++c)
          if (is_new(face.v[c])) out.push_back(face.v[c]);
    });
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

}  // namespace orthofront
