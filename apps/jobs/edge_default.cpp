#include "jobs/edge_default.h"

#include <algorithm>
#include <cstdio>
#include <limits>
#include <vector>

namespace orthofront::jobs {

double grid_cell_size(const GridGeometry& grid) {
  std::vector<double> sides;
  for (int a = 0; a < grid.dimension; ++a) {
    const auto n = grid.size[static_cast<std::size_t>(a)];
    if (n < 2) continue;
    double spacing = grid.spacing[a];
    if (grid.rectilinear()) {
      const std::vector<double>& axis = grid.axes[static_cast<std::size_t>(a)];
      std::vector<double> widths(axis.size() - 1);
      for (std::size_t i = 0; i + 1 < axis.size(); ++i) widths[i] = axis[i + 1] - axis[i];
      std::nth_element(widths.begin(), widths.begin() + static_cast<std::ptrdiff_t>(widths.size() / 2),
                       widths.end());
      spacing = widths[widths.size() / 2];
    }
    if (spacing > 0) sides.push_back(spacing);
  }
  if (sides.empty()) return std::numeric_limits<double>::infinity();
  std::sort(sides.begin(), sides.end());
  return sides.size() == 3 ? sides[1] : sides[0];
}

EdgeChoice choose_edge(double edge, bool given, const GridGeometry* grid) {
  if (given) return {edge, "--edge"};
  if (grid != nullptr) {
    const double cell = grid_cell_size(*grid);
    if (cell > 0 && cell < std::numeric_limits<double>::infinity()) return {cell, "grid cell"};
  }
  return {edge, "default"};
}

void add_edge_keys(nlohmann::json& report, const EdgeChoice& choice) {
  report["edge"] = choice.edge;
  report["edge_source"] = choice.source;
}

std::string edge_note(const EdgeChoice& choice) {
  if (choice.source == "--edge") return {};
  char text[160];
  std::snprintf(text, sizeof text, "Edge length %g: %s (--edge sets it).\n", choice.edge,
                choice.source == "grid cell" ? "the grid's cell size" : "the default");
  return text;
}

}  // namespace orthofront::jobs
