#include "orthofront/engine/stitch.h"

namespace orthofront {

template <int N>
void StripStitcher<N>::smooth_rows(const Front<N>& f, std::vector<char>& fresh) const {
  const std::size_t n = f.v.size();
  const double full = opt_.skip_fraction * opt_.edge;
  const double low = opt_.join_fraction * full;
  const double high = 0.9 * opt_.edge;
  auto moved = [&](std::size_t i) { return moved_[i]; };
  auto movable = [&](std::size_t i) { return f.v[i].origin >= 0 && moved(i) >= low; };
  // Inserted vertices count as moving (they are new mesh vertices).
  auto moving = [&](std::size_t i) { return f.v[i].origin < 0 || fresh[i]; };
  for (std::size_t i = 1; i < n; ++i)
    if (!fresh[i] && moving(i - 1) && movable(i)) fresh[i] = 1;
  for (std::size_t i = n - 1; i-- > 0;)
    if (!fresh[i] && moving(i + 1) && movable(i)) fresh[i] = 1;
  // A short moving run inside waiting vertices waits too, unless it has gone nearly ℓ.
  for (std::size_t i = 0; i < n;) {
    if (!(f.v[i].origin >= 0 && fresh[i])) {
      ++i;
      continue;
    }
    std::size_t j = i;
    bool early = true;
    for (; j < n && f.v[j].origin >= 0 && fresh[j]; ++j) early = early && moved(j) < high;
    if (early && j - i <= 2 && i > 0 && j < n && !moving(i - 1) && !moving(j))
      for (std::size_t k = i; k < j; ++k) fresh[k] = 0;
    i = j;
  }
  // A waiting run of up to 16 vertices between moving ones, or between one and an open end,
  // moves too once each of its vertices has gone a twentieth of the skip distance: a waiting run
  // costs a triangle at each end beside a moving vertex in every step it waits, and a short run
  // adds few short edges. Longer runs stay: letting every run move trades the triangles for a
  // much wider edge spread (the figures behind both limits: docs/benchmarks/engine-options.md,
  // row skipping).
  const double lone = 0.05 * full;
  constexpr std::size_t kLongestJoiningRun = 16;
  // A closed front's runs are taken in cyclic order from a vertex that moves (a run may go on
  // across its last and first vertex); an open front's from its first vertex.
  std::size_t start = 0;
  if (f.closed) {
    while (start < n && !moving(start)) ++start;
    if (start == n) return;  // every vertex waits: the front stays as it is
  }
  const auto at = [&](std::size_t k) { return start + k < n ? start + k : start + k - n; };
  for (std::size_t k = 0; k < n;) {
    if (moving(at(k))) {
      ++k;
      continue;
    }
    std::size_t end = k;
    bool far = true;
    for (; end < n && !moving(at(end)); ++end) far = far && moved(at(end)) >= lone;
    // Beside moving vertices on both sides (always, on a closed front), or beside one and the
    // end of an open front; an open front that waits as a whole stays as it is.
    const bool beside_moving = f.closed || ((k > 0 || end < n) && (k == 0 || moving(k - 1)) &&
                                            (end == n || moving(end)));
    if (far && end - k <= kLongestJoiningRun && beside_moving)
      for (std::size_t m = k; m < end; ++m) fresh[at(m)] = 1;
    k = end;
  }
}

template <int N>
void StripStitcher<N>::emit_moved(Front<N>& f, const Front<N>& old, int step) {
  const std::size_t n = f.v.size();
  std::vector<char>& fresh = fresh_;
  fresh.assign(n, 0);
  moved_.resize(n);
  const double min_move = opt_.skip_fraction * opt_.edge;
  for (std::size_t i = 0; i < n; ++i) {
    moved_[i] = 0;
    if (f.v[i].origin < 0) continue;  // inserted: already a mesh vertex
    const double distance = moved_[i] = (f.v[i].x - f.v[i].anchor).norm();
    // Without row skipping every vertex that moved at all gets a new mesh vertex; one whose α
    // was clamped to 0 did not move and keeps its own (a copy would make a zero-area face).
    const bool every_row = row_skip_ == RowSkip::off;
    fresh[i] = every_row ? has_moved(f.v[i], opt_.edge) : distance >= min_move;
  }
  if (row_skip_ == RowSkip::run) smooth_rows(f, fresh);
  for (std::size_t i = 0; i < n; ++i)
    if (fresh[i] && f.v[i].origin >= 0 && lands_on_mesh_vertex(f, old, fresh, i)) fresh[i] = 0;
  renew_across_merges(f, old, fresh);
  for (std::size_t i = 0; i < n; ++i) {
    if (f.v[i].origin < 0) continue;
    if (fresh[i]) {
      f.v[i].mesh = emit_vertex(mesh_, f.v[i], closed_seed_, 0.0, f.id, step);
      f.v[i].anchor = f.v[i].x;
    } else {
      ++report_.skipped_vertex_steps;
    }
  }
}

template <int N>
bool StripStitcher<N>::lands_on_mesh_vertex(const Front<N>& f, const Front<N>& old,
                                             const std::vector<char>& fresh,
                                             std::size_t i) const {
  const double tolerance = 1e-8 * opt_.edge;
  const double tolerance2 = tolerance * tolerance;
  const Vec3 x = f.v[i].x.template head<3>();
  const auto near = [&](const Vec3& p) { return (p - x).squaredNorm() <= tolerance2; };
  const auto near_mesh = [&](std::int32_t m) {
    return m >= 0 && near(mesh_.positions[static_cast<std::size_t>(m)]);
  };
  const std::size_t n = f.v.size(), n_old = old.v.size();
  for (const bool next : {false, true}) {
    if (!f.closed && (next ? i + 1 >= n : i == 0)) continue;
    const std::size_t k = next ? next_index(i, n) : previous_index(i, n);
    // A neighbour that gets a new mesh vertex gets it at its position; the others keep theirs.
    if (k != i && (fresh[k] ? near(f.v[k].x.template head<3>()) : near_mesh(f.v[k].mesh)))
      return true;
  }
  const auto o = static_cast<std::size_t>(f.v[i].origin);
  if (near_mesh(old.v[o].mesh)) return true;
  if ((old.closed || o > 0) && near_mesh(old.v[previous_index(o, n_old)].mesh)) return true;
  if ((old.closed || o + 1 < n_old) && near_mesh(old.v[next_index(o, n_old)].mesh)) return true;
  return false;
}

template <int N>
void StripStitcher<N>::renew_across_merges(const Front<N>& f, const Front<N>& old,
                                            std::vector<char>& fresh) const {
  const std::size_t n = f.v.size(), n_old = old.v.size();
  const std::size_t segments = f.closed ? n : (n > 0 ? n - 1 : 0);
  for (std::size_t i = 0; i < segments; ++i) {
    const std::size_t j = next_index(i, n);
    const FrontVertex<N>& a = f.v[i];
    const FrontVertex<N>& b = f.v[j];
    if (a.origin < 0 || b.origin < 0 || fresh[i] || fresh[j]) continue;
    // Old vertices from a.origin to b.origin, as stitch walks them (forward, wrapping on a
    // closed previous front; a single vertex on a closed front goes all the way round).
    const auto oa = static_cast<std::size_t>(a.origin), ob = static_cast<std::size_t>(b.origin);
    if (ob < oa && !old.closed) continue;
    const std::size_t span = ob > oa ? ob - oa : ob + n_old - oa;
    if (span < 2) continue;  // adjacent on the previous front too: one quad, no merge
    const double da = (a.x - a.anchor).norm(), db = (b.x - b.anchor).norm();
    const std::size_t k = da >= db ? i : j;
    if (has_moved(f.v[k], opt_.edge)) fresh[k] = 1;
  }
}

template <int N>
void StripStitcher<N>::add_face(std::array<std::int32_t, 4> ids, int count) {
  // Four different corners (almost every face): the quad as it is.
  if (count == 4 && ids[0] != ids[1] && ids[0] != ids[2] && ids[0] != ids[3] &&
      ids[1] != ids[2] && ids[1] != ids[3] && ids[2] != ids[3]) {
    mesh_.add_quad(ids[0], ids[1], ids[2], ids[3]);
    return;
  }
  std::array<std::int32_t, 4> u{};
  int m = 0;
  for (int k = 0; k < count; ++k) {
    bool seen = false;
    for (int l = 0; l < m; ++l)
      seen = seen || u[static_cast<std::size_t>(l)] == ids[static_cast<std::size_t>(k)];
    if (!seen) u[static_cast<std::size_t>(m++)] = ids[static_cast<std::size_t>(k)];
  }
  if (m < 3) return;
  if (m == 4) {
    mesh_.add_quad(u[0], u[1], u[2], u[3]);
  } else {
    mesh_.add_triangle(u[0], u[1], u[2]);
    // zipper's triangles join rows of different lengths; a quad collapses where a corner kept
    // its mesh vertex.
    ++(count == 3 ? report_.triangles_at_row_changes : report_.triangles_at_waiting_vertices);
  }
}

template <int N>
bool StripStitcher<N>::flat_face(std::array<std::int32_t, 4> ids, int count) const {
  std::array<Vec3, 4> p;
  int m = 0;
  for (int k = 0; k < count; ++k) {
    const std::int32_t id = ids[static_cast<std::size_t>(k)];
    bool seen = false;
    for (int l = 0; l < k; ++l) seen = seen || ids[static_cast<std::size_t>(l)] == id;
    if (!seen) p[static_cast<std::size_t>(m++)] = mesh_.positions[static_cast<std::size_t>(id)];
  }
  if (m < 3) return false;
  const Vec3 area = m == 4 ? Vec3((p[2] - p[0]).cross(p[3] - p[1]))
                           : Vec3((p[1] - p[0]).cross(p[2] - p[0]));
  return 0.5 * area.norm() < 1e-9 * opt_.edge * opt_.edge;
}

template <int N>
double StripStitcher<N>::distance(std::int32_t a, std::int32_t b) const {
  return (mesh_.positions[static_cast<std::size_t>(a)] -
          mesh_.positions[static_cast<std::size_t>(b)])
      .norm();
}

template <int N>
bool StripStitcher<N>::flat_choice(const std::vector<std::int32_t>& a,
                                    const std::vector<std::int32_t>& b, std::size_t i,
                                    std::size_t j, bool triangle, bool on_a) const {
  const std::size_t ma = a.size() - 1, mb = b.size() - 1;
  const bool triangle_flat =
      on_a ? flat_face({a[i], a[i + 1], b[j], -1}, 3) : flat_face({a[i], b[j + 1], b[j], -1}, 3);
  bool quad_flat = flat_face({a[i], a[i + 1], b[j + 1], b[j]}, 4);
  if (on_a && mb - j == 1)
    for (std::size_t k = i + 1; k < ma && !quad_flat; ++k)
      quad_flat = flat_face({a[k], a[k + 1], b[mb], -1}, 3);
  if (!on_a && ma - i == 1)
    for (std::size_t k = j + 1; k < mb && !quad_flat; ++k)
      quad_flat = flat_face({a[ma], b[k + 1], b[k], -1}, 3);
  return triangle ? triangle_flat && !quad_flat : quad_flat && !triangle_flat;
}

template <int N>
void StripStitcher<N>::zipper(const std::vector<std::int32_t>& a,
                               const std::vector<std::int32_t>& b) {
  std::size_t i = 0, j = 0;
  const std::size_t ma = a.size() - 1, mb = b.size() - 1;
  while (i < ma || j < mb) {
    const std::size_t ra = ma - i, rb = mb - j;
    if (ra == rb) {
      add_face({a[i], a[i + 1], b[j + 1], b[j]}, 4);
      ++i, ++j;
    } else if (ra > rb) {
      // An end of B that kept its old mesh vertex (a waiting vertex next to a merge) is an old
      // vertex: a triangle from it to a segment of A that does not contain it lies on the
      // previous front, made of old mesh vertices only (see renew_across_merges). Step past it
      // on B first, and keep the last segment of B for the end when B ends on an old vertex.
      const bool b_old = (j == 0 && b[0] == a[0]) || (j == mb && b[mb] == a[ma]);
      const bool next_old = j + 1 == mb && b[mb] == a[ma];
      bool triangle = rb == 0 || distance(a[i + 1], b[j]) <= distance(a[i + 1], b[j + 1]);
      // The other choice where this one would be flat (flat_choice); the rules for old ends
      // of B, which keep the surface manifold, still come first.
      if (rb > 0 && flat_choice(a, b, i, j, triangle, true)) triangle = !triangle;
      if (b_old && b[j] != a[i] && b[j] != a[i + 1] && rb > 0 && !next_old) triangle = false;
      if (next_old && !b_old) triangle = true;
      if (triangle) {
        add_face({a[i], a[i + 1], b[j], -1}, 3);
        ++i;
      } else {
        add_face({a[i], a[i + 1], b[j + 1], b[j]}, 4);
        ++i, ++j;
      }
    } else {
      bool triangle = ra == 0 || distance(a[i], b[j + 1]) <= distance(a[i + 1], b[j + 1]);
      if (ra > 0 && flat_choice(a, b, i, j, triangle, false)) triangle = !triangle;
      if (triangle) {
        add_face({a[i], b[j + 1], b[j], -1}, 3);
        ++j;
      } else {
        add_face({a[i], a[i + 1], b[j + 1], b[j]}, 4);
        ++i, ++j;
      }
    }
  }
}

namespace {

/// The chain between anchors ja and jb of f (consecutive vertices that came from `old`): the
/// old front's segments from one's origin to the other's (wrapping on a closed old front) and
/// f's from ja to jb. False where no old segment joins them (an open old front, origins
/// backwards).
template <int N>
bool chain_between(const Front<N>& old, const Front<N>& f, std::size_t ja, std::size_t jb,
                   std::size_t& steps_old, std::size_t& steps_new) {
  const std::size_t n = f.v.size(), n_old = old.v.size();
  const auto oa = static_cast<std::size_t>(f.v[ja].origin);
  const auto ob = static_cast<std::size_t>(f.v[jb].origin);
  if (ob < oa && !old.closed) return false;
  steps_old = ob >= oa ? ob - oa : ob + n_old - oa;
  if (steps_old == 0) steps_old = n_old;  // a closed front with a single anchor
  steps_new = jb >= ja ? jb - ja : jb + n - ja;
  if (steps_new == 0) steps_new = n;
  return true;
}

}  // namespace

template <int N>
template <class Visit>
void StripStitcher<N>::for_each_chain(const Front<N>& old, const Front<N>& f,
                                      Visit&& visit) const {
  // Consecutive anchors in one pass (the last to the first on a closed front; a closed front
  // with a single anchor joins it to itself), without listing them first.
  constexpr std::size_t kNone = static_cast<std::size_t>(-1);
  std::size_t first = kNone, previous = kNone, steps_old = 0, steps_new = 0;
  const auto chain = [&](std::size_t ja, std::size_t jb) {
    if (chain_between(old, f, ja, jb, steps_old, steps_new))
      visit(static_cast<std::size_t>(f.v[ja].origin), steps_old, ja, steps_new);
  };
  for (std::size_t i = 0; i < f.v.size(); ++i) {
    if (f.v[i].origin < 0) continue;
    if (previous == kNone)
      first = i;
    else
      chain(previous, i);
    previous = i;
  }
  if (f.closed && first != kNone) chain(previous, first);
}

template <int N>
void StripStitcher<N>::stitch(const Front<N>& old, const Front<N>& f) {
  const std::size_t n = f.v.size();
  const std::size_t n_old = old.v.size();
  std::vector<std::int32_t>& chain_a = chain_a_;
  std::vector<std::int32_t>& chain_b = chain_b_;
  for_each_chain(old, f, [&](std::size_t oa, std::size_t steps_old, std::size_t ja,
                             std::size_t steps_new) {
    if (steps_old == 1 && steps_new == 1) {
      // One segment on each side (almost every chain): zipper's single quad, without the chains.
      add_face({old.v[oa].mesh, old.v[next_index(oa, n_old)].mesh, f.v[next_index(ja, n)].mesh,
                f.v[ja].mesh},
               4);
      return;
    }
    chain_a.clear();
    chain_b.clear();
    for (std::size_t s = 0, o = oa; s <= steps_old; ++s, o = next_index(o, n_old))
      chain_a.push_back(old.v[o].mesh);
    for (std::size_t s = 0, j = ja; s <= steps_new; ++s, j = next_index(j, n))
      chain_b.push_back(f.v[j].mesh);
    zipper(chain_a, chain_b);
  });
}

template class StripStitcher<3>;
template class StripStitcher<4>;

}  // namespace orthofront
