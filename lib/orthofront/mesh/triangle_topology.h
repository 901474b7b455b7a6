#pragma once
/// The connectivity of an oriented, manifold triangle mesh that changes by local operations:
/// edge split, edge flip, half-edge collapse and face removal, each O(valence). Every face keeps
/// its neighbour across each of its edges; every vertex keeps one face it belongs to, so its fan
/// is found by rotating across edges. Vertex data (positions, labels) live with the caller,
/// indexed by the vertex ids handed out here; geometry tests are the caller's too.
#include <array>
#include <cstdint>
#include <vector>

namespace orthofront {

class TriangleTopology {
 public:
  static constexpr std::int32_t none = -1;
  /// Edge e of face f runs from corner e to corner (e + 1) % 3.
  struct HalfEdge {
    std::int32_t face = none;
    int edge = 0;
  };

  /// A vertex with no face yet; returns its id (ids are dense and never reused before compact()).
  std::int32_t add_vertex();
  /// Adds the counter-clockwise face (a, b, c) and links it to the faces that hold the reversed
  /// edges (b, a), (c, b), (a, c). Throws InvalidArgument for repeated corners or an edge that
  /// is already used in this direction (the mesh would not stay oriented and manifold).
  std::int32_t add_face(std::int32_t a, std::int32_t b, std::int32_t c);

  std::size_t vertex_slots() const { return vertex_face_.size(); }
  std::size_t face_slots() const { return faces_.size(); }
  std::size_t face_count() const { return live_faces_; }
  bool face_alive(std::int32_t f) const { return faces_[idx(f)][0] != none; }
  const std::array<std::int32_t, 3>& face(std::int32_t f) const { return faces_[idx(f)]; }
  std::int32_t neighbor(std::int32_t f, int e) const { return neighbors_[idx(f)][e]; }
  std::int32_t from(HalfEdge h) const { return faces_[idx(h.face)][h.edge]; }
  std::int32_t to(HalfEdge h) const { return faces_[idx(h.face)][(h.edge + 1) % 3]; }
  /// The corner of f opposite edge e.
  std::int32_t opposite(std::int32_t f, int e) const { return faces_[idx(f)][(e + 2) % 3]; }
  bool has_faces(std::int32_t v) const { return vertex_face_[idx(v)] != none; }
  /// Faces that hold v.
  int face_count(std::int32_t v) const { return vertex_faces_[idx(v)]; }

  /// The faces around v, each as the half-edge that leaves v in it, in order around v (for a
  /// boundary vertex from one boundary edge to the other). Returns whether v is on the boundary.
  bool fan(std::int32_t v, std::vector<HalfEdge>& out) const;
  bool on_boundary(std::int32_t v) const;
  /// True when u and w share an edge.
  bool adjacent(std::int32_t u, std::int32_t w) const;

  /// Splits edge e of f (and its twin) at a new vertex, which is returned: two faces become four
  /// (one becomes two at the boundary). The new vertex's first face is f.
  std::int32_t split(std::int32_t f, int e);
  /// Replaces the interior edge e of f by the other diagonal of its two faces. Returns false (and
  /// changes nothing) at the boundary or where that diagonal already exists.
  bool flip(std::int32_t f, int e);
  /// Whether collapsing edge e of f onto one end (u = the end removed) keeps the mesh manifold:
  /// the link condition (u and w share no neighbour but the corners opposite their edge), no
  /// interior edge between two boundary vertices, a boundary u only along a boundary edge, and
  /// no fan that would lose all its faces.
  bool can_collapse(std::int32_t u, std::int32_t w) const;
  /// Moves u onto w: the faces that hold both go, every other face of u takes w. Call only where
  /// can_collapse(u, w).
  void collapse(std::int32_t u, std::int32_t w);
  /// Removes face f (its neighbours get a boundary edge there). Where that would leave a corner
  /// with two fans (f in the middle of a boundary vertex's fan), the smaller fan goes too, so
  /// the mesh stays manifold. Returns the faces removed; appends their corners to `corners`
  /// when given.
  std::size_t remove_face(std::int32_t f,
                          std::vector<std::array<std::int32_t, 3>>* corners = nullptr);
  /// Removes every face of v (and what remove_face removes with them). Returns the faces removed.
  std::size_t remove_faces_of(std::int32_t v);
  /// Whether add_face(a, b, c) would keep the mesh manifold and oriented: distinct corners, no
  /// edge already used in that direction, and no corner whose faces it would touch at that
  /// corner alone (two fans meeting at a point).
  bool can_add_face(std::int32_t a, std::int32_t b, std::int32_t c) const;

  /// Drops dead faces and the vertices that have no face and are not kept (keep[v] != 0).
  /// Returns, per old vertex id, its new id (none for a dropped vertex).
  std::vector<std::int32_t> compact(const std::vector<char>& keep);

 private:
  static std::size_t idx(std::int32_t i) { return static_cast<std::size_t>(i); }
  // The edge of f that runs a -> b, or -1.
  int edge_of(std::int32_t f, std::int32_t a, std::int32_t b) const;
  // Makes g the neighbour of `neighbor_face` where old_face was (g = none: a boundary edge).
  void relink(std::int32_t neighbor_face, std::int32_t old_face, std::int32_t g);
  // The existing face with edge a -> b, or none.
  std::int32_t face_with_edge(std::int32_t a, std::int32_t b) const;
  // Unlinks and kills f, with the counts and first faces of its corners.
  void kill(std::int32_t f);
  // Gives v another first face where its first face is f and leaves it (none: v has no face).
  void repoint(std::int32_t v, std::int32_t f);
  // The half-edge leaving v in f.
  HalfEdge leaving(std::int32_t v, std::int32_t f) const;

  std::vector<std::array<std::int32_t, 3>> faces_;      // corners; [0] == none: dead
  std::vector<std::array<std::int32_t, 3>> neighbors_;  // across edge e; none: boundary
  std::vector<std::int32_t> vertex_face_;               // one face of the vertex; none: no face
  std::vector<int> vertex_faces_;                       // faces of the vertex
  std::size_t live_faces_ = 0;
};

}  // namespace orthofront
