#include "orthofront/mesh/close_gaps.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <unordered_map>
#include <vector>

namespace orthofront {

namespace {

constexpr std::int32_t kNone = -1;
constexpr std::int32_t kAmbiguous = -2;  ///< a pinch: more than one boundary edge leaves or enters

/// The mesh's boundary as chains of vertices: each boundary edge a → b runs as its one face
/// walks it, so a chain walks the boundary with the surface on the same side throughout. The
/// per-vertex figures are kept for boundary vertices only, at their slot (their place in
/// `vertices`): arrays over every vertex of a large surface cost more in first touches of fresh
/// memory (page faults) than the whole search.
struct Boundary {
  std::vector<std::int32_t> vertices;  ///< every vertex on a boundary edge, in index order
  std::vector<std::int32_t> next, prev;  ///< boundary successor / predecessor (vertex ids)
  std::vector<std::int32_t> owner;       ///< the face of the edge v → next(v)
  std::vector<std::int32_t> chain, index;  ///< chain of a vertex and its place there (-1: none)
  std::vector<double> arc;                 ///< arc length from the chain's first vertex
  std::vector<std::vector<std::int32_t>> chains;
  std::vector<char> closed;
  std::vector<double> length;  ///< a chain's length (with the closing edge when closed)

  /// A boundary vertex's slot.
  std::size_t slot(std::int32_t v) const {
    return static_cast<std::size_t>(std::lower_bound(vertices.begin(), vertices.end(), v) -
                                    vertices.begin());
  }
};

Boundary find_boundary(const Mesh& mesh, const std::vector<BoundaryEdge>& edges) {
  Boundary bd;
  std::vector<std::int32_t>& vertices = bd.vertices;
  vertices.reserve(2 * edges.size());
  for (const BoundaryEdge& e : edges) {
    vertices.push_back(e.from);
    vertices.push_back(e.to);
  }
  std::sort(vertices.begin(), vertices.end());
  vertices.erase(std::unique(vertices.begin(), vertices.end()), vertices.end());
  const std::size_t nb = vertices.size();
  bd.next.assign(nb, kNone);
  bd.prev.assign(nb, kNone);
  bd.owner.assign(nb, kNone);
  for (const BoundaryEdge& e : edges) {
    const std::size_t ua = bd.slot(e.from), ub = bd.slot(e.to);
    bd.next[ua] = bd.next[ua] == kNone ? e.to : kAmbiguous;
    bd.prev[ub] = bd.prev[ub] == kNone ? e.from : kAmbiguous;
    bd.owner[ua] = bd.next[ua] == kAmbiguous ? kNone : e.face;
  }
  // Chains are numbered in vertex order, whatever order the edges came in (a pinch vertex, with
  // two edges out or in, ends its chains and takes part in no gap).
  bd.chain.assign(nb, -1);
  bd.index.assign(nb, -1);
  bd.arc.assign(nb, 0.0);
  const auto usable = [&](std::size_t u) { return bd.next[u] >= 0; };  // u: a slot
  const auto walk = [&](std::int32_t start) {
    const auto id = static_cast<std::int32_t>(bd.chains.size());
    std::vector<std::int32_t> chain;
    double s = 0;
    std::int32_t v = start;
    bool closed = false;
    while (true) {
      const std::size_t uv = bd.slot(v);
      bd.chain[uv] = id;
      bd.index[uv] = static_cast<std::int32_t>(chain.size());
      bd.arc[uv] = s;
      chain.push_back(v);
      const std::int32_t w = bd.next[uv];
      if (w < 0) break;
      s += (mesh.positions[static_cast<std::size_t>(w)] -
            mesh.positions[static_cast<std::size_t>(v)])
               .norm();
      if (w == start) {
        closed = true;
        break;
      }
      const std::size_t uw = bd.slot(w);
      if (bd.chain[uw] >= 0 || bd.prev[uw] < 0) break;  // runs into a pinch: the chain ends here
      if (!usable(uw)) {  // the chain's last vertex has no successor
        bd.chain[uw] = id;
        bd.index[uw] = static_cast<std::int32_t>(chain.size());
        bd.arc[uw] = s;
        chain.push_back(w);
        break;
      }
      v = w;
    }
    bd.chains.push_back(std::move(chain));
    bd.closed.push_back(closed);
    bd.length.push_back(s);
  };
  // Open chains first (from vertices without a single predecessor), then the closed loops.
  for (std::size_t u = 0; u < nb; ++u)
    if (usable(u) && bd.prev[u] < 0 && bd.chain[u] < 0) walk(vertices[u]);
  for (std::size_t u = 0; u < nb; ++u)
    if (usable(u) && bd.chain[u] < 0) walk(vertices[u]);
  return bd;
}

Face make_face(std::array<std::int32_t, 4> ids, int count) {
  Face f;
  for (int k = 0; k < count; ++k) {
    const std::int32_t id = ids[static_cast<std::size_t>(k)];
    bool seen = false;
    for (int l = 0; l < f.size; ++l) seen = seen || f.v[static_cast<std::size_t>(l)] == id;
    if (!seen) f.v[f.size++] = id;
  }
  return f;
}

}  // namespace

std::vector<BoundaryEdge> boundary_edges(const Mesh& mesh) {
  const std::size_t nv = mesh.vertex_count();
  // Face edges bucketed by their lower vertex (a counting sort, O(V + F)); an edge that occurs
  // once in its bucket is a boundary edge.
  std::vector<std::uint32_t> bucket(nv + 1, 0);
  for (const Face& face : mesh.faces)
    for (std::size_t k = 0; k < face.size; ++k) {
      const std::int32_t a = face.v[k], b = face.v[(k + 1) % face.size];
      if (a != b) ++bucket[static_cast<std::size_t>(std::min(a, b)) + 1];
    }
  for (std::size_t v = 0; v < nv; ++v) bucket[v + 1] += bucket[v];
  std::vector<BoundaryEdge> uses(bucket[nv]);
  std::vector<std::uint32_t> fill(bucket.begin(), bucket.end() - 1);
  for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
    const Face& face = mesh.faces[f];
    for (std::size_t k = 0; k < face.size; ++k) {
      const std::int32_t a = face.v[k], b = face.v[(k + 1) % face.size];
      if (a != b)
        uses[fill[static_cast<std::size_t>(std::min(a, b))]++] =
            BoundaryEdge{a, b, static_cast<std::int32_t>(f)};
    }
  }
  std::vector<BoundaryEdge> out;
  for (std::size_t lo = 0; lo < nv; ++lo)
    for (std::uint32_t u = bucket[lo]; u < bucket[lo + 1]; ++u) {
      const std::int32_t hi = std::max(uses[u].from, uses[u].to);
      std::size_t twins = 0;
      for (std::uint32_t w = bucket[lo]; w < bucket[lo + 1]; ++w)
        twins += std::max(uses[w].from, uses[w].to) == hi ? 1 : 0;
      if (twins == 1) out.push_back(uses[u]);
    }
  return out;
}

GapReport close_gaps(Mesh& mesh, double distance, double min_length) {
  return close_gaps(mesh, distance, min_length, boundary_edges(mesh));
}

GapReport close_gaps(Mesh& mesh, double distance, double min_length,
                      const std::vector<BoundaryEdge>& boundary) {
  GapReport out;
  if (!(distance > 0) || mesh.faces.empty()) return out;
  const Boundary bd = find_boundary(mesh, boundary);
  const auto& p = mesh.positions;
  const auto at = [&](std::int32_t v) -> const Vec3& { return p[static_cast<std::size_t>(v)]; };

  // Boundary directions, and the vertices in a grid of cells `distance` wide.
  const std::size_t nb = bd.vertices.size();
  // The directions of the boundary edges into and out of the boundary vertex at slot u.
  const auto unit = [](const Vec3& d) { return d.norm() > 0 ? Vec3(d.normalized()) : Vec3::Zero(); };
  const auto directions = [&](std::size_t u) {
    std::array<Vec3, 2> d{Vec3::Zero(), Vec3::Zero()};
    const Vec3& x = at(bd.vertices[u]);
    if (bd.prev[u] >= 0) d[0] = unit(x - at(bd.prev[u]));
    if (bd.next[u] >= 0) d[1] = unit(at(bd.next[u]) - x);
    return d;
  };
  using CellKey = std::uint64_t;
  const auto cell_of = [&](const Vec3& x, int dx, int dy, int dz) {
    const auto c = [&](double u, int d) {
      return static_cast<std::uint64_t>(static_cast<std::int64_t>(std::floor(u / distance)) + d +
                                        (1 << 20)) & 0x1fffff;
    };
    return c(x.x(), dx) << 42 | c(x.y(), dy) << 21 | c(x.z(), dz);
  };
  std::unordered_map<CellKey, std::vector<std::size_t>> cells;  // slots, ascending
  const auto pinch = [&](std::size_t u) { return bd.next[u] == kAmbiguous || bd.prev[u] == kAmbiguous; };
  for (std::size_t u = 0; u < nb; ++u)
    if (bd.chain[u] >= 0 && !pinch(u)) cells[cell_of(at(bd.vertices[u]), 0, 0, 0)].push_back(u);

  // Each boundary vertex's partner across a gap: the nearest boundary vertex closer than
  // `distance`, running the other way (a boundary edge at each that point against each other:
  // at a corner one of the two does), and not its own neighbour along the boundary.
  const auto antiparallel = [&](std::size_t uv, std::size_t uw) {
    for (const Vec3& dv : directions(uv))
      for (const Vec3& dw : directions(uw))
        if (dv.dot(dw) < -0.5) return true;
    return false;
  };
  // Per slot, as the boundary's figures.
  std::vector<std::int32_t> partner_of(nb, kNone);
  const auto partner = [&](std::int32_t v) { return partner_of[bd.slot(v)]; };
  for (std::size_t uv = 0; uv < nb; ++uv) {
    const auto v = static_cast<std::size_t>(bd.vertices[uv]);
    if (bd.chain[uv] < 0 || pinch(uv)) continue;
    double best = distance;
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          const auto it = cells.find(cell_of(p[v], dx, dy, dz));
          if (it == cells.end()) continue;
          for (const std::size_t uw : it->second) {
            const std::int32_t w = bd.vertices[uw];
            const double d = (at(w) - p[v]).norm();
            if (uw == uv || !(d < best)) continue;
            if (!antiparallel(uv, uw)) continue;
            if (bd.chain[uw] == bd.chain[uv]) {
              const auto c = static_cast<std::size_t>(bd.chain[uv]);
              double along = std::abs(bd.arc[uw] - bd.arc[uv]);
              if (bd.closed[c]) along = std::min(along, bd.length[c] - along);
              if (along < 4 * distance) continue;
            }
            best = d;
            partner_of[uv] = w;
          }
        }
  }

  // Runs of consecutive vertices along a chain whose partners run backwards along one chain.
  std::vector<char> used_at(nb, 0);
  const auto used = [&](std::int32_t v) -> char& { return used_at[bd.slot(v)]; };
  const std::size_t original_faces = mesh.faces.size();
  for (std::size_t c = 0; c < bd.chains.size(); ++c) {
    // A closed loop is scanned from a vertex without a partner, so that no stretch is split where
    // the loop's numbering starts (a loop partnered all round is no gap: it is skipped).
    std::vector<std::int32_t> chain = bd.chains[c];
    if (bd.closed[c]) {
      const auto lone = std::find_if(chain.begin(), chain.end(), [&](std::int32_t v) {
        return partner(v) < 0;
      });
      if (lone == chain.end()) continue;
      std::rotate(chain.begin(), lone, chain.end());
    }
    const std::size_t n = chain.size();
    // Backward steps of the partner along its chain (cyclic on a closed chain).
    const auto back_steps = [&](std::int32_t from, std::int32_t to) -> long {
      const std::size_t uf = bd.slot(from), ut = bd.slot(to);
      const auto cf = static_cast<std::size_t>(bd.chain[uf]);
      if (bd.chain[ut] != static_cast<std::int32_t>(cf)) return -1;
      long d = bd.index[uf] - bd.index[ut];
      const auto m = static_cast<long>(bd.chains[cf].size());
      if (bd.closed[cf]) d = ((d % m) + m) % m;
      return d;
    };
    std::size_t k = 0;
    while (k < n) {
      if (partner(chain[k]) < 0) {
        ++k;
        continue;
      }
      std::size_t e = k;
      while (e + 1 < n) {
        const std::int32_t q0 = partner(chain[e]);
        const std::int32_t q1 = partner(chain[e + 1]);
        if (q1 < 0) break;
        const long d = back_steps(q0, q1);
        if (d < 0 || d > 8) break;
        ++e;
      }
      const std::size_t first = k;
      k = e + 1;
      if (e == first) continue;
      // A = chain[first .. e]; C = the partners' chain walked backwards from partner(A first).
      std::vector<std::int32_t> a(chain.begin() + static_cast<long>(first),
                                  chain.begin() + static_cast<long>(e) + 1);
      const std::int32_t c_first = partner(a.front());
      const std::int32_t c_last = partner(a.back());
      std::vector<std::int32_t> c_side{c_first};
      for (std::int32_t v = c_first; v != c_last;) {
        v = bd.prev[bd.slot(v)];
        if (v < 0 || c_side.size() > 4 * a.size() + 8) break;
        c_side.push_back(v);
      }
      if (c_side.back() != c_last || c_side.size() < 2) continue;
      const auto arc_of = [&](const std::vector<std::int32_t>& side) {
        double s = 0;
        for (std::size_t i = 0; i + 1 < side.size(); ++i) s += (at(side[i + 1]) - at(side[i])).norm();
        return s;
      };
      if (arc_of(a) < min_length || arc_of(c_side) < min_length) continue;
      // Neither side may be zipped already, nor may the two sides share a vertex.
      bool taken = false;
      for (const auto v : c_side) taken = taken || used(v);
      if (taken) continue;
      for (const auto v : c_side) used(v) = 2;  // marked for a moment
      for (const auto v : a) taken = taken || used(v) != 0;
      for (const auto v : c_side) used(v) = 0;
      if (taken) continue;

      // Faces between A (a_i → a_{i+1} boundary edges) and C (c_{j+1} → c_j boundary edges),
      // each walking its boundary edges backwards, as stitch's zipper places them.
      std::vector<Face> strip;
      // Per new face, the old faces across its edge on A and on C (kNone where it has none).
      std::vector<std::int32_t> neighbour_on_a, neighbour_on_c;
      std::size_t i = 0, j = 0;
      const std::size_t ma = a.size() - 1, mc = c_side.size() - 1;
      const auto owner_a = [&](std::size_t ia) { return bd.owner[bd.slot(a[ia])]; };
      const auto owner_c = [&](std::size_t jc) { return bd.owner[bd.slot(c_side[jc + 1])]; };
      while (i < ma || j < mc) {
        const std::size_t ra = ma - i, rc = mc - j;
        bool advance_a = ra > 0, advance_c = rc > 0;
        if (ra > 0 && rc > 0 && ra != rc) {
          if (ra > rc)
            advance_c = (at(a[i + 1]) - at(c_side[j])).norm() > (at(a[i + 1]) - at(c_side[j + 1])).norm();
          else
            advance_a = (at(c_side[j + 1]) - at(a[i])).norm() > (at(c_side[j + 1]) - at(a[i + 1])).norm();
        }
        if (advance_a && advance_c) {
          strip.push_back(make_face({a[i + 1], a[i], c_side[j], c_side[j + 1]}, 4));
          neighbour_on_a.push_back(owner_a(i));
          neighbour_on_c.push_back(owner_c(j));
          ++i, ++j;
        } else if (advance_a) {
          strip.push_back(make_face({a[i + 1], a[i], c_side[j], -1}, 3));
          neighbour_on_a.push_back(owner_a(i));
          neighbour_on_c.push_back(kNone);
          ++i;
        } else {
          strip.push_back(make_face({a[i], c_side[j], c_side[j + 1], -1}, 3));
          neighbour_on_a.push_back(kNone);
          neighbour_on_c.push_back(owner_c(j));
          ++j;
        }
      }
      // Refuse a strip with a flat face or one that folds over its neighbours.
      bool acceptable = true;
      Vec3 previous = Vec3::Zero();
      for (std::size_t f = 0; f < strip.size() && acceptable; ++f) {
        if (strip[f].size < 3) {
          acceptable = false;
          break;
        }
        const Vec3 area = area_vector(mesh, strip[f]);
        if (!(area.norm() > 1e-9 * distance * distance)) {
          acceptable = false;
          break;
        }
        const Vec3 normal = area.normalized();
        for (const std::int32_t old : {neighbour_on_a[f], neighbour_on_c[f]})
          if (old >= 0 && normal.dot(unit_normal(mesh, mesh.faces[static_cast<std::size_t>(old)])) < 0)
            acceptable = false;
        if (previous.squaredNorm() > 0 && normal.dot(previous) < 0) acceptable = false;
        previous = normal;
      }
      if (!acceptable) {
        ++out.refused;
        continue;
      }
      for (const auto v : a) used(v) = 1;
      for (const auto v : c_side) used(v) = 1;
      mesh.faces.insert(mesh.faces.end(), strip.begin(), strip.end());
      ++out.stretches;
    }
  }
  out.faces = mesh.faces.size() - original_faces;
  return out;
}

}  // namespace orthofront
