#pragma once
/// Folds caught at stitch time: a face of the strip just stitched whose normal turns by more than
/// 90° from a neighbour's across a shared edge (the quality measure's definition of a fold), the
/// neighbour being another face of that strip or a face of the surface so far.
#include <cstddef>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "orthofront/mesh/mesh.h"

namespace orthofront {

class FoldGuard {
 public:
  /// Starts from a surface made elsewhere (a restored engine): every face of `mesh` is accepted.
  void rebuild(const Mesh& mesh);

  /// Mesh vertices made by the part just stitched (index >= first_new_vertex) that stand on a
  /// fold of faces [first_face, end): the new ends of a folded edge, or else the new corners of
  /// the folded face. Empty when those faces fold over nothing.
  std::vector<std::int32_t> folded_vertices(const Mesh& mesh, std::size_t first_face,
                                            std::size_t first_new_vertex);

  /// Faces [first_face, end) are part of the surface: later strips are checked against them.
  void accept(const Mesh& mesh, std::size_t first_face);

 private:
  struct EdgeFace {
    std::uint32_t face;
    bool forward;  ///< the face walks the edge from its lower to its higher vertex index
  };
  /// Edges of accepted faces that have one face so far: the surface's boundary, which holds
  /// every edge a new strip can share with it (the front's rows among them).
  std::unordered_map<std::uint64_t, EdgeFace> open_;
  std::unordered_multimap<std::uint64_t, EdgeFace> strip_;  ///< scratch: the faces checked
};

}  // namespace orthofront
