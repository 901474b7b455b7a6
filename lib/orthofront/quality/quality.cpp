#include "orthofront/quality/quality.h"

#include <Eigen/Geometry>  // cross products
#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <numbers>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_reduce.h>

#include "orthofront/error.h"
#include "orthofront/huge_pages.h"

namespace orthofront {
namespace {

constexpr double kDegrees = 180.0 / std::numbers::pi;

/// Leaves elements default-initialized (trivial ones untouched): the buffers of a mesh of
/// millions of faces are then first touched, and their pages faulted in, by the parallel loops
/// that fill them, not zeroed by one thread beforehand (which kept the measurement from scaling).
/// Large ones are on huge pages (HugePageAllocator).
template <class T>
struct UninitializedAllocator : HugePageAllocator<T> {
  using value_type = T;
  UninitializedAllocator() = default;
  template <class U>
  UninitializedAllocator(const UninitializedAllocator<U>&) noexcept {}
  template <class U>
  struct rebind {
    using other = UninitializedAllocator<U>;
  };
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    if constexpr (sizeof...(Args) == 0) {
      ::new (static_cast<void*>(p)) U;
    } else {
      ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
    }
  }
};
template <class T>
using Buffer = std::vector<T, UninitializedAllocator<T>>;

/// n elements, unwritten, on huge pages where the system gives them.
template <class T>
Buffer<T> untouched(std::size_t n) {
  Buffer<T> b;
  b.resize(n);
  return b;
}

/// body(i) for i in [0, n), in parallel blocks.
template <class F>
void for_each_index(std::size_t n, const F& body) {
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t i = range.begin(); i < range.end(); ++i) body(i);
                    });
}

/// Open-addressing hash map from 64-bit keys to 32-bit values (grid cells of the T-junction
/// search). Sized once from an upper bound on the number of keys, so it never rehashes.
class FlatMap {
 public:
  explicit FlatMap(std::size_t max_keys)
      : keys_(std::bit_ceil(std::max<std::size_t>(16, max_keys + max_keys / 2 + 1)), kEmpty),
        values_(keys_.size()),
        mask_(keys_.size() - 1) {}

  /// Value stored under key, after storing `value` there if the key was absent.
  /// The flag says whether it was inserted.
  std::pair<std::uint32_t, bool> emplace(std::uint64_t key, std::uint32_t value) {
    for (std::size_t slot = hash(key) & mask_;; slot = (slot + 1) & mask_) {
      if (keys_[slot] == key) return {values_[slot], false};
      if (keys_[slot] == kEmpty) {
        keys_[slot] = key;
        values_[slot] = value;
        return {value, true};
      }
    }
  }

  const std::uint32_t* find(std::uint64_t key) const {
    for (std::size_t slot = hash(key) & mask_;; slot = (slot + 1) & mask_) {
      if (keys_[slot] == key) return &values_[slot];
      if (keys_[slot] == kEmpty) return nullptr;
    }
  }

 private:
  static constexpr std::uint64_t kEmpty = ~std::uint64_t{0};  // cell keys use 63 bits

  // splitmix64 finalizer: neighbouring cells must not cluster under linear probing.
  static std::size_t hash(std::uint64_t x) {
    x ^= x >> 30;
    x *= 0xbf58476d1ce4e5b9ULL;
    x ^= x >> 27;
    x *= 0x94d049bb133111ebULL;
    x ^= x >> 31;
    return static_cast<std::size_t>(x);
  }

  std::vector<std::uint64_t> keys_;
  std::vector<std::uint32_t> values_;
  std::size_t mask_;
};

/// What the edges of a mesh show: interior edges with more than two faces, traversed twice the
/// same way, or between faces whose normals oppose; and the boundary edges.
struct EdgeFigures {
  std::size_t non_manifold = 0, inconsistent = 0, folds = 0;
  /// (smaller, larger vertex index), ordered by the smaller, then the larger.
  std::vector<std::array<std::int32_t, 2>> boundary;
};

/// Undirected edges with the faces using them, found by their smaller vertex index: each face
/// edge goes into the bucket of that index (a counting sort, O(V + F)); a bucket holds a handful
/// of uses, which a small sort orders by the other index, then the face. Each bucket's edges are
/// counted as soon as it is sorted: no list of edges is made (for a frame of millions of faces
/// that list alone meant half a gigabyte of fresh pages). Buckets are counted, filled and sorted
/// in parallel, in fixed blocks joined in order, so nothing depends on the schedule.
/// `normals`: unit face normals, zero for degenerate faces (kept out of folds).
EdgeFigures scan_edges(const Mesh& mesh, const Buffer<Vec3>& normals, double fold_cos) {
  struct Use {
    std::int32_t other;
    std::uint32_t face_way;  ///< face * 2 + 1 where the face traverses smaller -> other
  };
  const std::size_t nv = mesh.positions.size();
  const std::size_t nf = mesh.faces.size();
  Buffer<std::uint32_t> fill = untouched<std::uint32_t>(nv + 1);
  const auto bump = [&](std::size_t v) {
    return std::atomic_ref<std::uint32_t>(fill[v]).fetch_add(1, std::memory_order_relaxed);
  };
  for_each_index(nv + 1, [&](std::size_t v) { fill[v] = 0; });
  for_each_index(nf, [&](std::size_t f) {
    const Face& face = mesh.faces[f];
    for (int i = 0; i < face.size; ++i) {
      const std::int32_t u = face.v[i], w = face.v[(i + 1) % face.size];
      if (u != w) bump(static_cast<std::size_t>(std::min(u, w)) + 1);
    }
  });
  Buffer<std::uint32_t> start = untouched<std::uint32_t>(nv + 1);
  start[0] = 0;
  for (std::size_t v = 0; v < nv; ++v) start[v + 1] = start[v] + fill[v + 1];
  for_each_index(nv, [&](std::size_t v) { fill[v] = start[v]; });
  Buffer<Use> uses = untouched<Use>(start[nv]);
  for_each_index(nf, [&](std::size_t f) {
    const Face& face = mesh.faces[f];
    for (int i = 0; i < face.size; ++i) {
      const std::int32_t u = face.v[i], w = face.v[(i + 1) % face.size];
      if (u == w) continue;
      const std::uint32_t slot = bump(static_cast<std::size_t>(std::min(u, w)));
      uses[slot] = Use{std::max(u, w), static_cast<std::uint32_t>(f) * 2 + (u < w ? 1 : 0)};
    }
  });

  const auto before = [](const Use& x, const Use& y) {
    return x.other != y.other ? x.other < y.other : x.face_way < y.face_way;
  };
  constexpr std::size_t kBlock = 16384;  // buckets
  std::vector<EdgeFigures> blocks((nv + kBlock - 1) / kBlock);
  tbb::parallel_for(std::size_t{0}, blocks.size(), [&](std::size_t b) {
    EdgeFigures& out = blocks[b];
    for (std::size_t a = b * kBlock; a < std::min(nv, (b + 1) * kBlock); ++a) {
      const auto first = uses.begin() + start[a], last = uses.begin() + start[a + 1];
      if (last - first > 32) {
        std::sort(first, last, before);
      } else {
        for (auto it = first; it != last; ++it) {  // insertion sort: buckets are tiny
          const Use use = *it;
          auto hole = it;
          for (; hole != first && before(use, *(hole - 1)); --hole) *hole = *(hole - 1);
          *hole = use;
        }
      }
      for (auto it = first; it != last;) {
        auto group_end = it + 1;
        while (group_end != last && group_end->other == it->other) ++group_end;
        const auto count = group_end - it;
        if (count == 1) {
          out.boundary.push_back({static_cast<std::int32_t>(a), it->other});
        } else if (count > 2) {
          ++out.non_manifold;
        } else {
          const bool inconsistent = ((it->face_way ^ (it + 1)->face_way) & 1) == 0;
          out.inconsistent += inconsistent;
          const Vec3& n0 = normals[it->face_way / 2];
          const Vec3& n1 = normals[(it + 1)->face_way / 2];
          if (n0.squaredNorm() != 0 && n1.squaredNorm() != 0) {
            // Undo an orientation flip so that only geometry decides.
            const double dot = inconsistent ? -n0.dot(n1) : n0.dot(n1);
            out.folds += dot < fold_cos;
          }
        }
        it = group_end;
      }
    }
  });
  EdgeFigures all;
  std::size_t boundary = 0;
  for (const EdgeFigures& b : blocks) boundary += b.boundary.size();
  all.boundary.reserve(boundary);
  for (const EdgeFigures& b : blocks) {
    all.non_manifold += b.non_manifold;
    all.inconsistent += b.inconsistent;
    all.folds += b.folds;
    all.boundary.insert(all.boundary.end(), b.boundary.begin(), b.boundary.end());
  }
  return all;
}

Histogram make_histogram(double lo, double hi, int bins) {
  Histogram h;
  h.lo = lo;
  h.hi = hi;
  h.counts.assign(static_cast<std::size_t>(std::max(1, bins)), 0);
  return h;
}

void add(Histogram& h, double x) {
  if (!std::isfinite(x)) return;
  const auto n = h.counts.size();
  const double u = (x - h.lo) / (h.hi - h.lo) * static_cast<double>(n);
  std::size_t bin = 0;
  if (u >= static_cast<double>(n)) {
    bin = n - 1;
  } else if (u > 0) {
    bin = static_cast<std::size_t>(u);
  }
  ++h.counts[bin];
}

// A key whose unsigned order is the order of the doubles (negatives below positives).
std::uint64_t order_key(double x) {
  const auto bits = std::bit_cast<std::uint64_t>(x);
  return (bits >> 63) != 0 ? ~bits : bits | (std::uint64_t{1} << 63);
}

/// Values kept in parts (one stretch per block of faces, in face order), never joined: a frame
/// of millions of faces would copy hundreds of megabytes, on one thread, to make one list.
using Parts = std::vector<std::span<const double>>;

std::size_t total_size(const Parts& parts) {
  std::size_t n = 0;
  for (const auto& p : parts) n += p.size();
  return n;
}

/// The k-th and (k+1)-th smallest (from 0) of many values, without reordering them: the bins of
/// their top 16 key bits are found from one histogram counted in parallel, then only those bins'
/// values (gathered in parallel) are ordered. The second is the first where k is the last.
std::pair<double, double> kth_smallest_pair(const Parts& parts, std::size_t k) {
  constexpr int kBits = 16;
  constexpr std::size_t kBins = std::size_t{1} << kBits;
  const auto bin_of = [](double x) { return static_cast<std::size_t>(order_key(x) >> (64 - kBits)); };
  tbb::enumerable_thread_specific<std::vector<std::size_t>> local(
      [] { return std::vector<std::size_t>(kBins, 0); });
  tbb::parallel_for(std::size_t{0}, parts.size(), [&](std::size_t p) {
    std::vector<std::size_t>& h = local.local();
    for (const double x : parts[p]) ++h[bin_of(x)];
  });
  std::vector<std::size_t> counts(kBins, 0);
  for (const auto& h : local)
    for (std::size_t b = 0; b < kBins; ++b) counts[b] += h[b];
  const std::size_t n = total_size(parts);
  const std::size_t k1 = std::min(k + 1, n - 1);
  // Bins of the two, and how many values lie below the first bin.
  std::size_t first = 0, below = 0;
  while (below + counts[first] <= k) below += counts[first++];
  std::size_t last = first, below_last = below;
  while (below_last + counts[last] <= k1) below_last += counts[last++];
  std::vector<std::vector<double>> found(parts.size());
  tbb::parallel_for(std::size_t{0}, parts.size(), [&](std::size_t p) {
    for (const double x : parts[p]) {
      const std::size_t b = bin_of(x);
      if (b == first || b == last) found[p].push_back(x);
    }
  });
  // The values of both bins, in bin order: [first's values, last's values].
  std::vector<double> in_bins;
  in_bins.reserve(counts[first] + (last != first ? counts[last] : 0));
  for (const auto& f : found) in_bins.insert(in_bins.end(), f.begin(), f.end());
  const auto split = std::partition(in_bins.begin(), in_bins.end(),
                                    [&](double x) { return bin_of(x) == first; });
  const auto nth = [&](std::size_t rank) {
    // rank within all values; its bin's values start at `below` (first) or `below_last` (last).
    const bool in_first = rank < below + counts[first];
    const auto begin = in_first ? in_bins.begin() : split;
    const auto end = in_first ? split : in_bins.end();
    const auto at = begin + static_cast<std::ptrdiff_t>(rank - (in_first ? below : below_last));
    std::nth_element(begin, at, end);
    return *at;
  };
  const double a = nth(k);
  return {a, k1 == k ? a : nth(k1)};
}

/// q-quantile with linear interpolation between order statistics (the same for any order of
/// the values, so of the parts joined).
double quantile(const Parts& parts, double q) {
  const std::size_t n = total_size(parts);
  if (n == 0) return 0;
  const double pos = q * static_cast<double>(n - 1);
  const auto k = static_cast<std::size_t>(pos);
  // Below this, one copy and a selection are quicker than the histogram.
  constexpr std::size_t kManyValues = std::size_t{1} << 16;
  if (n >= kManyValues) {
    const auto [lo, hi] = kth_smallest_pair(parts, k);
    if (k + 1 >= n) return lo;
    return lo + (pos - static_cast<double>(k)) * (hi - lo);
  }
  std::vector<double> values;
  values.reserve(n);
  for (const auto& p : parts) values.insert(values.end(), p.begin(), p.end());
  const auto kth = values.begin() + static_cast<std::ptrdiff_t>(k);
  std::nth_element(values.begin(), kth, values.end());
  const double lo = *kth;
  if (k + 1 >= values.size()) return lo;
  const double hi = *std::min_element(kth + 1, values.end());
  return lo + (pos - static_cast<double>(k)) * (hi - lo);
}

/// Angle between two vectors in degrees; atan2 stays accurate near 0° and 180°.
double angle_deg(const Vec3& u, const Vec3& w) {
  return std::atan2(u.cross(w).norm(), u.dot(w)) * kDegrees;
}

void validate(const Mesh& mesh) {
  // Edge uses are counted, and faces numbered twice over, in 32 bits.
  constexpr std::size_t kMaxFaces = (std::size_t{1} << 30) - 1;
  if (mesh.faces.size() > kMaxFaces)
    throw InvalidArgument("measure_quality: " + std::to_string(mesh.faces.size()) +
                          " faces, more than the " + std::to_string(kMaxFaces) + " it measures");
  const auto n = static_cast<std::int64_t>(mesh.positions.size());
  const auto bad = [n](const Face& face) {
    if (face.size != 3 && face.size != 4) return true;
    for (int i = 0; i < face.size; ++i)
      if (face.v[i] < 0 || face.v[i] >= n) return true;
    return false;
  };
  // Checked in parallel; only a bad mesh is walked again for the first bad face to name.
  const bool any_bad = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, mesh.faces.size(), 16384), false,
      [&](const tbb::blocked_range<std::size_t>& range, bool found) {
        for (std::size_t f = range.begin(); f < range.end() && !found; ++f) found = bad(mesh.faces[f]);
        return found;
      },
      [](bool a, bool b) { return a || b; });
  if (!any_bad) return;
  for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
    const Face& face = mesh.faces[f];
    if (face.size != 3 && face.size != 4) {
      throw InvalidArgument("measure_quality: face " + std::to_string(f) + " has size " +
                            std::to_string(face.size) + " (expected 3 or 4)");
    }
    for (int i = 0; i < face.size; ++i) {
      if (face.v[i] < 0 || face.v[i] >= n) {
        throw InvalidArgument("measure_quality: face " + std::to_string(f) + " has vertex index " +
                              std::to_string(face.v[i]) + " outside [0, " + std::to_string(n) +
                              ")");
      }
    }
  }
}

bool has_repeated_index(const Face& face) {
  for (int i = 0; i < face.size; ++i) {
    for (int j = i + 1; j < face.size; ++j) {
      if (face.v[i] == face.v[j]) return true;
    }
  }
  return false;
}

/// Boundary vertices lying strictly inside a boundary edge they are not an endpoint of. Edges go
/// into a uniform grid (cell ~ mean boundary edge length) and each vertex tests only its cell, so
/// the cost grows with the boundary size, not its square.
std::size_t count_t_junctions(const Mesh& mesh,
                              const std::vector<std::array<std::int32_t, 2>>& boundary) {
  if (boundary.empty()) return 0;
  const auto& p = mesh.positions;
  constexpr double kRel = 1e-6;

  Vec3 lo = p[boundary[0][0]], hi = lo;
  double total_length = 0;
  for (const auto& [ia, ib] : boundary) {
    const Vec3& a = p[ia];
    const Vec3& b = p[ib];
    lo = lo.cwiseMin(a).cwiseMin(b);
    hi = hi.cwiseMax(a).cwiseMax(b);
    total_length += (b - a).norm();
  }
  double cell = total_length / static_cast<double>(boundary.size());
  if (!(cell > 0) || !std::isfinite(cell)) return 0;
  // 21 bits per axis in the cell key; a coarser cell only costs time.
  constexpr double kMaxCells = double{1 << 20};
  cell = std::max(cell, (hi - lo).maxCoeff() / kMaxCells);
  const Vec3 origin = lo - Vec3::Constant(cell);  // margin for the tolerance around edges
  const auto cell_of = [&](const Vec3& x) {
    const Vec3 c = (x - origin) / cell;
    std::array<std::uint64_t, 3> idx{};
    for (int k = 0; k < 3; ++k) {
      idx[k] = static_cast<std::uint64_t>(std::clamp(std::floor(c[k]), 0.0, 2.0 * kMaxCells - 1));
    }
    return idx;
  };
  const auto key_of = [](const std::array<std::uint64_t, 3>& idx) {
    return (idx[0] << 42) | (idx[1] << 21) | idx[2];
  };

  // (cell, edge) pairs: each edge is cut into pieces no longer than a cell, and the box of each
  // piece, grown by the tolerance, covers the cells it may touch. Pieces total at most
  // 2 * boundary.size() since the cell is the mean length.
  std::vector<std::pair<std::uint64_t, std::uint32_t>> pairs;
  pairs.reserve(boundary.size() * 8);
  for (std::uint32_t e = 0; e < boundary.size(); ++e) {
    const Vec3& a = p[boundary[e][0]];
    const Vec3 d = p[boundary[e][1]] - a;
    const double length = d.norm();
    if (!(length > 0)) continue;
    const double tol = kRel * length;
    const auto pieces = static_cast<int>(std::ceil(length / cell));
    for (int s = 0; s < pieces; ++s) {
      const Vec3 x0 = a + d * (static_cast<double>(s) / pieces);
      const Vec3 x1 = a + d * (static_cast<double>(s + 1) / pieces);
      const auto c0 = cell_of(x0.cwiseMin(x1) - Vec3::Constant(tol));
      const auto c1 = cell_of(x0.cwiseMax(x1) + Vec3::Constant(tol));
      for (auto i = c0[0]; i <= c1[0]; ++i) {
        for (auto j = c0[1]; j <= c1[1]; ++j) {
          for (auto k = c0[2]; k <= c1[2]; ++k) pairs.emplace_back(key_of({i, j, k}), e);
        }
      }
    }
  }
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  FlatMap first(pairs.size());  // cell key -> index of its first pair
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    first.emplace(pairs[i].first, static_cast<std::uint32_t>(i));
  }

  std::vector<char> on_boundary(p.size(), 0);
  std::vector<std::int32_t> candidates;
  for (const auto& edge : boundary) {
    for (const std::int32_t v : edge) {
      if (!on_boundary[v]) {
        on_boundary[v] = 1;
        candidates.push_back(v);
      }
    }
  }

  std::size_t count = 0;
  for (std::int32_t v : candidates) {
    const std::uint64_t key = key_of(cell_of(p[v]));
    const std::uint32_t* start = first.find(key);
    if (start == nullptr) continue;
    for (std::size_t i = *start; i < pairs.size() && pairs[i].first == key; ++i) {
      const auto& [ia, ib] = boundary[pairs[i].second];
      if (ia == v || ib == v) continue;
      const Vec3& a = p[ia];
      const Vec3 d = p[ib] - a;
      const double length_sq = d.squaredNorm();
      const double t = (p[v] - a).dot(d) / length_sq;
      if (!(t > kRel && t < 1 - kRel)) continue;
      if ((p[v] - (a + t * d)).squaredNorm() < kRel * kRel * length_sq) {
        ++count;
        break;
      }
    }
  }
  return count;
}

}  // namespace

QualityReport measure_quality(const Mesh& mesh, const QualityOptions& options) {
  validate(mesh);
  const auto& p = mesh.positions;
  QualityReport r;
  r.vertices = p.size();
  r.faces = mesh.faces.size();
  r.quad_angles = make_histogram(0, 180, options.angle_bins);
  r.edge_ratio = make_histogram(-1, 1, options.edge_bins);
  r.triangle_min_angle = make_histogram(0, 90, options.triangle_bins);

  r.quads = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, mesh.faces.size(), 65536), std::size_t{0},
      [&](const tbb::blocked_range<std::size_t>& range, std::size_t n) {
        for (std::size_t f = range.begin(); f < range.end(); ++f) n += mesh.faces[f].is_quad();
        return n;
      },
      [](std::size_t a, std::size_t b) { return a + b; });
  r.triangles = mesh.faces.size() - r.quads;
  r.quad_share = r.faces ? static_cast<double>(r.quads) / static_cast<double>(r.faces) : 0.0;

  // The edges' figures and the shapes' side by side: each has serial stretches (sums, joins,
  // selections) where the other's loops keep the threads busy.
  const std::size_t nf = mesh.faces.size();
  const auto edge_figures = [&] {
    // Unit normals, zero where the face is degenerate (which keeps it out of folds). A zero
    // normal alone does not mark one: an area too large to square gives zero too.
    Buffer<Vec3> normals = untouched<Vec3>(nf);
    Buffer<char> degenerate = untouched<char>(nf);
    for_each_index(nf, [&](std::size_t f) {
      const Face& face = mesh.faces[f];
      normals[f].setZero();
      degenerate[f] = 1;
      if (has_repeated_index(face)) return;
      double longest_sq = 0;
      for (int i = 0; i < face.size; ++i)
        longest_sq =
            std::max(longest_sq, (p[face.v[(i + 1) % face.size]] - p[face.v[i]]).squaredNorm());
      const Vec3 area = area_vector(mesh, face);
      const double norm = area.norm();
      if (!(norm > options.degenerate_area * longest_sq) || norm == 0) return;
      degenerate[f] = 0;
      normals[f] = area / norm;
    });
    r.degenerate_faces = tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, nf, 65536), std::size_t{0},
        [&](const tbb::blocked_range<std::size_t>& range, std::size_t n) {
          for (std::size_t f = range.begin(); f < range.end(); ++f) n += degenerate[f];
          return n;
        },
        [](std::size_t x, std::size_t y) { return x + y; });

    const EdgeFigures edges = scan_edges(mesh, normals, options.fold_cos);
    r.non_manifold_edges = edges.non_manifold;
    r.inconsistent_edges = edges.inconsistent;
    r.folds = edges.folds;
    r.boundary_edges = edges.boundary.size();
    r.t_junctions = count_t_junctions(mesh, edges.boundary);
  };
  const auto shape_figures = [&] {
    // Shape statistics; faces with a zero-length edge have no defined angles and are skipped.
    // Fixed blocks of faces are measured in parallel, each into its own histograms, sums and
    // values; blocks are then taken in face order, so no figure depends on the schedule.
    struct Shapes {
      Histogram quad_angles, edge_ratio, triangle_min_angle;
      std::span<double> angle_dev, spread, tri_min;  // the block's values, in face order
      double angle_dev_sum = 0, spread_sum = 0, longest_edge = 0;
      std::size_t measured_quads = 0, measured_triangles = 0, within_10 = 0, below_10 = 0;
    };
    constexpr std::size_t kShapeBlock = 16384;
    std::vector<Shapes> blocks((nf + kShapeBlock - 1) / kShapeBlock);
    // Each block writes its values into its own stretch of a buffer shared by all blocks (four a
    // quad, one a triangle at most): hundreds of megabytes for a frame of millions of faces,
    // faulted in by the blocks in 2 MiB pages, with no allocation per block.
    Buffer<double> angle_dev_values = untouched<double>(4 * nf);
    Buffer<double> spread_values = untouched<double>(4 * nf);
    Buffer<double> tri_min_values = untouched<double>(nf);
    tbb::parallel_for(std::size_t{0}, blocks.size(), [&](std::size_t b) {
      Shapes& out = blocks[b];
      out.quad_angles = make_histogram(0, 180, options.angle_bins);
      out.edge_ratio = make_histogram(-1, 1, options.edge_bins);
      out.triangle_min_angle = make_histogram(0, 90, options.triangle_bins);
      const std::size_t end = std::min(nf, (b + 1) * kShapeBlock);
      double* const dev = angle_dev_values.data() + 4 * b * kShapeBlock;
      double* const spread = spread_values.data() + 4 * b * kShapeBlock;
      double* const tri_min = tri_min_values.data() + b * kShapeBlock;
      std::size_t n_angles = 0, n_triangles = 0;
      for (std::size_t f = b * kShapeBlock; f < end; ++f) {
        const Face& face = mesh.faces[f];
        const int n = face.size;
        std::array<Vec3, 4> e;  // e[i] = p[i+1] - p[i]
        std::array<double, 4> length{};
        bool measurable = true;
        for (int i = 0; i < n; ++i) {
          e[i] = p[face.v[(i + 1) % n]] - p[face.v[i]];
          length[i] = e[i].norm();
          out.longest_edge = std::max(out.longest_edge, length[i]);
          measurable = measurable && length[i] > 0;
        }
        if (!measurable) continue;
        if (face.is_quad()) {
          ++out.measured_quads;
          const double avg = 0.25 * (length[0] + length[1] + length[2] + length[3]);
          for (int i = 0; i < 4; ++i) {
            const double angle = angle_deg(-e[(i + 3) % 4], e[i]);
            add(out.quad_angles, angle);
            dev[n_angles] = std::abs(angle - 90);
            out.angle_dev_sum += dev[n_angles];
            if (angle >= 80 && angle <= 100) ++out.within_10;
            const double ratio = 1 - length[i] / avg;
            add(out.edge_ratio, ratio);
            spread[n_angles] = std::abs(ratio);
            out.spread_sum += spread[n_angles];
            ++n_angles;
          }
        } else {
          ++out.measured_triangles;
          double smallest = 180;
          for (int i = 0; i < 3; ++i)
            smallest = std::min(smallest, angle_deg(-e[(i + 2) % 3], e[i]));
          add(out.triangle_min_angle, smallest);
          tri_min[n_triangles++] = smallest;
          if (smallest < 10) ++out.below_10;
        }
      }
      out.angle_dev = {dev, n_angles};
      out.spread = {spread, n_angles};
      out.tri_min = {tri_min, n_triangles};
    });
    Parts angle_dev(blocks.size()), spread(blocks.size()), tri_min(blocks.size());
    std::size_t within_10 = 0, below_10 = 0;
    double angle_dev_sum = 0, spread_sum = 0;  // block after block: the same for any schedule
    const auto add_counts = [](Histogram& to, const Histogram& from) {
      for (std::size_t i = 0; i < to.counts.size(); ++i) to.counts[i] += from.counts[i];
    };
    for (std::size_t b = 0; b < blocks.size(); ++b) {
      Shapes& block = blocks[b];
      r.measured_quads += block.measured_quads;
      r.measured_triangles += block.measured_triangles;
      within_10 += block.within_10;
      below_10 += block.below_10;
      angle_dev_sum += block.angle_dev_sum;
      spread_sum += block.spread_sum;
      r.longest_edge = std::max(r.longest_edge, block.longest_edge);
      add_counts(r.quad_angles, block.quad_angles);
      add_counts(r.edge_ratio, block.edge_ratio);
      add_counts(r.triangle_min_angle, block.triangle_min_angle);
      angle_dev[b] = block.angle_dev;
      spread[b] = block.spread;
      tri_min[b] = block.tri_min;
    }
    const std::size_t angles = total_size(angle_dev), triangles = total_size(tri_min);
    if (angles > 0) {
      r.quad_angles_within_10 = static_cast<double>(within_10) / static_cast<double>(angles);
      r.quad_angle_mean_abs_dev = angle_dev_sum / static_cast<double>(angles);
      r.edge_spread_mean = spread_sum / static_cast<double>(angles);
    }
    // Order statistics side by side.
    tbb::parallel_invoke([&] { r.quad_angle_abs_dev_p90 = quantile(angle_dev, 0.9); },
                         [&] {
                           r.edge_spread_median = quantile(spread, 0.5);
                           r.edge_spread_p90 = quantile(spread, 0.9);
                         },
                         [&] {
                           r.triangle_min_angle_median = quantile(tri_min, 0.5);
                           r.triangle_min_angle_p05 = quantile(tri_min, 0.05);
                         });
    if (triangles > 0) {
      r.triangles_below_10deg = static_cast<double>(below_10) / static_cast<double>(triangles);
    }
  };
  tbb::parallel_invoke(edge_figures, shape_figures);
  return r;
}

}  // namespace orthofront
