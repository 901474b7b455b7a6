#pragma once
/// Closing the gap behind a rip: where a surface tore (at an obstacle, a rip, a no-data cut) and
/// its two halves meet again downstream, their boundaries run side by side, in opposite
/// directions, a small distance apart. Faces zip such stretches together (Stalling's closing;
/// the paper leaves the gap open).
#include <cstddef>
#include <cstdint>
#include <vector>

#include "orthofront/mesh/mesh.h"

namespace orthofront {

/// An edge with one face, as that face walks it.
struct BoundaryEdge {
  std::int32_t from = 0, to = 0, face = 0;
};

/// The mesh's boundary edges (O(V + F)), in order of their lower vertex.
std::vector<BoundaryEdge> boundary_edges(const Mesh& mesh);

struct GapReport {
  std::size_t stretches = 0;  ///< boundary stretches zipped together
  std::size_t faces = 0;      ///< faces added
  std::size_t refused = 0;    ///< stretches left open because a new face would fold or be flat
};

/// Zips together every two boundary stretches of `mesh` that run in opposite directions closer
/// than `distance` to each other, at least `min_length` long on each side. A boundary vertex is
/// paired with the nearest boundary vertex across (further than 4 `distance` along the boundary
/// from it, with an antiparallel boundary direction); runs of consecutive pairs become strips of
/// quads and triangles, placed as the engine's stitch places them, oriented as their neighbours.
/// A stretch whose faces would fold over a neighbour (normals more than 90° apart) or have no
/// area is left open (counted as refused). Vertices are not moved or added.
GapReport close_gaps(Mesh& mesh, double distance, double min_length);
/// The same with the boundary known already (e.g. kept by the fold guard as it stitched).
GapReport close_gaps(Mesh& mesh, double distance, double min_length,
                      const std::vector<BoundaryEdge>& boundary);

}  // namespace orthofront
