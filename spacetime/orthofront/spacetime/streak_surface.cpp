#include "orthofront/spacetime/streak_surface.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "orthofront/error.h"
#include "orthofront/seed/seed_check.h"
#include "orthofront/spacetime/aside_task.h"
#include "orthofront/spacetime/bulk_flow_map.h"
#include "orthofront/spacetime/remeshed_streak.h"
#include "orthofront/spacetime/streak_flow_access.h"
#include "orthofront/spacetime/streak_frame_finisher.h"
#include "orthofront/spacetime/streak_refinement.h"
#include "orthofront/spacetime/streak_release_schedule.h"
#include "orthofront/spacetime/streak_resident_set.h"
#include "orthofront/spacetime/streak_rows.h"
#include "orthofront/spacetime/streamed_field.h"
#include "orthofront/stage_timer.h"

namespace orthofront::spacetime {

const char* to_string(ParticleInsertion insertion) {
  return insertion == ParticleInsertion::exact ? "exact" : "interpolate";
}

const char* to_string(StreakMesh mesh) {
  return mesh == StreakMesh::remeshed ? "remeshed" : "rows";
}

namespace {

using Clock = std::chrono::steady_clock;
std::string number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", value);
  return text;
}

// Counts a particle's stop: [0] left the domain, [1] no data.
void count_stop(ParticleStatus status, std::array<std::size_t, 2>& stopped) {
  if (status == ParticleStatus::left_domain) ++stopped[0];
  if (status == ParticleStatus::no_data) ++stopped[1];
}

// The driver of a rows streak surface: releases rows as the schedule says, moves the particles
// from break to break (through the resident set where there is one), refines and coarsens the
// rows at each break, and builds the frames, which the finisher hands to the sink. With a
// resident set and overlap, the set moves on to the next break (and the rows released before it
// with it) while the rows are refined and the frame is built at this one.
class StreakBuilder final : private StreakRefinement::Owner {
 public:
  StreakBuilder(const StreakFlowAccess& access, const SeedCurve& seed, const StreakOptions& options,
                const StreakFrameSink& sink)
      : access_(access), flow_(access.flow), seed_(seed), o_(options),
        integrated_(access.flow, options.tolerance),
        map_(access.map ? *access.map : integrated_),
        finisher_(sink, options.finish_frames_aside) {
    if (access.bulk && options.resident_particles) resident_ = std::make_unique<StreakResidentSet>(*access.bulk);
  }
  StreakBuilder(const StreakBuilder&) = delete;
  StreakBuilder& operator=(const StreakBuilder&) = delete;

  StreakReport run();

 private:
  using Stops = StreakResidentSet::Stops;

  void validate();
  double seed_speed_median(const std::vector<double>& params) const;
  // The s of the newest row (the seed's before the first): a new row takes them, so the strip
  // between them is all quads.
  std::vector<double> newest_params() const;
  // The row released at tau with these s, on the seed (ids not given yet). Reads only the field:
  // it may run beside the driver.
  StreakRow seed_row(double tau, const std::vector<double>& params) const;
  void release(double tau);
  // Rows released between breaks (releases_per_break > 1), moved from their release times to
  // the next break in one call, with what the call counted.
  struct Released {
    std::vector<StreakRow> rows;
    std::size_t evaluations = 0, moved = 0;
    std::array<std::size_t, 2> stopped{0, 0};  // left the domain, no data
    double particle_time = 0;
  };
  Released release_and_move(const std::vector<double>& taus, const std::vector<double>& params,
                            double to) const;
  // Gives the released rows their ids and counts, appends them and enters their particles;
  // the driver's time on them is counted from `since`. Returns whether there was no read error.
  bool admit(Released released, Clock::time_point since);
  // Releases the rows of `taus` (before t_, increasing) and moves them to t_ (in turn).
  bool release_before(const std::vector<double>& taus);
  // Overlapped: the rows of `taus` (between t_ and the move's end) are released and moved there
  // as a task, beside the move, the frame and the next break's landing; take_released() admits
  // them once the move has landed.
  void start_release(const std::vector<double>& taus);
  bool take_released();
  // Stops the run at t_ for `error` (a read error; empty: none). Returns whether there was none.
  bool no_error(const std::string& error) {
    if (error.empty()) return true;
    report_.complete = false;
    report_.message = "stopped at t = " + number(t_) + ": " + error;
    return false;
  }
  bool read_ok() { return !access_.read_error || no_error(access_.read_error()); }
  // Moves the rows' moving particles to t_to in turn: through the resident set, or all of them
  // in one advect_all call.
  bool advance(double t_to);
  std::size_t move_all(double t_to, Stops& stopped);
  // Overlapped: sends the resident set on to t_to; land() waits for it and makes t_to the
  // current time.
  bool launch(double t_to);
  bool land();
  // Counts the moves of one interval of advance() or land().
  void count_interval(std::size_t moved, double t_to, const Stops& stopped);
  void adapt();
  void emit(int index);
  // The refinement's and the finisher's and the resident set's counts, into the report.
  void file_counts();

  // StreakRefinement::Owner: inserted particles released at their own (s, τ) and moved to now;
  // the resident set told of particles that come and go.
  bool place_exact(std::span<StreakParticle* const> fresh, std::span<const double> from) override;
  void enter(const std::vector<StreakParticle*>& ps) override {
    if (resident_) resident_->enter(ps);
  }
  void leave(StreakParticle& p) override {
    if (resident_) resident_->leave(p);
  }

  Vec3 seed_point(double s) const {
    Vec3 p = seed_.point(s);
    if (flow_.dimension() == 2) p.z() = 0;
    return p;
  }
  std::string seed_name() const { return o_.seed_name.empty() ? "the seed curve" : "seed '" + o_.seed_name + "'"; }
  std::string field_name() const { return o_.field_name.empty() ? flow_.describe() : o_.field_name; }

  const StreakFlowAccess& access_;
  const UnsteadyField& flow_;
  const SeedCurve& seed_;
  StreakOptions o_;
  IntegratedFlowMap integrated_;
  const FlowMap& map_;
  StreakReport report_;
  std::vector<double> seed_params_;
  std::vector<StreakRow> rows_;  // oldest first
  std::optional<StreakRefinement> refinement_;  // set once the release step is known
  StreakFrameFinisher finisher_;
  std::unique_ptr<StreakResidentSet> resident_;
  // move_all()'s scratch, reused every interval.
  std::vector<Vec3> x_;
  std::vector<double> from_;
  std::vector<ParticleStatus> status_;
  double t_ = 0;
  std::int32_t next_id_ = 0;
  Clock::time_point start_;
  Released released_;  // start_release()'s
  // Last: destroyed first, so rows being released are waited for while what they use is there.
  AsideTask release_;
};

void StreakBuilder::validate() {
  check_streak_options(o_, flow_, field_name());
  if (!(o_.merge > 0 && o_.merge <= 0.5 * o_.split))
    throw InvalidArgument(
        "merge factor must lie in (0, split/2] (so a merge never makes an edge that splits), got " +
        number(o_.merge));
  if (o_.releases_per_break < 1)
    throw InvalidArgument("releases per break must be at least 1, got " +
                          std::to_string(o_.releases_per_break));
}

double StreakBuilder::seed_speed_median(const std::vector<double>& params) const {
  std::vector<double> speeds;
  for (const double s : params) {
    Vec3 v;
    if (flow_.velocity(seed_point(s), o_.release_begin, v) == FieldStatus::inside) {
      if (flow_.dimension() == 2) v.z() = 0;
      speeds.push_back(v.norm());
    }
  }
  if (speeds.empty()) return -1;
  std::nth_element(speeds.begin(), speeds.begin() + static_cast<std::ptrdiff_t>(speeds.size() / 2),
                   speeds.end());
  return speeds[speeds.size() / 2];
}

std::vector<double> StreakBuilder::newest_params() const {
  if (rows_.empty()) return seed_params_;
  std::vector<double> s;
  s.reserve(rows_.back().p.size());
  for (const StreakParticle& p : rows_.back().p) s.push_back(p.s);
  return s;
}

StreakRow StreakBuilder::seed_row(double tau, const std::vector<double>& params) const {
  StreakRow row;
  row.tau = tau;
  row.p.reserve(params.size());
  for (const double s : params) {
    StreakParticle p;
    p.s = s;
    p.x = seed_point(s);
    Vec3 v;
    const FieldStatus st = flow_.velocity(p.x, tau, v);
    p.set_status(st == FieldStatus::inside ? ParticleStatus::moving
               : st == FieldStatus::outside ? ParticleStatus::left_domain
                                            : ParticleStatus::no_data);
    row.p.push_back(p);
  }
  return row;
}

void StreakBuilder::release(double tau) {
  // A new row takes the s of the newest one, so the strip between them is all quads.
  StreakRow row = seed_row(tau, newest_params());
  for (StreakParticle& p : row.p) p.id = next_id_++;
  std::vector<StreakParticle*> entering(row.p.size());
  for (std::size_t i = 0; i < row.p.size(); ++i) entering[i] = &row.p[i];
  enter(entering);
  rows_.push_back(std::move(row));
  ++report_.rows_released;
}

StreakBuilder::Released StreakBuilder::release_and_move(const std::vector<double>& taus,
                                                        const std::vector<double>& params,
                                                        double to) const {
  Released out;
  for (const double tau : taus) out.rows.push_back(seed_row(tau, params));
  std::vector<Vec3> x;
  std::vector<double> from;
  for (const StreakRow& row : out.rows)
    for (const StreakParticle& p : row.p)
      if (p.alive()) {
        x.push_back(p.x);
        from.push_back(row.tau);
      }
  std::vector<ParticleStatus> status(x.size());
  out.evaluations = map_.advect_all(x, from, to, status);
  std::size_t k = 0;
  for (StreakRow& row : out.rows)
    for (StreakParticle& p : row.p)
      if (p.alive()) {
        p.x = x[k];
        p.set_status(status[k]);
        count_stop(p.status(), out.stopped);
        out.particle_time += to - from[k++];
      }
  out.moved = x.size();
  return out;
}

bool StreakBuilder::admit(Released released, Clock::time_point since) {
  report_.evaluations += released.evaluations;
  report_.particle_steps += released.moved;
  report_.particle_time += released.particle_time;
  report_.left_domain += released.stopped[0];
  report_.no_data += released.stopped[1];
  ++report_.release_calls;
  std::vector<StreakParticle*> entering;
  for (StreakRow& row : released.rows) {
    ++report_.rows_released;
    ++report_.rows_released_between;
    for (StreakParticle& p : row.p) p.id = next_id_++;
    rows_.push_back(std::move(row));  // the particles stay where they are: pointers hold
    for (StreakParticle& p : rows_.back().p) entering.push_back(&p);
  }
  enter(entering);
  report_.release_call_seconds += seconds_since(since);
  report_.advect_seconds += seconds_since(since);
  return read_ok();
}

bool StreakBuilder::release_before(const std::vector<double>& taus) {
  const auto t0 = Clock::now();
  return admit(release_and_move(taus, newest_params(), t_), t0);
}

void StreakBuilder::start_release(const std::vector<double>& taus) {
  release_.start([this, taus, params = newest_params(), to = resident_->flight_to()] {
    released_ = release_and_move(taus, params, to);
  });
}

bool StreakBuilder::take_released() {
  if (!release_.started()) return true;
  const auto t0 = Clock::now();
  release_.wait();  // rethrows what the release threw
  return admit(std::exchange(released_, Released{}), t0);
}

bool StreakBuilder::advance(double t_to) {
  const auto t0 = Clock::now();
  if (access_.prepare && !no_error(access_.prepare(t_, t_to))) return false;
  Stops stopped(rows_.size(), {0, 0});
  const std::size_t n = resident_ ? resident_->advance(rows_, t_, t_to, stopped) : move_all(t_to, stopped);
  count_interval(n, t_to, stopped);
  report_.advect_seconds += seconds_since(t0);
  return read_ok();
}

void StreakBuilder::count_interval(std::size_t moved, double t_to, const Stops& stopped) {
  for (const auto& c : stopped) {
    report_.left_domain += c[0];
    report_.no_data += c[1];
  }
  report_.particle_steps += moved;
  report_.particle_time += static_cast<double>(moved) * (t_to - t_);
  ++report_.intervals;
  t_ = t_to;
  report_.time_reached = t_;
}

std::size_t StreakBuilder::move_all(double t_to, Stops& stopped) {
  // The moving particles, row after row (millions: each row finds its own, in parallel, at an
  // offset counted beforehand).
  const std::size_t nr = rows_.size();
  std::vector<std::size_t> first(nr + 1, 0);
  for_each_row(nr, [&](std::size_t r) {
    first[r + 1] = static_cast<std::size_t>(std::count_if(
        rows_[r].p.begin(), rows_[r].p.end(), [](const StreakParticle& p) { return p.alive(); }));
  });
  for (std::size_t r = 0; r < nr; ++r) first[r + 1] += first[r];
  const std::size_t n = first[nr];
  x_.resize(n);
  from_.resize(n);
  status_.resize(n);
  for_each_row(nr, [&](std::size_t r) {
    std::size_t k = first[r];
    for (const StreakParticle& p : rows_[r].p)
      if (p.alive()) {
        from_[k] = t_;
        x_[k++] = p.x;
      }
  });
  report_.evaluations += map_.advect_all(x_, from_, t_to, status_);
  for_each_row(nr, [&](std::size_t r) {
    std::size_t k = first[r];
    for (StreakParticle& p : rows_[r].p) {
      if (!p.alive()) continue;
      p.x = x_[k];
      p.set_status(status_[k++]);
      count_stop(p.status(), stopped[r]);
    }
  });
  return n;
}

bool StreakBuilder::launch(double t_to) {
  if (access_.prepare && !no_error(access_.prepare(t_, t_to))) return false;
  resident_->launch(t_, t_to);
  return true;
}

bool StreakBuilder::land() {
  const auto t0 = Clock::now();
  const double t_to = resident_->flight_to();
  Stops stopped(rows_.size(), {0, 0});
  const std::size_t moved = resident_->land(rows_, stopped);
  count_interval(moved, t_to, stopped);
  report_.advect_seconds += seconds_since(t0);
  return read_ok();
}

bool StreakBuilder::place_exact(std::span<StreakParticle* const> fresh, std::span<const double> from) {
  std::vector<Vec3> x(fresh.size());
  std::vector<ParticleStatus> status(fresh.size());
  for (std::size_t i = 0; i < fresh.size(); ++i) x[i] = seed_point(fresh[i]->s);
  // A streamed sweep moves the field's band and reads earlier steps: not while the set moves on
  // (it lands later; the particles inserted here are fresh and catch up then).
  if (access_.prepare && resident_) resident_->wait_flight();
  if (!no_error(advect_from_release(access_, map_, x, from, t_, status, report_.evaluations))) return false;
  for (std::size_t i = 0; i < fresh.size(); ++i) {
    fresh[i]->x = x[i];
    fresh[i]->set_status(status[i]);
  }
  return true;
}

void StreakBuilder::adapt() {
  if (!o_.adaptive) return;
  const auto t0 = Clock::now();
  refinement_->begin(rows_);
  for (int round = 0; round < o_.max_refinement_rounds; ++round) {
    if (!refinement_->refine_once(rows_, next_id_, *this)) break;
    if (particle_count(rows_) > o_.max_vertices) break;
  }
  if (resident_ && resident_->in_flight()) resident_->start_catch_up();  // beside coarsening
  const auto c0 = Clock::now();
  refinement_->coarsen(rows_, *this);
  report_.coarsen_seconds += seconds_since(c0);
  report_.refine_seconds += seconds_since(t0);
}

void StreakBuilder::emit(int index) {
  const auto t0 = Clock::now();
  StreakFrame frame;
  frame.mesh = finisher_.take_mesh();  // the frame before's, once finished
  const auto t_build = Clock::now();
  frame.index = index;
  frame.time = t_;
  frame.rows = rows_.size();
  const std::size_t dead = mesh_rows(rows_, seed_.closed(), t_, flow_, frame.mesh);
  StreakFrameRecord rec;
  rec.index = index;
  rec.time = t_;
  rec.vertices = frame.mesh.vertex_count();
  rec.faces = frame.mesh.face_count();
  rec.rows = rows_.size();
  rec.dead_particles = dead;
  rec.build_seconds = seconds_since(t_build);
  const double built = seconds_since(t0);
  report_.frame_seconds += built;
  report_.frame_seconds += finisher_.finish(std::move(frame), rec, built);  // 0 when aside
}

void StreakBuilder::file_counts() {
  const StreakRefinement::Counts& c = refinement_->counts();
  report_.s_insertions = c.s_insertions;
  report_.rows_inserted = c.rows_inserted;
  report_.row_particles = c.row_particles;
  report_.exact_insertions = c.exact_insertions;
  report_.interpolated_insertions = c.interpolated_insertions;
  report_.s_removals = c.s_removals;
  report_.rows_removed = c.rows_removed;
  report_.frames = finisher_.records();
  report_.frame_finish_seconds = finisher_.finish_seconds();
  if (!resident_) return;
  const StreakResidentSet::Counts& r = resident_->counts();
  report_.evaluations += r.evaluations;
  report_.catch_up_calls = r.catch_up_calls;
  report_.catch_up_particles = r.catch_up_particles;
  report_.take_seconds = r.take_seconds;
  report_.catch_up_seconds = r.catch_up_seconds;
  report_.catch_up_call_seconds = r.catch_up_call_seconds;
}

StreakReport StreakBuilder::run() {
  start_ = Clock::now();
  validate();
  report_.mesh = to_string(StreakMesh::rows);
  report_.dimension = flow_.dimension();
  report_.insertion = o_.insertion;
  report_.release_begin = o_.release_begin;
  report_.release_end = o_.release_end;
  const int count = o_.seed_count > 0
                        ? o_.seed_count
                        : static_cast<int>(std::clamp(std::ceil(seed_.length() / o_.edge), 1.0, 1e6)) + 1;
  seed_params_ = seed_.sample(count);
  report_.seed_count = seed_params_.size();
  SeedSurvey survey;
  for (const double s : seed_params_) {
    Vec3 v = Vec3::Zero();
    const Vec3 x = seed_point(s);
    survey.add(x, flow_.velocity(x, o_.release_begin, v), v);
  }
  SeedContext context;
  context.seed = seed_name();
  context.field = o_.field_name.empty() ? "the field" : "field '" + o_.field_name + "'";
  context.about = flow_.describe();
  context.when = " at t = " + number(o_.release_begin);
  context.domain = describe_box(flow_.domain(), flow_.dimension());
  context.dimension = flow_.dimension();
  require_seed_inside(survey, context, false);
  StreakReleaseSchedule schedule(o_, seed_speed_median(seed_params_), access_.step_times);
  report_.release_step = schedule.release_step();
  StreakRefinement::Limits limits;
  limits.edge = o_.edge;
  limits.split = o_.split;
  limits.merge = o_.merge;
  limits.insertion = o_.insertion;
  limits.closed = seed_.closed();
  limits.min_ds = 1e-12;
  limits.min_dtau = schedule.release_step() * 1e-9;
  refinement_.emplace(limits);

  t_ = o_.release_begin;
  const std::vector<double>& breaks = schedule.breaks();
  const double t_last = o_.frames.back();
  std::size_t next_frame = 0;
  const auto stop = [&](const std::string& why) {
    report_.complete = false;
    report_.message = why;
  };
  // With overlap, the particles move on to the next break while this one is refined (a row
  // released here goes with them: it needs no catch-up).
  const bool overlap = resident_ && o_.overlap_advection;
  for (std::size_t i = 0; i < breaks.size(); ++i) {
    const double b = breaks[i];
    if (resident_ && resident_->in_flight()) {
      if (!land()) break;
    } else if (b > t_) {
      if (!advance(b)) break;
    }
    if (!take_released()) break;
    const std::vector<double> before = schedule.take_before(b);  // since the last stop (in turn)
    if (!before.empty() && !release_before(before)) break;
    if (schedule.take_at(b)) release(b);
    if (overlap && i + 1 < breaks.size() && !launch(breaks[i + 1])) break;
    adapt();
    if (!report_.complete) break;  // a read error while inserting
    if (resident_ && resident_->in_flight()) {
      // The rows released before the move lands go there beside it (their s are the newest
      // row's now: nothing changes them before it lands).
      const std::vector<double> ahead = schedule.take_before(resident_->flight_to());
      if (!ahead.empty()) start_release(ahead);
    }
    report_.max_particles = std::max(report_.max_particles, particle_count(rows_));
    if (particle_count(rows_) > o_.max_vertices) {
      stop("stopped at t = " + number(t_) + ": " + std::to_string(particle_count(rows_)) +
           " particles exceed the cap of " + std::to_string(o_.max_vertices));
      break;
    }
    if (next_frame < o_.frames.size() && o_.frames[next_frame] == b) {
      emit(static_cast<int>(next_frame));
      ++next_frame;
    }
    if (finisher_.failed()) finisher_.wait();  // the sink threw: stop here
    if (o_.progress) {
      StreakProgress p;
      p.t = t_;
      p.t_end = t_last;
      p.frames_written = next_frame;
      p.frames = o_.frames.size();
      p.particles = particle_count(rows_);
      p.rows = rows_.size();
      p.elapsed_seconds = seconds_since(start_);
      p.advect_seconds = report_.advect_seconds;
      p.refine_seconds = report_.refine_seconds;
      p.frame_seconds = report_.frame_seconds;
      if (!o_.progress(p)) {
        stop("interrupted at t = " + number(t_) + " after " + std::to_string(next_frame) + " of " +
             std::to_string(o_.frames.size()) + " frames");
        break;
      }
    }
  }
  if (resident_) resident_->wait_flight();  // a run stopped early: that move's positions are not taken
  release_.wait_dropping_errors();          // nor the rows released before it
  const auto t_join = Clock::now();
  finisher_.wait();
  report_.frame_seconds += seconds_since(t_join);
  file_counts();
  report_.total_seconds = seconds_since(start_);
  return report_;
}

}  // namespace

StreakReport build_streak_surface(const UnsteadyField& flow, const SeedCurve& seed,
                                  const StreakOptions& options, const StreakFrameSink& sink) {
  const StreakFlowAccess access{flow, {}, {}, {}};
  if (options.mesh == StreakMesh::remeshed) return build_remeshed_streak(access, seed, options, sink);
  return StreakBuilder(access, seed, options, sink).run();
}

StreakReport build_streak_surface(BrickCache& cache, const SeedCurve& seed,
                                  const StreakOptions& options, const StreakFrameSink& sink) {
  StreamedField field(cache);
  StreakFlowAccess access{field, {}, {}, cache.times()};
  // One past the last step the run reads: the one after the last frame's interval.
  std::size_t steps_needed = cache.times().size();
  {
    std::size_t k = 0;
    double w = 0;
    if (!options.frames.empty() && locate_time(cache.times(), options.frames.back(), k, w))
      steps_needed = std::min(steps_needed, k + 2);
  }
  // The most steps the budget holds: a request need not name more (each walks what it names).
  const std::size_t step_bytes = std::max<std::size_t>(1, cache.unit_bytes() * cache.layout().bricks());
  const std::size_t steps_held = cache.budget() / step_bytes + 1;
  std::size_t read_ahead_from = cache.times().size();  // the step the last request was made at
  access.prepare = [&](double t_a, double t_b) -> std::string {
    try {
      field.update_band(t_a, t_b);
    } catch (const InvalidArgument&) {
      throw;  // the budget cannot hold two steps
    } catch (const Error& e) {
      return e.what();  // a read error: the frames handed over stay valid
    }
    // Read every later step the run needs while this interval is computed, nearest first: the
    // cache stops where its prefetch share is full. Intervals take uneven time (a frame, a large
    // refinement), and a reader kept a few steps ahead idles through the slow ones and holds the
    // run up in the fast ones after them (256^3 steps, three ahead: 4.4-5.0 s waiting for data).
    // Asked again only where the interval reaches another step: the request walks every unit it
    // names, and units read ahead stay resident until loads need their room (units behind the
    // band go first), so asking at every interval would only walk them again.
    std::size_t k = 0;
    double w = 0;
    if (locate_time(cache.times(), t_b, k, w) && k != read_ahead_from && k + 2 < steps_needed) {
      read_ahead_from = k;
      cache.prefetch(cache.step_keys(k + 2, std::min(steps_needed, k + 2 + steps_held)));
    }
    return {};
  };
  access.read_error = [&] { return field.error(); };
  std::unique_ptr<CachedSteps> steps;
  std::unique_ptr<BulkFlowMap> bulk;
  if (options.device) {
    steps = std::make_unique<CachedSteps>(cache);
    advect::MethodOptions method;
    method.method = advect::Method::dopri5;
    method.absolute = options.tolerance.absolute;
    method.relative = options.tolerance.relative;
    bulk = std::make_unique<BulkFlowMap>(*steps, advect::make_advector(*options.device, options.device_bytes),
                                         method);
    access.map = bulk.get();
    access.bulk = bulk.get();
  }
  StreakReport report = options.mesh == StreakMesh::remeshed
                            ? build_remeshed_streak(access, seed, options, sink)
                            : StreakBuilder(access, seed, options, sink).run();
  if (bulk) {
    report.device = bulk->backend_name();
    report.bulk = bulk->statistics();
    report.bulk_batch = bulk->batch_statistics();
  }
  report.streamed = true;
  report.cache = cache.statistics();
  report.slow_evaluations = field.slow_evaluations();
  report.wait_seconds = report.cache.wait_seconds;
  report.io_seconds = report.cache.read_seconds;
  report.decode_seconds = report.cache.decode_seconds;
  return report;
}

}  // namespace orthofront::spacetime
