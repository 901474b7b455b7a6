#pragma once
/// Mesh quality measured the paper's way, plus validity checks (folds, non-manifold edges,
/// T-junctions, degenerate faces, orientation).
#include <cstdint>
#include <vector>

#include "orthofront/mesh/mesh.h"

namespace orthofront {

struct Histogram {
  double lo = 0, hi = 1;                 ///< value range; values outside are clamped into end bins
  std::vector<std::uint64_t> counts;     ///< equal-width bins over [lo, hi]
};

struct QualityOptions {
  int angle_bins = 36;                   ///< quad-angle histogram over [0°, 180°]
  int edge_bins = 40;                    ///< edge-ratio histogram over [-1, 1]
  int triangle_bins = 18;                ///< triangle min-angle histogram over [0°, 90°]
  double fold_cos = 0.0;                 ///< adjacent faces with normal dot below this are folds
  /// A face is degenerate when it repeats a vertex, or its area is at most this share of its own
  /// longest edge squared (a sliver or needle whatever its size; a small well-shaped face, as
  /// near a critical point, is not degenerate).
  double degenerate_area = 1e-12;
};

struct QualityReport {
  std::size_t vertices = 0, faces = 0, quads = 0, triangles = 0;
  std::size_t measured_quads = 0;         ///< quads with four non-zero edges (in the statistics)
  std::size_t measured_triangles = 0;     ///< triangles with three non-zero edges
  double quad_share = 0;                  ///< quads / faces
  double quad_angles_within_10 = 0;       ///< share of quad interior angles within 90° ± 10°
  double quad_angle_mean_abs_dev = 0;     ///< mean |angle - 90°|, degrees
  double quad_angle_abs_dev_p90 = 0;      ///< 90th percentile of |angle - 90°|, degrees
  double edge_spread_median = 0;          ///< median |1 - l_i / l_avg| over quad edges
  double edge_spread_mean = 0;
  double edge_spread_p90 = 0;             ///< 90th percentile of |1 - l_i / l_avg|
  double triangle_min_angle_median = 0;   ///< degrees
  double triangle_min_angle_p05 = 0;      ///< 5th percentile of the triangles' minimum angles, degrees
  double triangles_below_10deg = 0;       ///< share of triangles whose min angle < 10°
  std::size_t folds = 0;                  ///< interior edges whose two faces have opposite normals
  std::size_t non_manifold_edges = 0;     ///< edges with more than two faces
  std::size_t inconsistent_edges = 0;     ///< interior edges traversed twice in the same direction
  std::size_t t_junctions = 0;            ///< boundary vertices lying inside another boundary edge
  std::size_t degenerate_faces = 0;       ///< repeated index or (near) zero area
  std::size_t boundary_edges = 0;
  double longest_edge = 0;                ///< of any face, degenerate ones included
  Histogram quad_angles;                  ///< degrees; 4 * measured_quads values
  Histogram edge_ratio;                   ///< 1 - l_i / l_avg; 4 * measured_quads values
  Histogram triangle_min_angle;           ///< degrees; measured_triangles values
};

/// Quality of a polygon mesh. Quads: four interior angles and, per edge, 1 - l_i / l_avg of its
/// four edges; triangles: minimum angle. O(V + F): edges are found by a counting sort on their
/// smaller vertex. Folds compare normals after undoing an orientation flip, so a flipped face
/// counts as inconsistent, not as folded.
/// Throws InvalidArgument for a face whose size is not 3 or 4 or whose index is out of range.
QualityReport measure_quality(const Mesh& mesh, const QualityOptions& options = {});

}  // namespace orthofront
