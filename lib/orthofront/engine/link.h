#pragma once
/// Link (paper Figure 4, "triangulate"): the strip between a front and the one it advanced from
/// (stitch.h), checked by the fold guard (fold_guard.h) where the discretization has safeguards:
/// a strip that folds is undone, and stitched again without the vertices on the fold.
#include <cstddef>
#include <functional>
#include <vector>

#include "orthofront/engine/fold_guard.h"
#include "orthofront/engine/front.h"
#include "orthofront/engine/options.h"
#include "orthofront/engine/report.h"
#include "orthofront/engine/stitch.h"
#include "orthofront/mesh/close_gaps.h"
#include "orthofront/mesh/mesh.h"

namespace orthofront {

template <int N>
class StripLinker {
 public:
  /// Cuts a front where keep[i] == 0 (dropping those vertices) and after vertex i where
  /// cut[i] != 0 (split_front, with the engine's front ids and count).
  using Split = std::function<std::vector<Front<N>>(Front<N>&&, const std::vector<char>& keep,
                                                    const std::vector<char>& cut)>;

  /// Faces and vertices go to `mesh`, counts to `report` (both outlive this). `row_skip` is the
  /// discretization's; `guarded`: whether the fold guard checks each strip.
  StripLinker(const StreamSurfaceOptions& options, RowSkip row_skip, bool guarded,
              bool closed_seed, Mesh& mesh, SurfaceReport& report, Split split);

  /// Emits the moved vertices of `parts` (the parts of one front after adapt) and stitches each
  /// to `old`, the front they advanced from. Mesh vertices from first_inserted on were inserted
  /// this step (adapt). Returns the pieces that go on: the parts, less the vertices the guard
  /// took out of them (a local rip: their stream lines end at their previous mesh vertices).
  std::vector<Front<N>> link(std::vector<Front<N>>&& parts, const Front<N>& old, int step,
                             std::size_t first_inserted);

  /// Starts from a surface made elsewhere (a restored engine).
  void rebuild(const Mesh& mesh);
  /// The surface's boundary edges, as the guard kept them (guarded only).
  std::vector<BoundaryEdge> boundary();
  bool guarded() const { return guarded_; }

 private:
  /// One part, up to three rounds: where a face of the strip folds over a neighbour the round is
  /// undone and the vertices standing on the fold leave the part. Folds left after the last
  /// round stay in the mesh, counted in the report. A vertex inserted this step taken out leaves
  /// a mesh vertex no face uses (the engine removes those at the end when the guard ripped).
  void link_guarded(Front<N>&& part, const Front<N>& old, int step, std::size_t first_inserted,
                    std::vector<Front<N>>& out);

  bool guarded_;
  Mesh& mesh_;
  SurfaceReport& report_;
  Split split_;
  StripStitcher<N> stitcher_;
  FoldGuard fold_guard_;
};

extern template class StripLinker<3>;
extern template class StripLinker<4>;

}  // namespace orthofront
