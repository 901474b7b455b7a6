#pragma once
/// The edge length ℓ a surface takes when --edge is not given: on gridded data the grid's cell
/// size. The default in world units means nothing to data in metres or degrees (on a 0.3 m
/// domain 0.05 makes a surface of a few faces, or none), and an edge finer than a cell
/// resolves nothing the data holds.
#include <nlohmann/json.hpp>
#include <string>

#include "orthofront/field/grid.h"

namespace orthofront::jobs {

/// Of each axis with more than one sample its median spacing (so a rectilinear grid's refined
/// wall cells do not set it alone); of those the smaller in 2D, the middle one in 3D (so the
/// thin vertical layers of ocean and atmosphere grids, metres against kilometres or degrees,
/// do not set it either).
double grid_cell_size(const GridGeometry& grid);

/// ℓ and where it came from, for summaries and reports.
struct EdgeChoice {
  double edge = 0;
  std::string source;  ///< "--edge", "grid cell" or "default"
};

/// `edge` where --edge was given (`given`) or there is no grid (analytic fields), else the
/// grid's cell size.
EdgeChoice choose_edge(double edge, bool given, const GridGeometry* grid);

/// The report's `edge` and `edge_source`.
void add_edge_keys(nlohmann::json& report, const EdgeChoice& choice);

/// One line for the summary where ℓ was not given: its value, where it came from and the flag
/// that sets it; empty where it was given.
std::string edge_note(const EdgeChoice& choice);

}  // namespace orthofront::jobs
