#include "orthofront/mesh/triangle_topology.h"

#include <algorithm>
#include <string>

#include "orthofront/error.h"

namespace orthofront {

std::int32_t TriangleTopology::add_vertex() {
  vertex_face_.push_back(none);
  vertex_faces_.push_back(0);
  return static_cast<std::int32_t>(vertex_face_.size() - 1);
}

int TriangleTopology::edge_of(std::int32_t f, std::int32_t a, std::int32_t b) const {
  const auto& c = faces_[idx(f)];
  for (int e = 0; e < 3; ++e)
    if (c[e] == a && c[(e + 1) % 3] == b) return e;
  return -1;
}

TriangleTopology::HalfEdge TriangleTopology::leaving(std::int32_t v, std::int32_t f) const {
  const auto& c = faces_[idx(f)];
  for (int e = 0; e < 3; ++e)
    if (c[e] == v) return {f, e};
  return {none, 0};
}

bool TriangleTopology::fan(std::int32_t v, std::vector<HalfEdge>& out) const {
  out.clear();
  const std::int32_t start = vertex_face_[idx(v)];
  if (start == none) return false;
  // Backward (across the edge that leaves v) to the first face of the fan, or once round.
  std::int32_t first = start;
  for (std::size_t steps = 0;; ++steps) {
    if (steps > faces_.size()) throw Error("TriangleTopology: a vertex fan does not close");
    const HalfEdge h = leaving(v, first);
    const std::int32_t g = neighbors_[idx(first)][h.edge];
    if (g == none) break;
    if (g == start) {  // interior: the fan is a cycle
      first = start;
      break;
    }
    first = g;
  }
  bool boundary = true;
  std::int32_t f = first;
  for (;;) {
    const HalfEdge h = leaving(v, f);
    out.push_back(h);
    const std::int32_t g = neighbors_[idx(f)][(h.edge + 2) % 3];  // across the edge into v
    if (g == none) break;
    if (g == first) {
      boundary = false;
      break;
    }
    f = g;
    if (out.size() > faces_.size()) throw Error("TriangleTopology: a vertex fan does not close");
  }
  return boundary;
}

bool TriangleTopology::on_boundary(std::int32_t v) const {
  // fan()'s backward rotation alone: it meets a boundary edge or comes round to the start.
  const std::int32_t start = vertex_face_[idx(v)];
  if (start == none) return false;
  std::int32_t f = start;
  for (std::size_t steps = 0; steps <= faces_.size(); ++steps) {
    const std::int32_t g = neighbors_[idx(f)][leaving(v, f).edge];
    if (g == none) return true;
    if (g == start) return false;
    f = g;
  }
  throw Error("TriangleTopology: a vertex fan does not close");
}

bool TriangleTopology::adjacent(std::int32_t u, std::int32_t w) const {
  std::vector<HalfEdge> ring;
  const bool boundary = fan(u, ring);
  for (const HalfEdge& h : ring)
    if (to(h) == w) return true;
  // The edge into u of the last face of a boundary fan has no face leaving u along it.
  if (boundary && !ring.empty() && opposite(ring.back().face, ring.back().edge) == w) return true;
  return false;
}

std::int32_t TriangleTopology::face_with_edge(std::int32_t a, std::int32_t b) const {
  std::vector<HalfEdge> ring;
  fan(a, ring);
  for (const HalfEdge& h : ring)
    if (to(h) == b) return h.face;
  return none;
}

bool TriangleTopology::can_add_face(std::int32_t a, std::int32_t b, std::int32_t c) const {
  const std::array<std::int32_t, 3> v{a, b, c};
  for (const std::int32_t x : v)
    if (x < 0 || idx(x) >= vertex_face_.size()) return false;
  if (a == b || b == c || a == c) return false;
  for (int e = 0; e < 3; ++e)
    if (face_with_edge(v[e], v[(e + 1) % 3]) != none) return false;
  // Each corner with faces must share an edge with them there: its fan must end in one of the
  // new face's edges at that corner, or the corner would join two fans at a point.
  std::vector<HalfEdge> ring;
  for (int k = 0; k < 3; ++k) {
    const std::int32_t x = v[k], next = v[(k + 1) % 3], prev = v[(k + 2) % 3];
    if (!fan(x, ring)) {
      if (!ring.empty()) return false;  // interior vertex: no room for a face
      continue;
    }
    // The boundary edges at x: the first face's edge leaving x, the last face's edge into x.
    const std::int32_t out_end = to(ring.front());
    const std::int32_t in_start = opposite(ring.back().face, ring.back().edge);
    // The new face's edge x -> next is the twin of the fan's edge next -> x (into x, at the end
    // of the fan), and prev -> x the twin of x -> prev (leaving x, at its start).
    if (in_start != next && out_end != prev) return false;
  }
  return true;
}

std::int32_t TriangleTopology::add_face(std::int32_t a, std::int32_t b, std::int32_t c) {
  if (!can_add_face(a, b, c))
    throw InvalidArgument("TriangleTopology: face (" + std::to_string(a) + ", " +
                          std::to_string(b) + ", " + std::to_string(c) +
                          ") would not keep the mesh manifold and oriented");
  const auto f = static_cast<std::int32_t>(faces_.size());
  const std::array<std::int32_t, 3> v{a, b, c};
  std::array<std::int32_t, 3> across{none, none, none};
  for (int e = 0; e < 3; ++e) across[e] = face_with_edge(v[(e + 1) % 3], v[e]);
  faces_.push_back(v);
  neighbors_.push_back(across);
  for (int e = 0; e < 3; ++e) {
    if (across[e] != none) {
      const int back = edge_of(across[e], v[(e + 1) % 3], v[e]);
      neighbors_[idx(across[e])][back] = f;
    }
    if (vertex_face_[idx(v[e])] == none) vertex_face_[idx(v[e])] = f;
    ++vertex_faces_[idx(v[e])];
  }
  ++live_faces_;
  return f;
}

void TriangleTopology::relink(std::int32_t neighbor_face, std::int32_t old_face, std::int32_t g) {
  if (neighbor_face == none) return;
  auto& n = neighbors_[idx(neighbor_face)];
  for (int e = 0; e < 3; ++e)
    if (n[e] == old_face) {
      n[e] = g;
      return;
    }
}

void TriangleTopology::repoint(std::int32_t v, std::int32_t f) {
  if (vertex_face_[idx(v)] != f) return;
  const HalfEdge h = leaving(v, f);
  const std::int32_t out_face = neighbors_[idx(f)][h.edge];
  const std::int32_t in_face = neighbors_[idx(f)][(h.edge + 2) % 3];
  vertex_face_[idx(v)] = out_face != none ? out_face : in_face;
}

std::int32_t TriangleTopology::split(std::int32_t f, int e) {
  const std::int32_t a = faces_[idx(f)][e], b = faces_[idx(f)][(e + 1) % 3];
  const std::int32_t c = faces_[idx(f)][(e + 2) % 3];
  const std::int32_t g = neighbors_[idx(f)][e];
  const std::int32_t n_bc = neighbors_[idx(f)][(e + 1) % 3];
  const std::int32_t n_ca = neighbors_[idx(f)][(e + 2) % 3];
  const std::int32_t m = add_vertex();
  const auto f2 = static_cast<std::int32_t>(faces_.size());
  std::int32_t g2 = none;
  faces_.push_back({m, b, c});
  neighbors_.push_back({none, n_bc, f});
  ++live_faces_;
  if (g == none) {
    faces_[idx(f)] = {a, m, c};
    neighbors_[idx(f)] = {none, f2, n_ca};
    relink(n_bc, f, f2);
    vertex_face_[idx(m)] = f;
    vertex_faces_[idx(m)] = 2;
    ++vertex_faces_[idx(c)];
    if (vertex_face_[idx(b)] == f) vertex_face_[idx(b)] = f2;
    return m;
  }
  const int ge = edge_of(g, b, a);
  const std::int32_t d = faces_[idx(g)][(ge + 2) % 3];
  const std::int32_t n_ad = neighbors_[idx(g)][(ge + 1) % 3];
  const std::int32_t n_db = neighbors_[idx(g)][(ge + 2) % 3];
  g2 = static_cast<std::int32_t>(faces_.size());
  faces_.push_back({m, a, d});
  neighbors_.push_back({f, n_ad, g});
  ++live_faces_;
  faces_[idx(f)] = {a, m, c};
  neighbors_[idx(f)] = {g2, f2, n_ca};
  neighbors_[idx(f2)][0] = g;
  faces_[idx(g)] = {b, m, d};
  neighbors_[idx(g)] = {f2, g2, n_db};
  relink(n_bc, f, f2);
  relink(n_ad, g, g2);
  vertex_face_[idx(m)] = f;
  vertex_faces_[idx(m)] = 4;
  ++vertex_faces_[idx(c)];
  ++vertex_faces_[idx(d)];
  if (vertex_face_[idx(b)] == f) vertex_face_[idx(b)] = f2;
  if (vertex_face_[idx(a)] == g) vertex_face_[idx(a)] = g2;
  return m;
}

bool TriangleTopology::flip(std::int32_t f, int e) {
  const std::int32_t g = neighbors_[idx(f)][e];
  if (g == none) return false;
  const std::int32_t a = faces_[idx(f)][e], b = faces_[idx(f)][(e + 1) % 3];
  const std::int32_t c = faces_[idx(f)][(e + 2) % 3];
  const int ge = edge_of(g, b, a);
  const std::int32_t d = faces_[idx(g)][(ge + 2) % 3];
  if (c == d || adjacent(c, d)) return false;
  const std::int32_t n_bc = neighbors_[idx(f)][(e + 1) % 3];
  const std::int32_t n_ca = neighbors_[idx(f)][(e + 2) % 3];
  const std::int32_t n_ad = neighbors_[idx(g)][(ge + 1) % 3];
  const std::int32_t n_db = neighbors_[idx(g)][(ge + 2) % 3];
  // The quad a, d, b, c (counter-clockwise) cut along c-d: f = (a, d, c), g = (d, b, c).
  faces_[idx(f)] = {a, d, c};
  neighbors_[idx(f)] = {n_ad, g, n_ca};
  faces_[idx(g)] = {d, b, c};
  neighbors_[idx(g)] = {n_db, n_bc, f};
  relink(n_ad, g, f);
  relink(n_bc, f, g);
  --vertex_faces_[idx(a)];
  --vertex_faces_[idx(b)];
  ++vertex_faces_[idx(c)];
  ++vertex_faces_[idx(d)];
  if (vertex_face_[idx(a)] == g) vertex_face_[idx(a)] = f;
  if (vertex_face_[idx(b)] == f) vertex_face_[idx(b)] = g;
  return true;
}

bool TriangleTopology::can_collapse(std::int32_t u, std::int32_t w) const {
  if (u == w) return false;
  // Scratch kept per thread: collapse passes ask this for many edges in a row.
  thread_local std::vector<HalfEdge> ring_u, ring_w;
  thread_local std::vector<std::int32_t> shared, opposite_corners, nu, nw, common;
  const bool u_boundary = fan(u, ring_u);
  const bool w_boundary = fan(w, ring_w);
  if (ring_u.empty() || ring_w.empty()) return false;
  // The faces holding both, and their corners opposite the edge.
  shared.clear(), opposite_corners.clear();
  for (const HalfEdge& h : ring_u) {
    const auto& c = faces_[idx(h.face)];
    if (c[0] == w || c[1] == w || c[2] == w) {
      shared.push_back(h.face);
      for (const std::int32_t x : c)
        if (x != u && x != w) opposite_corners.push_back(x);
    }
  }
  if (shared.empty()) return false;  // not an edge
  const bool edge_on_boundary = shared.size() == 1;
  if (u_boundary && !edge_on_boundary) return false;
  if (u_boundary && w_boundary && !edge_on_boundary) return false;
  if (!u_boundary && edge_on_boundary) return false;
  if (ring_u.size() == shared.size() && ring_w.size() == shared.size()) return false;  // last faces
  // An ear (a face whose other two edges are boundary edges too) would vanish.
  for (const std::int32_t f : shared) {
    int boundary_edges = 0;
    for (int e = 0; e < 3; ++e) boundary_edges += neighbors_[idx(f)][e] == none ? 1 : 0;
    if (boundary_edges >= 2) return false;
  }
  // Link condition: the common neighbours of u and w are exactly the opposite corners.
  const auto neighbours = [&](const std::vector<HalfEdge>& ring, bool boundary,
                              std::vector<std::int32_t>& n) {
    n.clear();
    for (const HalfEdge& h : ring) n.push_back(to(h));
    if (boundary) n.push_back(opposite(ring.back().face, ring.back().edge));
    std::sort(n.begin(), n.end());
    n.erase(std::unique(n.begin(), n.end()), n.end());
  };
  neighbours(ring_u, u_boundary, nu);
  neighbours(ring_w, w_boundary, nw);
  common.clear();
  std::set_intersection(nu.begin(), nu.end(), nw.begin(), nw.end(), std::back_inserter(common));
  std::sort(opposite_corners.begin(), opposite_corners.end());
  if (std::adjacent_find(opposite_corners.begin(), opposite_corners.end()) != opposite_corners.end())
    return false;
  return common == opposite_corners;
}

void TriangleTopology::collapse(std::int32_t u, std::int32_t w) {
  std::vector<HalfEdge> ring;
  fan(u, ring);
  for (const HalfEdge& h : ring) {
    const std::int32_t f = h.face;
    const auto c = faces_[idx(f)];
    if (c[0] != w && c[1] != w && c[2] != w) continue;
    // f = (u, w, x) or (w, u, x) up to rotation: its neighbours across (w, x) and (x, u) become
    // each other's.
    std::int32_t x = none;
    for (const std::int32_t k : c)
      if (k != u && k != w) x = k;
    std::int32_t across_wx = none, across_xu = none;
    for (int e = 0; e < 3; ++e) {
      const std::int32_t p = c[e], q = c[(e + 1) % 3];
      if ((p == w && q == x) || (p == x && q == w)) across_wx = neighbors_[idx(f)][e];
      if ((p == x && q == u) || (p == u && q == x)) across_xu = neighbors_[idx(f)][e];
    }
    relink(across_wx, f, across_xu);
    relink(across_xu, f, across_wx);
    for (const std::int32_t k : c) {
      --vertex_faces_[idx(k)];
      if (vertex_face_[idx(k)] == f)
        vertex_face_[idx(k)] = across_wx != none ? across_wx : across_xu;
    }
    faces_[idx(f)] = {none, none, none};
    neighbors_[idx(f)] = {none, none, none};
    --live_faces_;
  }
  for (const HalfEdge& h : ring) {
    auto& c = faces_[idx(h.face)];
    if (c[0] == none) continue;
    c[h.edge] = w;
    ++vertex_faces_[idx(w)];
    if (vertex_face_[idx(w)] == none) vertex_face_[idx(w)] = h.face;
  }
  // w's first face may have been one of the removed ones and repointed to a face of u.
  if (vertex_face_[idx(w)] != none && leaving(w, vertex_face_[idx(w)]).face == none) {
    for (const HalfEdge& h : ring)
      if (faces_[idx(h.face)][0] != none) vertex_face_[idx(w)] = h.face;
  }
  vertex_face_[idx(u)] = none;
  vertex_faces_[idx(u)] = 0;
}

void TriangleTopology::kill(std::int32_t f) {
  const auto c = faces_[idx(f)];
  // New first faces while the links still stand.
  for (const std::int32_t k : c) {
    --vertex_faces_[idx(k)];
    repoint(k, f);
    if (vertex_faces_[idx(k)] == 0) vertex_face_[idx(k)] = none;
  }
  for (int e = 0; e < 3; ++e) relink(neighbors_[idx(f)][e], f, none);
  faces_[idx(f)] = {none, none, none};
  neighbors_[idx(f)] = {none, none, none};
  --live_faces_;
}

std::size_t TriangleTopology::remove_face(std::int32_t f,
                                          std::vector<std::array<std::int32_t, 3>>* corners) {
  std::size_t removed = 0;
  std::vector<std::int32_t> work{f};
  std::vector<HalfEdge> ring;
  while (!work.empty()) {
    const std::int32_t g = work.back();
    work.pop_back();
    if (!face_alive(g)) continue;
    // A boundary corner whose fan passes through g on both sides would keep two fans: the
    // smaller side goes with g.
    for (int k = 0; k < 3; ++k) {
      const std::int32_t v = faces_[idx(g)][k];
      const std::int32_t out_face = neighbors_[idx(g)][k];
      const std::int32_t in_face = neighbors_[idx(g)][(k + 2) % 3];
      if (out_face == none || in_face == none) continue;
      if (!fan(v, ring)) continue;  // interior: removing g leaves one fan
      std::size_t before = 0;
      while (before < ring.size() && ring[before].face != g) ++before;
      const std::size_t after = ring.size() - before - 1;
      // v keeps a face of the larger side (its first face may be on the side that goes).
      if (before <= after) {
        for (std::size_t i = 0; i < before; ++i) work.push_back(ring[i].face);
        vertex_face_[idx(v)] = ring[before + 1].face;
      } else {
        for (std::size_t i = before + 1; i < ring.size(); ++i) work.push_back(ring[i].face);
        vertex_face_[idx(v)] = ring[before - 1].face;
      }
    }
    if (corners != nullptr) corners->push_back(faces_[idx(g)]);
    kill(g);
    ++removed;
  }
  return removed;
}

std::size_t TriangleTopology::remove_faces_of(std::int32_t v) {
  std::size_t removed = 0;
  std::vector<HalfEdge> ring;
  while (vertex_face_[idx(v)] != none) {
    fan(v, ring);
    removed += remove_face(ring.front().face);
  }
  return removed;
}

std::vector<std::int32_t> TriangleTopology::compact(const std::vector<char>& keep) {
  std::vector<std::int32_t> vertex_index(vertex_face_.size(), none);
  std::int32_t next = 0;
  std::vector<std::int32_t> new_vertex_face, face_index(faces_.size(), none);
  std::vector<int> new_counts;
  std::int32_t next_face = 0;
  for (std::size_t f = 0; f < faces_.size(); ++f)
    if (faces_[f][0] != none) face_index[f] = next_face++;
  for (std::size_t v = 0; v < vertex_face_.size(); ++v) {
    const bool kept = vertex_face_[v] != none || (v < keep.size() && keep[v] != 0);
    if (!kept) continue;
    vertex_index[v] = next++;
    new_vertex_face.push_back(vertex_face_[v] == none ? none : face_index[idx(vertex_face_[v])]);
    new_counts.push_back(vertex_faces_[v]);
  }
  std::vector<std::array<std::int32_t, 3>> faces, neighbors;
  faces.reserve(static_cast<std::size_t>(next_face));
  neighbors.reserve(static_cast<std::size_t>(next_face));
  for (std::size_t f = 0; f < faces_.size(); ++f) {
    if (faces_[f][0] == none) continue;
    std::array<std::int32_t, 3> c{}, n{};
    for (int e = 0; e < 3; ++e) {
      c[e] = vertex_index[idx(faces_[f][e])];
      n[e] = neighbors_[f][e] == none ? none : face_index[idx(neighbors_[f][e])];
    }
    faces.push_back(c);
    neighbors.push_back(n);
  }
  faces_ = std::move(faces);
  neighbors_ = std::move(neighbors);
  vertex_face_ = std::move(new_vertex_face);
  vertex_faces_ = std::move(new_counts);
  live_faces_ = faces_.size();
  return vertex_index;
}

}  // namespace orthofront
