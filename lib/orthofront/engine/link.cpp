#include "orthofront/engine/link.h"

#include <algorithm>
#include <utility>

namespace orthofront {

template <int N>
StripLinker<N>::StripLinker(const StreamSurfaceOptions& options, RowSkip row_skip, bool guarded,
                            bool closed_seed, Mesh& mesh, SurfaceReport& report, Split split)
    : guarded_(guarded), mesh_(mesh), report_(report), split_(std::move(split)),
      stitcher_(options, row_skip, closed_seed, mesh, report) {}

template <int N>
std::vector<Front<N>> StripLinker<N>::link(std::vector<Front<N>>&& parts, const Front<N>& old,
                                           int step, std::size_t first_inserted) {
  if (!guarded_) {
    for (auto& part : parts) {
      stitcher_.emit_moved(part, old, step);
      stitcher_.stitch(old, part);
    }
    return std::move(parts);
  }
  std::vector<Front<N>> pieces;
  for (auto& part : parts) link_guarded(std::move(part), old, step, first_inserted, pieces);
  return pieces;
}

template <int N>
void StripLinker<N>::rebuild(const Mesh& mesh) {
  if (guarded_) fold_guard_.rebuild(mesh);
}

template <int N>
std::vector<BoundaryEdge> StripLinker<N>::boundary() {
  return fold_guard_.boundary();
}

template <int N>
void StripLinker<N>::link_guarded(Front<N>&& part, const Front<N>& old, int step,
                                  std::size_t first_inserted, std::vector<Front<N>>& out) {
  constexpr int kRounds = 3;
  std::vector<Front<N>> pieces;
  pieces.push_back(std::move(part));
  for (int round = 0;; ++round) {
    const std::size_t vertices = mesh_.vertex_count(), faces = mesh_.face_count();
    const std::size_t skipped = report_.skipped_vertex_steps;
    const std::size_t row_changes = report_.triangles_at_row_changes;
    const std::size_t waiting = report_.triangles_at_waiting_vertices;
    std::vector<std::int32_t> folded;
    for (auto& piece : pieces) {
      const std::size_t first_face = mesh_.face_count();
      // Checked after its stitching, on this thread: checked on another core as the faces came,
      // a strip took longer (its faces and the guard's lists crossed between the cores).
      stitcher_.emit_moved(piece, old, step);
      stitcher_.stitch(old, piece);
      const std::vector<std::int32_t> found =
          fold_guard_.folded_vertices(mesh_, first_face, first_inserted);
      folded.insert(folded.end(), found.begin(), found.end());
    }
    if (folded.empty() || round + 1 == kRounds) {
      if (!folded.empty()) report_.folds_left += folded.size();
      fold_guard_.accept(mesh_, faces);
      for (auto& piece : pieces) out.push_back(std::move(piece));
      return;
    }
    // Undo the round and take the folded vertices out of their pieces.
    mesh_.truncate(vertices, faces);
    report_.skipped_vertex_steps = skipped;
    report_.triangles_at_row_changes = row_changes;
    report_.triangles_at_waiting_vertices = waiting;
    std::sort(folded.begin(), folded.end());
    std::vector<Front<N>> next;
    for (std::size_t p = 0; p < pieces.size(); ++p) {
      Front<N>& linked = pieces[p];
      std::vector<char> keep(linked.v.size(), 1), cut(linked.v.size(), 0);
      for (std::size_t i = 0; i < linked.v.size(); ++i) {
        FrontVertex<N>& fv = linked.v[i];
        if (std::binary_search(folded.begin(), folded.end(), fv.mesh)) {
          keep[i] = 0;
          ++report_.fold_rips;
        }
        // A mesh vertex emit_moved gave it this round is gone: it stands for its origin's again
        // (it was a copy of that vertex before; inserted vertices are older than `vertices`).
        if (fv.origin >= 0 && fv.mesh >= 0 && static_cast<std::size_t>(fv.mesh) >= vertices) {
          const FrontVertex<N>& from = old.v[static_cast<std::size_t>(fv.origin)];
          fv.mesh = from.mesh;
          fv.anchor = from.anchor;
        }
      }
      for (auto& piece : split_(std::move(pieces[p]), keep, cut)) next.push_back(std::move(piece));
    }
    pieces = std::move(next);
  }
}

template class StripLinker<3>;
template class StripLinker<4>;

}  // namespace orthofront
