#include "orthofront/engine/adapt.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <utility>

#include "orthofront/engine/for_range.h"

namespace orthofront {

namespace {

/// a + λ (b - a): a seed parameter or time between a segment's ends. split_long, insertion_point
/// and start_likely_shots all take it from here, so a leg started ahead has the bits of the
/// leg an insertion asks for.
double between(double a, double b, double lambda) { return a + lambda * (b - a); }

/// The seed parameter of segment (i, j)'s end j: wrapped past 1 on a closed front's closing
/// segment.
template <int N>
double end_parameter(const Front<N>& f, std::size_t j) {
  return f.closed && j == 0 ? f.v[j].s + 1.0 : f.v[j].s;
}

/// Whether a segment's ends came from neighbours `oi`, `oj` of the previous front `old`.
template <int N>
bool neighbours_in(const Front<N>& old, std::int32_t oi, std::int32_t oj) {
  if (oi < 0 || oj < 0) return false;
  const auto a = static_cast<std::size_t>(oi);
  const auto b = static_cast<std::size_t>(oj);
  return b == a + 1 || (old.closed && b == (a + 1) % old.v.size());
}

/// Whether the seed shots beside a segment kept missing: its insertions start from the
/// previous row first.
template <int N>
bool shots_kept_missing(const FrontVertex<N>& a, const FrontVertex<N>& b) {
  return std::max(a.seed_misses, b.seed_misses) >= kSeedMissesBeforeRowFirst;
}

}  // namespace

template <int N>
FrontAdapter<N>::FrontAdapter(const Field<N>& field, const Seed<N>& seed,
                              const StreamSurfaceOptions& options, const Tolerance& tolerance,
                              const StopRequest& stop, Mesh& mesh, SurfaceReport& report)
    : field_(field), seed_(seed), opt_(options), tol_(tolerance), stop_(stop), mesh_(mesh),
      report_(report),
      legs_(field, seed, tolerance, stop,
            options.shot_evaluations > 0 ? options.shot_evaluations : kMaxEvaluations) {}

template <int N>
void FrontAdapter<N>::merge_short(Front<N>& f) {
  const std::size_t n = f.v.size();
  if (n < 3) return;
  const double limit = opt_.merge_factor * opt_.edge;
  // Kept vertices are compacted in place: v[0, kept) is the merged front so far (most steps
  // merge nothing, and a copy of the front each step cost more than the checks).
  std::vector<FrontVertex<N>>& v = f.v;
  std::size_t kept = 1;
  // A vertex that keeps its mesh vertex between two others that keep theirs is not merged:
  // the three old mesh vertices would close a flat triangle on the previous front.
  const double still = opt_.row_skip == RowSkip::off ? 0.0 : opt_.skip_fraction * opt_.edge;
  const auto waiting = [still](const FrontVertex<N>& fv) {
    return fv.origin >= 0 && (fv.x - fv.anchor).norm() <= still;
  };
  // Nor is one between two that did not move at all (α clamped to 0): neither can be given a
  // new mesh vertex (see renew_across_merges), so every face across the merge would be made of
  // old mesh vertices only.
  const auto stuck = [this](const FrontVertex<N>& a, const FrontVertex<N>& b) {
    return !has_moved(a, opt_.edge) && !has_moved(b, opt_.edge);
  };
  for (std::size_t i = 1; i + 1 < n; ++i) {
    const FrontVertex<N>& last = v[kept - 1];
    const double joined = (v[i].x - last.x).norm() + (v[i + 1].x - v[i].x).norm();
    // A closed front keeps three vertices at least: with two, both of its segments join the
    // same two vertices, and the faces stitched to them share both edges (non-manifold).
    const bool loop_kept = !f.closed || kept + (n - 1 - i) >= 3;
    if (joined < limit && loop_kept && !(waiting(last) && waiting(v[i]) && waiting(v[i + 1])) &&
        !stuck(last, v[i + 1])) {
      ++report_.merges;
      continue;
    }
    if (kept != i) v[kept] = v[i];
    ++kept;
  }
  if (kept != n - 1) v[kept] = v[n - 1];
  ++kept;
  v.resize(kept);
  if (f.closed && kept > 3 && !stuck(v[kept - 2], v.front())) {
    // The closing pair: drop the last vertex when it and its closing segment are short.
    const double joined = (v.back().x - v[kept - 2].x).norm() + (v.front().x - v.back().x).norm();
    if (joined < limit) {
      v.pop_back();
      ++report_.merges;
    }
  }
}

template <int N>
bool FrontAdapter<N>::along_one_stream_line(const Front<N>& f, std::size_t i, std::size_t j,
                                            double s_next) const {
  // Seed parameters a few rounding steps apart, which seed points may still tell apart by a
  // rounding step; a segment that is not across the flow shows they name one stream line.
  const double s = std::abs(f.v[i].s) + std::abs(s_next);
  if (!(std::abs(s_next - f.v[i].s) <= 64 * std::numeric_limits<double>::epsilon() * s))
    return false;
  const Vec<N> d = f.v[j].x - f.v[i].x;
  Vec<N> v;
  if (field_.velocity(0.5 * (f.v[i].x + f.v[j].x), v) != FieldStatus::inside) return false;
  const double dv = d.norm() * v.norm();
  return dv > 0 && std::abs(d.dot(v)) > 0.5 * dv;
}

template <int N>
bool FrontAdapter<N>::split_long(Front<N>& f, const Front<N>* old, int step,
                                 std::vector<char>& cut) {
  const std::size_t n = f.v.size();
  const double limit = opt_.split_factor * opt_.edge;
  const std::size_t segments = f.closed ? n : n - 1;
  jobs_.clear();
  std::vector<char> unresolved(n, 0);
  bool any_cut = false;
  const auto seed_point = [this](double s) {
    return seed_.point(seed_.closed ? s - std::floor(s) : s);
  };
  for (std::size_t i = 0; i < segments; ++i) {
    const std::size_t j = next_index(i, n);
    const double length = (f.v[j].x - f.v[i].x).norm();
    if (!(length > limit)) continue;
    const int pieces = static_cast<int>(std::ceil(length / opt_.edge));
    const double s_next = end_parameter(f, j);
    const std::size_t first = jobs_.size();
    Vec<N> previous = seed_point(f.v[i].s);
    const Vec<N> last = seed_point(s_next);
    bool resolved = !along_one_stream_line(f, i, j, s_next);
    for (int k = 1; k < pieces && resolved; ++k) {
      InsertionJob job;
      job.segment = i;
      job.lambda = static_cast<double>(k) / pieces;
      job.s = between(f.v[i].s, s_next, job.lambda);
      job.t = between(f.v[i].t, f.v[j].t, job.lambda);
      const Vec<N> p = seed_point(job.s);
      resolved = p != previous && p != last;
      previous = p;
      jobs_.push_back(job);
    }
    if (!resolved) {
      jobs_.resize(first);
      unresolved[i] = 1;
      any_cut = true;
    }
  }
  cut.clear();
  if (jobs_.empty()) {
    if (any_cut) cut = std::move(unresolved);
    return any_cut;
  }
  // Each insertion integrates a stream line from the seed: independent and costly, so they run
  // in parallel; the mesh vertices are then emitted in front order, as a serial run would.
  for_range(
      jobs_.size(), 2,
      [&](std::size_t b, std::size_t e) {
        for (std::size_t k = b; k < e; ++k) insertion_point(f, old, jobs_[k]);
      },
      1);
  std::vector<FrontVertex<N>> out;
  out.reserve(n + jobs_.size());
  if (any_cut) cut.reserve(n + jobs_.size());
  // The vertices between segments with insertions go over in blocks (one copy each, not a
  // push per vertex: most segments have none).
  std::size_t copied = 0;  // f.v[0, copied) are in out
  const auto copy_through = [&](std::size_t end) {
    out.insert(out.end(), f.v.begin() + static_cast<std::ptrdiff_t>(copied),
               f.v.begin() + static_cast<std::ptrdiff_t>(end));
    if (any_cut)
      cut.insert(cut.end(), unresolved.begin() + static_cast<std::ptrdiff_t>(copied),
                 unresolved.begin() + static_cast<std::ptrdiff_t>(end));
    copied = end;
  };
  for (std::size_t next_job = 0; next_job < jobs_.size();) {
    const std::size_t i = jobs_[next_job].segment;
    copy_through(i + 1);
    const std::size_t j = next_index(i, n);
    // The segment's seed shots update its ends' count of misses in a row, and the vertices
    // inserted on it start with that count: a hit clears it, a miss adds one.
    bool hit = false, missed = false;
    for (std::size_t k = next_job; k < jobs_.size() && jobs_[k].segment == i; ++k) {
      hit = hit || jobs_[k].seed_shot_hit;
      missed = missed || jobs_[k].seed_shot_missed;
    }
    FrontVertex<N>& end = j == 0 ? out.front() : f.v[j];
    std::uint8_t misses = std::max(out.back().seed_misses, end.seed_misses);
    if (hit)
      misses = 0;
    else if (missed && misses < 255)
      ++misses;
    if (hit || missed) out.back().seed_misses = end.seed_misses = misses;
    for (; next_job < jobs_.size() && jobs_[next_job].segment == i; ++next_job) {
      const InsertionJob& job = jobs_[next_job];
      report_.field_evaluations += static_cast<std::size_t>(job.evaluations);
      if (job.outcome == InsertionJob::Outcome::streamline) ++report_.streamline_insertions;
      if (job.outcome == InsertionJob::Outcome::previous_row) {
        ++report_.previous_row_insertions;
        if (job.seed_shot_skipped) ++report_.seed_shots_skipped;
      }
      if (job.over_budget) ++report_.seed_shots_over_budget;
      if (job.exhausted_leg > 0)
        report_.seed_shot_time_limit = std::min(report_.seed_shot_time_limit, job.exhausted_leg);
      if (job.outcome == InsertionJob::Outcome::fallback && !job.interrupted) {
        ++report_.insertion_fallbacks;
        ++(job.left_domain ? report_.fallback_left_domain : report_.fallback_far_from_front);
      }
      FrontVertex<N> nv;
      nv.s = job.s;
      nv.t = job.t;
      nv.x = job.x;
      nv.anchor = nv.x;
      nv.origin = -1;
      nv.seed_misses = misses;
      const double a =
          mesh_.alpha.empty() ? 0.0 : 0.5 * (alpha_or_zero(f.v[i]) + alpha_or_zero(f.v[j]));
      nv.mesh = emit_vertex(mesh_, nv, seed_.closed, a, f.id, step);
      out.push_back(nv);
      if (any_cut) cut.push_back(0);
      ++report_.splits;
    }
  }
  copy_through(n);
  f.v = std::move(out);
  return any_cut;
}

template <int N>
void FrontAdapter<N>::start_likely_shots(const Front<N>& f, const Front<N>& old) {
  // On fronts of any size: the worker is idle through a step's serial stretches (sampling, α,
  // rips, merges), and a leg there costs the advance that waits for it less than its own
  // integration costs adapt, so the engine as a whole gains (figures:
  // docs/benchmarks/measurements.md; Lorenz makes no shots after its first steps).
  if (!opt_.shots_ahead || opt_.insertion != Insertion::streamline || !legs_.can_run_ahead())
    return;
  const std::size_t n = f.v.size();
  const std::size_t segments = f.closed ? n : n - 1;
  const double limit = opt_.split_factor * opt_.edge;
  likely_legs_.clear();
  for (std::size_t i = 0; i < segments; ++i) {
    const std::size_t j = next_index(i, n);
    const FrontVertex<N>& a = f.v[i];
    const FrontVertex<N>& b = f.v[j];
    // The next step's insertions here start from the seed in two legs only where these ends
    // stay neighbours, and from the previous row where shots beside them kept missing.
    if (!neighbours_in(old, a.origin, b.origin) || shots_kept_missing(a, b)) continue;
    const double before = (old.v[static_cast<std::size_t>(b.origin)].x -
                           old.v[static_cast<std::size_t>(a.origin)].x)
                              .norm();
    const double now = (b.x - a.x).norm();
    const double next = now * (now / before);  // grown once more at this step's rate
    // (A segment that would grow eightfold in a step is no guess worth a thread.)
    if (!(before > 0) || !(next > limit) || !(next < 8 * limit)) continue;
    // λ, s and t1 as split_long and insertion_point make them, for the same bits.
    const int pieces = static_cast<int>(std::ceil(next / opt_.edge));
    const double s_next = end_parameter(f, j);
    for (int k = 1; k < pieces; ++k) {
      const double lambda = static_cast<double>(k) / pieces;
      const double t1 = between(a.t, b.t, lambda);
      if (t1 > 0 && t1 < report_.seed_shot_time_limit)
        likely_legs_.emplace_back(between(a.s, s_next, lambda), t1);
    }
  }
  legs_.start_ahead(likely_legs_);
}

template <int N>
double FrontAdapter<N>::alpha_or_zero(const FrontVertex<N>& fv) const {
  return fv.mesh >= 0 ? mesh_.alpha[static_cast<std::size_t>(fv.mesh)] : 0.0;
}

template <int N>
bool FrontAdapter<N>::shoot(const Front<N>& f, std::size_t i, std::size_t j,
                            const Vec<N>& guess, const Vec<N>& start, double duration,
                            InsertionJob& job, FieldStatus& status) const {
  const double seg = (f.v[j].x - f.v[i].x).norm();
  IntegrationResult<N> r = integrate_dopri5(field_, start, duration, tol_, 0, &stop_);
  job.evaluations += r.evaluations;
  double time = job.t;
  for (int iteration = 0; iteration < 4 && r.status == FieldStatus::inside; ++iteration) {
    Vec<N> w;
    if (field_.velocity(r.x, w) != FieldStatus::inside) break;
    const double ww = w.squaredNorm();
    if (!(ww > 0)) break;
    const double delta = (guess - r.x).dot(w) / ww;
    if (std::abs(delta) * std::sqrt(ww) < 1e-6 * seg) break;
    // A Newton step longer than the segment means the stream line runs nearly parallel to
    // the front here (or the flow is slow): give up instead of integrating for ages.
    if (std::abs(delta) * std::sqrt(ww) > seg) break;
    r = integrate_dopri5(field_, r.x, delta, tol_, 0, &stop_);
    job.evaluations += r.evaluations + 1;
    time += delta;
  }
  status = r.status;
  job.interrupted = job.interrupted || r.interrupted;
  if (r.status != FieldStatus::inside || !((r.x - guess).norm() < 0.25 * seg)) return false;
  job.t = time;
  job.x = r.x;
  return true;
}

template <int N>
void FrontAdapter<N>::insertion_point(const Front<N>& f, const Front<N>* old,
                                      InsertionJob& job) const {
  using Outcome = typename InsertionJob::Outcome;
  const std::size_t i = job.segment;
  const std::size_t j = (i + 1) % f.v.size();
  const double s = job.s;
  if (job.t == 0) {
    job.x = seed_.point(s - std::floor(s));
    job.outcome = Outcome::seed;
    return;
  }
  const Vec<N> guess = cubic_point(f, i, job.lambda);
  if (opt_.insertion == Insertion::streamline || opt_.insertion == Insertion::previous_row) {
    // Where the ends came from neighbours: the previous front's point between the ends' origins
    // (on their stream lines to within the interpolation), that front's time there, and the
    // time left to this front.
    struct RowStart {
      Vec<N> x;
      double t1 = 0, left = 0;
    };
    std::optional<RowStart> row_start;
    if (old && neighbours_in(*old, f.v[i].origin, f.v[j].origin)) {
      const auto oi = static_cast<std::size_t>(f.v[i].origin);
      const auto oj = static_cast<std::size_t>(f.v[j].origin);
      const double t1 = between(old->v[oi].t, old->v[oj].t, job.lambda);
      row_start = RowStart{cubic_point(*old, oi, job.lambda), t1, job.t - t1};
    }
    FieldStatus status = FieldStatus::inside;
    // streamline: from the seed (exact), then from the previous row where that fails;
    // previous-row: from the previous row (one step's integration), else from the seed.
    // Where seed shots kept missing the front beside the segment, streamline starts from the
    // previous row too: there the seed's stream lines (chaotic flow, or a front that drifted
    // from its exact place) would cost the surface's whole age in integration to miss again.
    // And where the shot's first leg is at least as long as one that ran out of evaluations
    // (the seed's shot, on its budget, is then tried only where the row's fails).
    const bool missed_before = shots_kept_missing(f.v[i], f.v[j]);
    const bool too_long = row_start && row_start->t1 >= report_.seed_shot_time_limit;
    const bool row_first =
        row_start && (opt_.insertion == Insertion::previous_row || missed_before || too_long);
    const bool streamline = opt_.insertion == Insertion::streamline;
    job.seed_shot_skipped = streamline && row_start && missed_before;
    job.over_budget = streamline && too_long && !missed_before;
    for (int attempt = 0; attempt < 2; ++attempt) {
      const bool from_row = (attempt == 0) == row_first;
      if (from_row && !row_start) break;
      bool hit = false;
      if (from_row) {
        hit = shoot(f, i, j, guess, row_start->x, row_start->left, job, status);
      } else if (row_start && row_start->t1 > 0) {
        // From the seed in two legs, the first to the previous front's time: that one the
        // last step may have integrated ahead (start_likely_shots).
        const IntegrationResult<N> first = legs_.leg(s, row_start->t1);
        job.evaluations += first.evaluations;
        job.interrupted = job.interrupted || first.interrupted;
        status = first.status;
        if (first.exhausted && !first.interrupted && opt_.shot_evaluations > 0) {
          // Too costly rather than a miss: this shot and longer ones start from the row.
          job.over_budget = true;
          job.exhausted_leg = row_start->t1;
          continue;
        }
        hit = first.status == FieldStatus::inside &&
              shoot(f, i, j, guess, first.x, row_start->left, job, status);
      } else {
        hit = shoot(f, i, j, guess, seed_.point(s - std::floor(s)), job.t, job, status);
      }
      if (hit) {
        job.outcome = from_row ? Outcome::previous_row : Outcome::streamline;
        job.seed_shot_hit = !from_row;
        return;
      }
      if (!from_row) job.seed_shot_missed = true;
    }
    job.outcome = Outcome::fallback;
    job.left_domain = status != FieldStatus::inside;
    job.x = guess;
    return;
  }
  job.outcome = Outcome::interpolated;
  job.x = opt_.insertion == Insertion::cubic
              ? guess
              : Vec<N>(f.v[i].x + job.lambda * (f.v[j].x - f.v[i].x));
}

template class FrontAdapter<3>;
template class FrontAdapter<4>;

}  // namespace orthofront
