#include "orthofront/field/cell_locator.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_scan.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <utility>

namespace orthofront {

namespace {

struct CellBox {
  std::array<double, 3> lo, hi;
};

// Exclusive prefix sum of counts (in place); returns the total.
std::int64_t exclusive_scan(std::vector<std::int64_t>& v) {
  return tbb::parallel_scan(
      tbb::blocked_range<std::size_t>(0, v.size()), std::int64_t{0},
      [&](const tbb::blocked_range<std::size_t>& r, std::int64_t sum, bool final) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
          const std::int64_t count = v[i];
          if (final) v[i] = sum;
          sum += count;
        }
        return sum;
      },
      std::plus<>());
}

// Bins per axis for `count` bins over a box of the given extents, as near cubic as the box
// allows; an axis far thinner than the others (a mesh one cell thick) gets one bin.
std::array<int, 3> bin_dims(const std::array<double, 3>& extent, double count) {
  const double largest = std::max({extent[0], extent[1], extent[2]});
  double volume = 1;
  int active = 0;
  for (double e : extent)
    if (e > 1e-3 * largest) volume *= e, ++active;
  const double per_length = std::pow(std::max(count, 1.0) / volume, 1.0 / std::max(active, 1));
  std::array<int, 3> dims{1, 1, 1};
  for (std::size_t a = 0; a < 3; ++a)
    if (extent[a] > 1e-3 * largest)
      dims[a] = static_cast<int>(std::clamp(std::ceil(extent[a] * per_length), 1.0, 4096.0));
  return dims;
}

// The bin range [first, last] along each axis of a box in a grid of `dims` bins of size `size`
// from `origin`.
void bin_range(const CellBox& b, const double* origin, const double* size, const int* dims,
               int first[3], int last[3]) {
  for (std::size_t a = 0; a < 3; ++a) {
    const auto clampi = [&](double u) {
      return static_cast<int>(std::clamp(std::floor(u), 0.0, static_cast<double>(dims[a] - 1)));
    };
    first[a] = clampi((b.lo[a] - origin[a]) / size[a]);
    last[a] = clampi((b.hi[a] - origin[a]) / size[a]);
  }
}

}  // namespace

CellLocator::CellLocator(const UnstructuredMesh& mesh, const Options& options)
    : neighbours_(mesh) {
  const std::size_t cells = mesh.cell_count();
  std::vector<CellBox> boxes(cells);
  tbb::parallel_for(std::size_t{0}, cells, [&](std::size_t c) {
    CellBox& b = boxes[c];
    b.lo.fill(std::numeric_limits<double>::infinity());
    b.hi.fill(-std::numeric_limits<double>::infinity());
    const std::int32_t* ids = mesh.cell_points(c);
    for (int i = 0; i < cell::point_count(mesh.shapes[c]); ++i)
      for (std::size_t a = 0; a < 3; ++a) {
        const double x = mesh.points[3 * static_cast<std::size_t>(ids[i]) + a];
        b.lo[a] = std::min(b.lo[a], x);
        b.hi[a] = std::max(b.hi[a], x);
      }
  });

  // The top level: a uniform grid over the mesh's box, slightly enlarged so that points on its
  // far faces fall in the last bins.
  const Box<3> box = mesh.bounds();
  std::array<double, 3> extent{};
  for (int a = 0; a < 3; ++a) extent[static_cast<std::size_t>(a)] = box.hi[a] - box.lo[a];
  const std::array<int, 3> top =
      bin_dims(extent, static_cast<double>(cells) / options.cells_per_top_bin);
  CellLocatorView& v = view_;
  for (int a = 0; a < 3; ++a) {
    const double e = std::max(extent[static_cast<std::size_t>(a)], 1e-300);
    v.origin[a] = box.lo[a] - 1e-9 * e;
    v.bin[a] = e * (1 + 2e-9) / top[static_cast<std::size_t>(a)];
    v.top[a] = top[static_cast<std::size_t>(a)];
  }
  const std::size_t top_bins = static_cast<std::size_t>(v.top[0]) * static_cast<std::size_t>(v.top[1]) *
                               static_cast<std::size_t>(v.top[2]);
  const auto top_index = [&](int i, int j, int k) {
    return static_cast<std::size_t>(i) +
           static_cast<std::size_t>(v.top[0]) *
               (static_cast<std::size_t>(j) + static_cast<std::size_t>(v.top[1]) * static_cast<std::size_t>(k));
  };

  // Cells per top bin (a cell counts in every bin its box touches).
  std::vector<std::int64_t> per_top(top_bins, 0);
  {
    std::vector<std::int64_t> touches(cells);
    tbb::parallel_for(std::size_t{0}, cells, [&](std::size_t c) {
      int f[3], l[3];
      bin_range(boxes[c], v.origin, v.bin, v.top, f, l);
      touches[c] = std::int64_t{l[0] - f[0] + 1} * (l[1] - f[1] + 1) * (l[2] - f[2] + 1);
    });
    const std::int64_t total = exclusive_scan(touches);
    std::vector<std::int64_t> pair_bin(static_cast<std::size_t>(total));
    tbb::parallel_for(std::size_t{0}, cells, [&](std::size_t c) {
      int f[3], l[3];
      bin_range(boxes[c], v.origin, v.bin, v.top, f, l);
      auto out = static_cast<std::size_t>(touches[c]);
      for (int k = f[2]; k <= l[2]; ++k)
        for (int j = f[1]; j <= l[1]; ++j)
          for (int i = f[0]; i <= l[0]; ++i) pair_bin[out++] = static_cast<std::int64_t>(top_index(i, j, k));
    });
    for (std::int64_t b : pair_bin) ++per_top[static_cast<std::size_t>(b)];
  }

  // Leaf grids: each top bin split for about cells_per_leaf cells a leaf.
  leaf_dims_.resize(3 * top_bins);
  leaf_first_.resize(top_bins + 1);
  tbb::parallel_for(std::size_t{0}, top_bins, [&](std::size_t b) {
    std::array<double, 3> bin_extent{v.bin[0], v.bin[1], v.bin[2]};
    for (std::size_t a = 0; a < 3; ++a)
      if (v.top[a] == 1 && extent[a] <= 1e-3 * std::max({extent[0], extent[1], extent[2]}))
        bin_extent[a] = 0;  // a flat axis stays one leaf thick
    const std::array<int, 3> d =
        bin_dims(bin_extent, static_cast<double>(per_top[b]) / options.cells_per_leaf);
    for (std::size_t a = 0; a < 3; ++a) leaf_dims_[3 * b + a] = per_top[b] == 0 ? 1 : d[a];
    leaf_first_[b] = std::int64_t{leaf_dims_[3 * b]} * leaf_dims_[3 * b + 1] * leaf_dims_[3 * b + 2];
  });
  leaf_first_[top_bins] = 0;
  const std::int64_t leaves = exclusive_scan(leaf_first_);
  leaf_first_[top_bins] = leaves;

  // (leaf, cell) pairs, sorted so that each leaf lists its cells in increasing order.
  std::vector<std::int64_t> touches(cells);
  const auto for_each_leaf = [&](std::size_t c, auto&& visit) {
    int f[3], l[3];
    bin_range(boxes[c], v.origin, v.bin, v.top, f, l);
    for (int k = f[2]; k <= l[2]; ++k)
      for (int j = f[1]; j <= l[1]; ++j)
        for (int i = f[0]; i <= l[0]; ++i) {
          const std::size_t b = top_index(i, j, k);
          const double origin[3] = {v.origin[0] + i * v.bin[0], v.origin[1] + j * v.bin[1],
                                    v.origin[2] + k * v.bin[2]};
          const int* d = leaf_dims_.data() + 3 * b;
          const double size[3] = {v.bin[0] / d[0], v.bin[1] / d[1], v.bin[2] / d[2]};
          int lf[3], ll[3];
          bin_range(boxes[c], origin, size, d, lf, ll);
          for (int z = lf[2]; z <= ll[2]; ++z)
            for (int y = lf[1]; y <= ll[1]; ++y)
              for (int x = lf[0]; x <= ll[0]; ++x)
                visit(leaf_first_[b] + x + std::int64_t{d[0]} * (y + std::int64_t{d[1]} * z));
        }
  };
  tbb::parallel_for(std::size_t{0}, cells, [&](std::size_t c) {
    std::int64_t n = 0;
    for_each_leaf(c, [&](std::int64_t) { ++n; });
    touches[c] = n;
  });
  const std::int64_t pairs = exclusive_scan(touches);
  std::vector<std::pair<std::int64_t, std::int32_t>> leaf_cell(static_cast<std::size_t>(pairs));
  tbb::parallel_for(std::size_t{0}, cells, [&](std::size_t c) {
    auto out = static_cast<std::size_t>(touches[c]);
    for_each_leaf(c, [&](std::int64_t leaf) {
      leaf_cell[out++] = {leaf, static_cast<std::int32_t>(c)};
    });
  });
  tbb::parallel_sort(leaf_cell.begin(), leaf_cell.end());
  leaf_cells_.resize(leaf_cell.size());
  leaf_cells_first_.assign(static_cast<std::size_t>(leaves) + 1, 0);
  for (std::size_t i = 0; i < leaf_cell.size(); ++i) {
    leaf_cells_[i] = leaf_cell[i].second;
    ++leaf_cells_first_[static_cast<std::size_t>(leaf_cell[i].first) + 1];
  }
  for (std::size_t i = 1; i < leaf_cells_first_.size(); ++i)
    leaf_cells_first_[i] += leaf_cells_first_[i - 1];

  v.points = mesh.points.data();
  v.connectivity = mesh.connectivity.data();
  v.offsets = mesh.offsets.data();
  v.shapes = mesh.shapes.data();
  v.neighbours = neighbours_.data();
  v.leaf_dims = leaf_dims_.data();
  v.leaf_first = leaf_first_.data();
  v.leaf_cells_first = leaf_cells_first_.data();
  v.leaf_cells = leaf_cells_.data();
}

std::size_t CellLocator::bytes() const {
  return leaf_dims_.size() * sizeof(std::int32_t) + leaf_first_.size() * sizeof(std::int64_t) +
         leaf_cells_first_.size() * sizeof(std::int64_t) +
         leaf_cells_.size() * sizeof(std::int32_t);
}

}  // namespace orthofront
