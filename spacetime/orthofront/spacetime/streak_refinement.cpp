#include "orthofront/spacetime/streak_refinement.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <utility>

namespace orthofront::spacetime {

namespace {

// A distance between neighbouring rows not measured yet (or changed since).
constexpr double kUnmeasured = -1;

// Catmull-Rom at the middle of p1 and p2 (uniform parameter).
Vec3 cubic_middle(const Vec3& p0, const Vec3& p1, const Vec3& p2, const Vec3& p3) {
  return (-p0 + 9.0 * p1 + 9.0 * p2 - p3) / 16.0;
}

// Whether particle m, between a and b on a row, may go: both its edges are short, and a and b
// would not be too far apart without it.
bool removable(const StreakParticle& a, const StreakParticle& m, const StreakParticle& b,
               const LengthLimit& short_limit, const LengthLimit& long_limit) {
  return a.alive() && m.alive() && b.alive() && short_limit.shorter(a.x - m.x) &&
         short_limit.shorter(m.x - b.x) && long_limit.shorter(a.x - b.x);
}

}  // namespace

void StreakRefinement::begin(const std::vector<StreakRow>& rows) {
  change_.assign(rows.size(), RowChange{});
  gap_.assign(rows.size(), kUnmeasured);
}

bool StreakRefinement::refine_once(std::vector<StreakRow>& rows, std::int32_t& next_id, Owner& owner) {
  const double long_edge = limits_.split * limits_.edge;
  std::vector<RowChange>& change = change_;
  std::vector<double>& gap = gap_;
  // Each row's (and each pair of rows') new particles are found independently, in parallel, and
  // gathered in row order: the particles, their ids and the mesh are those of a serial scan.
  std::vector<std::vector<Insert>> along(rows.size());       // per row, by left particle
  std::vector<std::optional<StreakRow>> across(rows.size());  // [r]: the new row after row r
  // Row r and the pair (r, r + 1) in one task: row r is still in cache for the pair, and for
  // coarsening's search of a row looked at whole (particles do not move until it runs).
  for_each_row(rows.size(), [&](std::size_t r) {
    if (change[r].any()) along[r] = inserts_along(rows, r, long_edge, change[r]);
    if (change[r].whole) rows[r].coarsen_from = first_removable(rows[r].p, 1);
    if (r + 1 < rows.size() && (change[r].any() || change[r + 1].any()))
      across[r] = row_between(rows, r, long_edge, gap[r]);
  });
  std::size_t along_count = 0, across_count = 0;
  for (std::size_t r = 0; r < rows.size(); ++r) {
    along_count += along[r].size();
    across_count += across[r].has_value();
  }
  if (along_count == 0 && across_count == 0) return false;

  // The new particles in order (along each row, then the new rows), gathered row by row in
  // parallel at offsets counted beforehand; ids follow that order.
  const std::size_t nr = rows.size();
  std::vector<std::size_t> first(2 * nr + 1, 0);  // [r]: along row r; [nr + r]: the row after r
  for (std::size_t r = 0; r < nr; ++r) first[r + 1] = first[r] + along[r].size();
  for (std::size_t r = 0; r < nr; ++r) first[nr + r + 1] = first[nr + r] + (across[r] ? across[r]->p.size() : 0);
  std::vector<StreakParticle*> fresh(first[2 * nr]);
  std::vector<double> from(fresh.size());
  const auto id0 = next_id;
  for_each_row(nr, [&](std::size_t r) {
    std::size_t k = first[r];
    for (Insert& ins : along[r]) {
      fresh[k] = &ins.particle;
      from[k] = rows[r].tau;
      ins.particle.id = id0 + static_cast<std::int32_t>(k++);
    }
    if (!across[r]) return;
    k = first[nr + r];
    for (StreakParticle& q : across[r]->p) {
      fresh[k] = &q;
      from[k] = across[r]->tau;
      q.id = id0 + static_cast<std::int32_t>(k++);
    }
  }, fresh.size() >= kParallelParticles);
  next_id += static_cast<std::int32_t>(fresh.size());
  // Exact positions: every new particle released at its own (s, τ), moved to t in one batch.
  if (limits_.insertion == ParticleInsertion::exact) {
    if (!owner.place_exact(fresh, from)) return false;
    counts_.exact_insertions += fresh.size();
  } else {
    counts_.interpolated_insertions += fresh.size();
  }
  owner.enter(fresh);
  counts_.s_insertions += along_count;
  counts_.rows_inserted += across_count;
  for (const std::optional<StreakRow>& row : across)
    if (row) counts_.row_particles += row->p.size();

  // Insert along rows in place, from the back (each row grows once, in linear time, mostly in the
  // room it has), then the new rows. A new particle goes right after its left neighbour (the
  // closing edge of a closed row: after the last particle); its index is kept for the next pass.
  std::vector<RowChange> next(rows.size() + across_count);
  std::vector<std::size_t> at(rows.size());  // row r's index after the new rows
  for (std::size_t r = 0, k = 0; r < rows.size(); ++r) {
    at[r] = k;
    k += across[r] ? 2 : 1;
  }
  for_each_row(rows.size(), [&](std::size_t r) {
    const std::vector<Insert>& ins = along[r];
    RowChange& c = next[at[r]];
    c.whole = false;
    if (ins.empty()) return;
    std::vector<StreakParticle>& p = rows[r].p;
    const std::size_t old = p.size();
    // Particles before the first new one keep their neighbours (a row of three may lose one
    // only once it grows): `ins` is by increasing `after`, one each, and no particle moves
    // between refinement and coarsening.
    std::size_t& coarsen_from = rows[r].coarsen_from;
    coarsen_from =
        old <= 3 ? 1 : std::max<std::size_t>(1, std::min(coarsen_from, ins.front().after));
    if (p.capacity() < old + ins.size()) {
      // Merged into the new array as it is copied, instead of copied and then moved up.
      std::vector<StreakParticle> grown;
      grown.reserve(std::max(2 * old, old + ins.size()));
      for (std::size_t i = 0, k = 0; i < old; ++i) {
        grown.push_back(p[i]);
        if (k < ins.size() && ins[k].after == i) grown.push_back(ins[k++].particle);
      }
      p.swap(grown);
    } else {
      p.resize(old + ins.size());
      std::size_t w = p.size(), k = ins.size();
      for (std::size_t i = old; i-- > 0 && k > 0;) {
        if (ins[k - 1].after == i) p[--w] = ins[--k].particle;
        p[--w] = p[i];
      }
    }
    c.added.resize(ins.size());
    for (std::size_t j = 0; j < ins.size(); ++j) c.added[j] = static_cast<std::uint32_t>(ins[j].after + j + 1);
  });
  if (across_count > 0) {
    std::vector<StreakRow> grown;
    grown.reserve(rows.size() + across_count);
    for (std::size_t r = 0; r < rows.size(); ++r) {
      grown.push_back(std::move(rows[r]));
      if (across[r]) grown.push_back(std::move(*across[r]));  // next[]: whole, as made
    }
    rows.swap(grown);
  }
  // Distances: a new row has none measured; rows that only got particles grow theirs by those.
  std::vector<double> next_gap(rows.size(), kUnmeasured);
  for_each_row(gap.size(), [&](std::size_t r) {
    if (across[r] || r + 1 >= gap.size() || gap[r] == kUnmeasured) return;
    const std::size_t a = at[r];
    next_gap[a] = grown_gap(rows, a, gap[r], next[a], next[a + 1]);
  }, along_count >= kParallelParticles / 16);  // a search in a row for each
  change.swap(next);
  gap.swap(next_gap);
  return true;
}

double StreakRefinement::grown_gap(const std::vector<StreakRow>& rows, std::size_t r, double gap,
                                   const RowChange& a, const RowChange& b) const {
  if (a.added.empty() && b.added.empty()) return gap;
  // The largest square over the pairs the added particles make with the other row: the root of
  // the larger of it and gap² is row_distance's, bit for bit.
  double d = 0;
  const auto pairs = [&](const StreakRow& with_added, const std::vector<std::uint32_t>& added,
                         const StreakRow& other) {
    const std::vector<StreakParticle>& o = other.p;
    for (const std::uint32_t i : added) {
      const StreakParticle& q = with_added.p[i];
      if (!q.alive()) continue;
      const auto it = std::lower_bound(o.begin(), o.end(), q.s,
                                       [](const StreakParticle& x, double s) { return x.s < s; });
      if (it != o.end() && it->s == q.s && it->alive()) d = std::max(d, (q.x - it->x).squaredNorm());
    }
  };
  pairs(rows[r], a.added, rows[r + 1]);
  pairs(rows[r + 1], b.added, rows[r]);
  return std::max(gap, std::sqrt(d));
}

std::vector<StreakRefinement::Insert> StreakRefinement::inserts_along(const std::vector<StreakRow>& rows,
                                                                      std::size_t r, double long_edge,
                                                                      const RowChange& change) const {
  std::vector<Insert> along;
  const LengthLimit long_limit(long_edge);
  const bool closed = limits_.closed;
  const std::vector<StreakParticle>& p = rows[r].p;
  const std::size_t n = p.size();
  const std::size_t edges = closed ? n : n - 1;
  const auto edge = [&](std::size_t i) {  // i: the edge's left particle
    const StreakParticle& a = p[i];
    const StreakParticle& b = p[(i + 1) % n];
    if (!a.alive() || !b.alive()) return;
    const double sb = (i + 1 == n) ? b.s + 1.0 : b.s;
    if (sb - a.s <= limits_.min_ds || long_limit.not_longer(a.x - b.x)) return;
    StreakParticle q;
    q.s = 0.5 * (a.s + sb);  // < 1: a closed row starts at s = 0, which is never removed
    if (limits_.insertion == ParticleInsertion::interpolate) {
      const auto at = [&](std::ptrdiff_t j) -> const StreakParticle* {
        const auto m = static_cast<std::ptrdiff_t>(n);
        if (closed) j = ((j % m) + m) % m;
        if (j < 0 || j >= m || !p[static_cast<std::size_t>(j)].alive()) return nullptr;
        return &p[static_cast<std::size_t>(j)];
      };
      const auto ii = static_cast<std::ptrdiff_t>(i);
      const StreakParticle* p0 = at(ii - 1);
      const StreakParticle* p3 = at(ii + 2);
      q.x = (p0 && p3) ? cubic_middle(p0->x, a.x, b.x, p3->x) : 0.5 * (a.x + b.x);
    }
    along.push_back({i, q});
  };
  if (change.whole) {
    for (std::size_t i = 0; i < edges; ++i) edge(i);
    return along;
  }
  // Only the edges on either side of an added particle (never the first: added after another),
  // each once and in order.
  std::size_t next = 0;  // edges before it are done
  for (const std::uint32_t j : change.added) {
    for (std::size_t i = std::max<std::size_t>(next, j - 1); i <= j && i < edges; ++i) edge(i);
    next = std::size_t{j} + 1;
  }
  return along;
}

std::optional<StreakRow> StreakRefinement::row_between(const std::vector<StreakRow>& rows, std::size_t r,
                                                       double long_edge, double& gap) const {
  const StreakRow& a = rows[r];
  const StreakRow& b = rows[r + 1];
  if (b.tau - a.tau <= limits_.min_dtau) return std::nullopt;
  // (Beyond long_edge the measure stops: the pair is split, and its distance dropped.)
  if (gap == kUnmeasured) gap = row_distance(a, b, LengthLimit(long_edge));
  if (gap <= long_edge) return std::nullopt;
  StreakRow row;
  row.tau = 0.5 * (a.tau + b.tau);
  row.p.reserve(std::max(a.p.size(), b.p.size()));
  // The rows around, for cubic interpolation: the s asked for only grows along the walk, so a
  // cursor into each finds what a binary search would, without a search per particle (the rows
  // a stretching surface inserts hold thousands).
  const std::vector<StreakParticle>* before = r >= 1 ? &rows[r - 1].p : nullptr;
  const std::vector<StreakParticle>* after = r + 2 < rows.size() ? &rows[r + 2].p : nullptr;
  std::size_t at_before = 0, at_after = 0;
  const auto find = [](const std::vector<StreakParticle>* ps, std::size_t& at,
                       double s) -> const StreakParticle* {
    if (!ps) return nullptr;
    while (at < ps->size() && (*ps)[at].s < s) ++at;
    return at < ps->size() && (*ps)[at].s == s && (*ps)[at].alive() ? &(*ps)[at] : nullptr;
  };
  std::size_t i = 0, k = 0;
  while (i < a.p.size() || k < b.p.size()) {
    const bool take_a = k == b.p.size() || (i < a.p.size() && a.p[i].s <= b.p[k].s);
    const bool take_b = i == a.p.size() || (k < b.p.size() && b.p[k].s <= a.p[i].s);
    const bool common = take_a && take_b;
    StreakParticle q;
    q.s = take_a ? a.p[i].s : b.p[k].s;
    if (limits_.insertion == ParticleInsertion::exact) {
      row.p.push_back(q);
    } else if (common) {
      // Cubic across rows where the rows around carry this s too, linear otherwise.
      const StreakParticle& pa = a.p[i];
      const StreakParticle& pb = b.p[k];
      if (pa.alive() && pb.alive()) {
        const StreakParticle* p0 = find(before, at_before, q.s);
        const StreakParticle* p3 = find(after, at_after, q.s);
        q.x = (p0 && p3) ? cubic_middle(p0->x, pa.x, pb.x, p3->x) : 0.5 * (pa.x + pb.x);
      } else {
        q.set_status(advect::ParticleStatus::left_domain);
      }
      row.p.push_back(q);
    }
    if (take_a) ++i;
    if (take_b) ++k;
  }
  return row;
}

std::size_t StreakRefinement::first_removable(const std::vector<StreakParticle>& p, std::size_t from) const {
  const std::size_t n = p.size();
  if (n <= 3) return n;  // a row keeps three particles
  const LengthLimit short_limit(limits_.merge * limits_.edge), long_limit(limits_.split * limits_.edge);
  std::size_t i = std::max<std::size_t>(from, 1);
  while (i + 1 < n && !removable(p[i - 1], p[i], p[i + 1], short_limit, long_limit)) ++i;
  return i;
}

void StreakRefinement::coarsen(std::vector<StreakRow>& rows, Owner& owner) {
  const double short_edge = limits_.merge * limits_.edge;
  const double long_edge = limits_.split * limits_.edge;
  const LengthLimit short_limit(short_edge), long_limit(long_edge);
  std::vector<double>& gap = gap_;
  if (gap.size() != rows.size()) gap.assign(rows.size(), kUnmeasured);  // coarsened unrefined
  // Along rows: a particle whose two edges are short goes (never a row's ends, and a row keeps
  // three particles), unless its neighbours would then be too far apart. Rows in parallel.
  std::vector<std::size_t> removed(rows.size(), 0);
  std::vector<std::vector<StreakParticle>> gone(rows.size());  // in the resident set: their slots go back
  for_each_row(rows.size(), [&](std::size_t r) {
    std::vector<StreakParticle>& p = rows[r].p;
    // Most rows lose nothing: find the first particle that goes before moving any (refinement's
    // first pass has mostly found it). The kept particles close up in place: p[0, w) are kept,
    // and p[i + 1] is not moved yet.
    const std::size_t n = p.size();
    const std::size_t first = first_removable(p, std::exchange(rows[r].coarsen_from, 1));
    // Builds without NDEBUG (the sanitizer build) check the start against a search from 1.
    assert(first == first_removable(p, 1) && "refinement's coarsening start");
    if (first + 1 >= n) return;
    std::size_t w = first;
    for (std::size_t i = first; i < n; ++i) {
      const bool interior = i + 1 < n;
      if (interior && n - (i - w) > 3 &&
          removable(p[w - 1], p[i], p[i + 1], short_limit, long_limit)) {
        ++removed[r];
        if (p[i].slot() != kNoSlot) gone[r].push_back(p[i]);
        continue;
      }
      p[w++] = p[i];
    }
    p.resize(w);
  });
  for (std::size_t r = 0; r < rows.size(); ++r) {
    if (removed[r] == 0) continue;
    counts_.s_removals += removed[r];
    gap[r] = kUnmeasured;
    if (r > 0) gap[r - 1] = kUnmeasured;
  }
  for (std::vector<StreakParticle>& row : gone)
    for (StreakParticle& p : row) owner.leave(p);
  // Across rows: a row between two close ones goes (never the oldest or the newest). Which row
  // goes depends on the rows kept before it, so the walk is serial; the distances between
  // neighbouring rows, which it mostly asks, are measured beforehand in parallel.
  if (rows.size() > 2) {
    std::vector<double> next_distance(rows.size() - 1);  // [r]: rows r and r + 1
    for_each_row(next_distance.size(), [&](std::size_t r) {
      next_distance[r] = gap[r] != kUnmeasured ? gap[r] : row_distance(rows[r], rows[r + 1], short_limit);
    });
    std::vector<StreakRow> kept;
    kept.reserve(rows.size());
    kept.push_back(std::move(rows[0]));
    bool previous_kept = true;  // kept.back() is rows[r - 1]
    for (std::size_t r = 1; r + 1 < rows.size(); ++r) {
      const StreakRow& a = kept.back();
      const StreakRow& m = rows[r];
      const StreakRow& b = rows[r + 1];
      const double am = previous_kept ? next_distance[r - 1] : row_distance(a, m, short_limit);
      if (am < short_edge && next_distance[r] < short_edge && row_distance(a, b, long_limit) < long_edge) {
        ++counts_.rows_removed;
        for (StreakParticle& p : rows[r].p) owner.leave(p);
        previous_kept = false;
        continue;
      }
      kept.push_back(std::move(rows[r]));
      previous_kept = true;
    }
    kept.push_back(std::move(rows.back()));
    rows.swap(kept);
  }
  // Rows whose particles have all stopped carry nothing any more.
  std::erase_if(rows, [](const StreakRow& r) {
    return std::none_of(r.p.begin(), r.p.end(), [](const StreakParticle& p) { return p.alive(); });
  });
  // The rows changed: the next break starts afresh.
  change_.clear();
  gap_.clear();
}

}  // namespace orthofront::spacetime
