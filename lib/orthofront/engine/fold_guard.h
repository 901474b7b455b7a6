#pragma once
/// Folds caught at stitch time: a face of the strip just stitched whose normal turns by more than
/// 90° from a neighbour's across a shared edge (the quality measure's definition of a fold), the
/// neighbour being another face of that strip or a face of the surface so far.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "orthofront/huge_pages.h"
#include "orthofront/mesh/close_gaps.h"
#include "orthofront/mesh/mesh.h"

namespace orthofront {

class FoldGuard {
 public:
  FoldGuard() = default;
  FoldGuard(const FoldGuard&) = delete;
  FoldGuard& operator=(const FoldGuard&) = delete;

  /// Starts from a surface made elsewhere (a restored engine): every face of `mesh` is accepted.
  void rebuild(const Mesh& mesh);

  /// Mesh vertices made by the part just stitched (index >= first_new_vertex) that stand on a
  /// fold of faces [first_face, end): the new ends of a folded edge, or else the new corners of
  /// the folded face. Empty when those faces fold over nothing.
  std::vector<std::int32_t> folded_vertices(const Mesh& mesh, std::size_t first_face,
                                            std::size_t first_new_vertex);

  /// Faces [first_face, end) are part of the surface: later strips are checked against them.
  void accept(const Mesh& mesh, std::size_t first_face);

  /// The accepted surface's boundary edges, as their faces walk them: those with one face (and,
  /// on a non-manifold mesh, those with an odd number: boundary_edges() leaves those out).
  std::vector<BoundaryEdge> boundary();

 private:
  /// rebuild()'s and accept()'s work on faces [first, end) of `mesh` (the area vectors of the
  /// faces checked last are known already).
  void add_to_boundary(const Mesh& mesh, std::size_t first, std::size_t end);

  /// folded_vertices()'s check of the faces from `begin` on, adding the vertices on folds to
  /// `out`.
  void check_faces(const Mesh& mesh, std::size_t begin, std::size_t first_new_vertex,
                   std::vector<std::int32_t>& out);

  /// A face of the strip being checked on an edge: the face, whether it walks the edge from its
  /// lower to its higher vertex (its area vector is in checked_normals_), and the boundary change
  /// it recorded for the edge.
  static constexpr std::uint32_t kNoChange = (std::uint32_t{1} << 31) - 1;
  struct StripEdge {
    std::uint32_t face;
    std::uint32_t change : 31;
    std::uint32_t forward : 1;
  };
  /// What accepting the checked faces does to the boundary, learnt by the check (which looks up
  /// each of their edges in both lists anyway): accepting then only applies these, in face order,
  /// instead of looking up every edge again. An edge two strip faces share is no change (the
  /// first face's addition is cancelled when the second comes).
  struct BoundaryChange {
    enum Kind : std::uint8_t { add, remove, cancelled };
    std::int32_t a, b;
    std::uint32_t face;
    Kind kind;
  };
  /// Applies changes_ to the boundary (faces [changes_first_, changes_end_), all checked).
  void apply_changes();
  /// An accepted face on a boundary edge, with its area vector (zero for a face without area):
  /// nothing else keeps the area vectors of accepted faces.
  struct OpenEdge {
    Vec3 normal;
    std::uint32_t face;
    bool forward;
  };

  /// Faces on undirected edges, listed with the edge's lower vertex: a list head per mesh vertex
  /// and pooled entries, so a step allocates nothing once the pool has grown (a hash map's node
  /// per edge made the guard cost more than the rest of stitching).
  template <class Payload>
  class EdgeLists {
   public:
    struct Entry {
      Payload payload;
      std::int32_t other;    ///< the edge's higher vertex
      std::uint32_t next;    ///< next entry of the same lower vertex (kNone: last)
    };
    static constexpr std::uint32_t kNone = 0xffffffffu;

    /// Forgets every edge (O(1): list heads of an older generation read as empty).
    void clear();
    void add(std::int32_t a, std::int32_t b, const Payload& face) {
      const auto [lo, hi] = ordered(a, b);
      if (hi >= vertex_end_) cover(hi);
      Head& h = heads_[static_cast<std::size_t>(lo)];
      if (h.generation != generation_) h = Head{kNone, generation_};
      std::uint32_t e = free_;
      if (e != kNone) {
        free_ = entries_[e].next;
        entries_[e] = Entry{face, hi, h.first};
      } else {
        e = static_cast<std::uint32_t>(entries_.size());
        entries_.push_back(Entry{face, hi, h.first});
      }
      h.first = e;
    }
    /// Removes one entry of edge (a, b); false when there is none.
    bool remove(std::int32_t a, std::int32_t b);
    /// Calls visit(lower vertex, entry) for every entry.
    template <class Visit>
    void for_each(Visit&& visit) const {
      for (std::size_t v = 0; v < heads_.size(); ++v)
        for (std::uint32_t e = head(static_cast<std::int32_t>(v)); e != kNone; e = entries_[e].next)
          visit(static_cast<std::int32_t>(v), entries_[e]);
    }
    /// Calls visit(payload) for each face on edge (a, b) until it returns true; returns whether
    /// one did.
    template <class Visit>
    bool any_of(std::int32_t a, std::int32_t b, Visit&& visit) const {
      const auto [lo, hi] = ordered(a, b);
      if (hi >= vertex_end_) return false;
      for (std::uint32_t e = covered_head(lo); e != kNone; e = entries_[e].next)
        if (entries_[e].other == hi && visit(entries_[e].payload)) return true;
      return false;
    }

   private:
    static std::pair<std::int32_t, std::int32_t> ordered(std::int32_t a, std::int32_t b) {
      return a < b ? std::pair{a, b} : std::pair{b, a};
    }
    std::uint32_t head(std::int32_t v) const {
      const auto i = static_cast<std::size_t>(v);
      return i < heads_.size() ? covered_head(v) : kNone;
    }
    /// head() of a vertex below vertex_end_, which heads_ always covers.
    std::uint32_t covered_head(std::int32_t v) const {
      const Head& h = heads_[static_cast<std::size_t>(v)];
      return h.generation == generation_ ? h.first : kNone;
    }
    /// Raises vertex_end_ past `hi` (most edges of a strip end at its newest vertex), growing
    /// heads_ to cover it.
    void cover(std::int32_t hi) {
      vertex_end_ = hi + 1;
      if (static_cast<std::size_t>(vertex_end_) > heads_.size()) grow_heads();
    }
    void grow_heads();

    /// A vertex's list: its first entry, valid while `generation` is the lists' (one cache line
    /// for both).
    struct Head {
      std::uint32_t first = kNone;
      std::uint32_t generation = 0;
    };
    HugePageVector<Head> heads_;
    std::uint32_t generation_ = 1;
    /// One past the highest vertex of any edge added since the last clear() (heads_ covers it):
    /// an edge whose higher vertex is at or above it has no entry, found without a look. The
    /// strip's new vertices are numbered after everything accepted, and in the order stitch makes
    /// faces, so most of a strip's edges are new to both lists.
    std::int32_t vertex_end_ = 0;
    HugePageVector<Entry> entries_;
    std::uint32_t free_ = kNone;  ///< removed entries, chained through `next`
  };

  /// Edges of accepted faces that have one face so far: the surface's boundary, which holds
  /// every edge a new strip can share with it (the front's rows among them).
  EdgeLists<OpenEdge> open_;
  /// Scratch: the faces of the part being checked. Their area vectors are in checked_normals_
  /// (entries of 16 bytes instead of 40).
  EdgeLists<StripEdge> strip_;
  /// Area vectors of the faces checked since the last acceptance, from face checked_first_ on.
  std::vector<Vec3> checked_normals_;
  std::size_t checked_first_ = 0;
  /// The boundary changes of faces [changes_first_, changes_end_), checked by the last
  /// folded_vertices(); unusable (changes_known_ false) when an edge met more than one other
  /// face there: accepting then looks every edge up again.
  std::vector<BoundaryChange> changes_;
  std::size_t changes_first_ = 0, changes_end_ = 0;
  bool changes_known_ = false;
};

}  // namespace orthofront
