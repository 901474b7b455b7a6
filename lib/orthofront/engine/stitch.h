#pragma once
/// Stitch and emit (paper §6): which front vertices get new mesh vertices (row skipping keeps
/// squares square where the front moves little), and the faces between the previous front's mesh
/// vertices and the new ones: quads while both rows advance together, triangles where one has
/// more segments.
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "orthofront/engine/front.h"
#include "orthofront/engine/options.h"
#include "orthofront/engine/report.h"
#include "orthofront/mesh/mesh.h"

namespace orthofront {

template <int N>
class StripStitcher {
 public:
  /// Mesh vertices and faces go to `mesh`, skipped vertex-steps to `report` (owned by the engine
  /// and outliving this); `row_skip` is the discretization's (options.row_skip's is ignored);
  /// `closed_seed` wraps the seed parameter of emitted vertices.
  StripStitcher(const StreamSurfaceOptions& options, RowSkip row_skip, bool closed_seed,
                Mesh& mesh, SurfaceReport& report)
      : opt_(options), row_skip_(row_skip), closed_seed_(closed_seed), mesh_(mesh),
        report_(report) {}

  /// Gives moved vertices new mesh vertices (all of them without row skipping).
  void emit_moved(Front<N>& f, const Front<N>& old, int step);

  /// The faces between the previous front `old` and `f`: between each two consecutive vertices
  /// of f that came from `old` (origin >= 0), zipper joins the chain of old mesh vertices from
  /// one's origin to the other's with the chain of f's mesh vertices between them.
  void stitch(const Front<N>& old, const Front<N>& f);

  /// Faces between an old chain A and a new chain B with common ends in correspondence:
  /// quads while both advance together, triangles where one side has more segments, placed
  /// where they create the shorter connecting edge.
  void zipper(const std::vector<std::int32_t>& a, const std::vector<std::int32_t>& b);

 private:
  /// Row skipping leaves one triangle wherever a waiting vertex neighbours a moving one. Grow
  /// moving regions into neighbours that went at least join_fraction of the way, and let short
  /// waiting or moving runs join their surroundings, so rows start and end in few places.
  /// moved_[i]: how far vertex i went from its mesh vertex (emit_moved fills it).
  void smooth_rows(const Front<N>& f, std::vector<char>& fresh) const;

  /// Whether moved vertex i of the front, if it got a new mesh vertex, would lie on (within
  /// 1e-8 ℓ of) a mesh vertex of the faces stitched to it: its own old one, those of its origin's
  /// neighbours on the previous front, or those its neighbours on the front will have. A stalled
  /// front folded onto one stream line (abc) settles into a cycle in which a vertex returns to
  /// where a neighbour's kept mesh vertex was made steps earlier; a copy there gives a face two
  /// coincident corners (zero area). And a vertex that moved less than that from its own (a front
  /// near a stagnation point, e.g. the timeline baseline on `stalling`) made a new row of copies
  /// every step. Such a vertex keeps its old mesh vertex instead, as a waiting vertex does
  /// (renew_across_merges may still renew it where that is needed for a manifold).
  bool lands_on_mesh_vertex(const Front<N>& f, const Front<N>& old, const std::vector<char>& fresh,
                            std::size_t i) const;

  /// Two vertices of the front that both keep their old mesh vertices, with nothing inserted
  /// between them but vertices merged away (merge_short), would make stitch join an old chain of
  /// three or more mesh vertices to a new "chain" of those two old ones: every face between lies
  /// on the previous front, made of its mesh vertices only. Where that front turned back on
  /// itself (the tip of a fan, whose two front edges belong to one triangle) such a face is a
  /// copy of one already behind it, with the opposite orientation: non-manifold edges. So the
  /// one of the two that moved further gets a new mesh vertex (merge_short merges between no two
  /// that did not move at all). Where only one end of a chain is old, zipper avoids such faces.
  void renew_across_merges(const Front<N>& f, const Front<N>& old,
                           std::vector<char>& fresh) const;

  /// Calls visit(oa, steps_old, ja, steps_new) for each chain stitch() joins: the old front's
  /// vertices from oa on (steps_old segments, wrapping on a closed front) and f's from ja on.
  template <class Visit>
  void for_each_chain(const Front<N>& old, const Front<N>& f, Visit&& visit) const;

  /// Adds a face of `count` corners, dropping repeated ones (a vertex that kept its mesh vertex
  /// collapses a quad to a triangle; fewer than three corners add nothing).
  void add_face(std::array<std::int32_t, 4> ids, int count);

  /// Whether the face add_face would write for these corners has (near) zero area: below
  /// 1e-9 ℓ², far above rounding and far below any face worth keeping (quality counts a face
  /// degenerate below 1e-12 of its longest edge squared). Corners that collapse to fewer than three
  /// write no face, which is not degenerate.
  bool flat_face(std::array<std::int32_t, 4> ids, int count) const;

  /// Distance between two mesh vertices.
  double distance(std::int32_t a, std::int32_t b) const;

  /// Whether zipper's choice at (i, j) between a triangle (on A's segment when `on_a`, else on
  /// B's) and the quad that advances both would write a flat face while the other would not.
  /// Vertices inserted on a straight segment from a vertex that kept its mesh vertex (α clamped
  /// to 0) lie on one line with it (linear insertion, or the cubic fallback at an open front's
  /// end): a fan from that kept vertex across them is a row of collinear triangles. Where the quad
  /// leaves one side without segments, the fan that must follow counts as part of it.
  bool flat_choice(const std::vector<std::int32_t>& a, const std::vector<std::int32_t>& b,
                   std::size_t i, std::size_t j, bool triangle, bool on_a) const;

  const StreamSurfaceOptions& opt_;
  RowSkip row_skip_;
  bool closed_seed_;
  Mesh& mesh_;
  SurfaceReport& report_;
  // emit_moved's scratch, kept between steps: which vertices get a new mesh vertex, and how far
  // each went from its old one (one square root per vertex for all of row skipping's rules).
  std::vector<char> fresh_;
  std::vector<double> moved_;
  // stitch()'s scratch: a chain's two sides.
  std::vector<std::int32_t> chain_a_, chain_b_;
};

extern template class StripStitcher<3>;
extern template class StripStitcher<4>;

}  // namespace orthofront
