#include "orthofront/spacetime/streak_surface.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cassert>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <memory>
#include <optional>
#include <thread>
#include <utility>

#include "orthofront/error.h"
#include "orthofront/seed/seed_check.h"
#include "orthofront/spacetime/bulk_flow_map.h"
#include "orthofront/spacetime/remeshed_streak.h"
#include "orthofront/spacetime/streak_flow_access.h"
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

// Runs f(r) for r in [0, n), rows in parallel (each row's work is independent of the others'), or
// in turn where the work is too small to wake the threads for (`parallel` false).
template <class F>
void for_each_row(std::size_t n, const F& f, bool parallel = true) {
  if (!parallel) {
    for (std::size_t r = 0; r < n; ++r) f(r);
    return;
  }
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t r = range.begin(); r != range.end(); ++r) f(r);
                    });
}

// Resizes a frame's array to n elements. One that must grow is first emptied (nothing of it is
// kept: every element is written anew) and reserved anew, so that a frame several times larger
// than the last is not copied over (the mesh's arrays take their huge pages from their
// allocator).
template <class T, class Allocator>
void grow(std::vector<T, Allocator>& values, std::size_t n) {
  if (values.capacity() < n) {
    std::vector<T, Allocator>().swap(values);
    values.reserve(n + n / 4);  // room for the next frame to grow a little
  }
  values.resize(n);
}

// Fewer particles than this are handled in turn: waking the threads costs more.
constexpr std::size_t kParallelParticles = 32768;

constexpr std::uint32_t kNoSlot = ~std::uint32_t{0};

// Compares lengths |d| with a limit as `d.norm() < limit` (or <=) does, bit for bit, without a
// square root where |d|² is clearly on one side (the passes over every edge of every row are
// bound by the root's latency otherwise).
class LengthLimit {
 public:
  explicit LengthLimit(double limit)
      : limit_(limit), below_(limit * limit * (1 - 1e-12)), above_(limit * limit * (1 + 1e-12)) {}
  bool shorter(const Vec3& d) const {
    const double q = d.squaredNorm();
    return q < below_ || (q <= above_ && std::sqrt(q) < limit_);
  }
  bool not_longer(const Vec3& d) const {
    const double q = d.squaredNorm();
    return q < below_ || (q <= above_ && std::sqrt(q) <= limit_);
  }
  /// A square above this has a root above the limit, whatever the roundings.
  double above_squared() const { return above_; }

 private:
  double limit_, below_, above_;
};

// A distance between neighbouring rows not measured yet (or changed since).
constexpr double kUnmeasured = -1;

// A particle of a row. Its slot in the resident set and its status share a word: 40 bytes
// instead of 48, as the passes over the rows of ten million particles are bound by memory.
class Particle {
 public:
  /// Slots are below this (where slots are handed out, more particles are refused).
  static constexpr std::uint32_t kSlots = (std::uint32_t{1} << 30) - 1;

  double s = 0;
  Vec3 x = Vec3::Zero();
  std::int32_t id = 0;

  ParticleStatus status() const { return static_cast<ParticleStatus>(word_ >> kSlotBits); }
  void set_status(ParticleStatus status) {
    word_ = (word_ & kSlots) | (static_cast<std::uint32_t>(status) << kSlotBits);
  }
  bool alive() const { return word_ < (std::uint32_t{1} << kSlotBits); }  // status moving
  /// In the resident set (moving particles only), if there is one; else kNoSlot.
  std::uint32_t slot() const { return (word_ & kSlots) == kSlots ? kNoSlot : word_ & kSlots; }
  void set_slot(std::uint32_t slot) {
    word_ = (word_ & ~kSlots) | (slot == kNoSlot ? kSlots : slot);
  }

 private:
  static constexpr int kSlotBits = 30;
  static_assert(static_cast<unsigned>(ParticleStatus::time_bounds) < 4, "two bits of status");
  std::uint32_t word_ = kSlots;  // status moving (0) in the top bits, no slot
};
static_assert(sizeof(Particle) == 40);

struct Row {
  double tau = 0;  // release time
  std::vector<Particle> p;  // by increasing s
  // Coarsening's first candidate: no particle before it can go. Found by refinement's first pass
  // (the row is in cache there), kept as particles are inserted after it; 1 when unknown.
  std::size_t coarsen_from = 1;
};

// Whether particle m, between a and b on a row, may go: both its edges are short, and a and b
// would not be too far apart without it.
bool removable(const Particle& a, const Particle& m, const Particle& b,
               const LengthLimit& short_limit, const LengthLimit& long_limit) {
  return a.alive() && m.alive() && b.alive() && short_limit.shorter(a.x - m.x) &&
         short_limit.shorter(m.x - b.x) && long_limit.shorter(a.x - b.x);
}

class StreakBuilder {
 public:
  StreakBuilder(const StreakFlowAccess& access, const SeedCurve& seed, const StreakOptions& options,
                const StreakFrameSink& sink)
      : access_(access), flow_(access.flow), seed_(seed), o_(options), sink_(sink),
        integrated_(access.flow, options.tolerance),
        map_(access.map ? *access.map : integrated_) {
    if (access.bulk && options.resident_particles) resident_ = access.bulk->make_resident();
  }

  // A run that throws leaves a frame being finished, and maybe a move in flight: wait for them
  // (their own errors are dropped).
  ~StreakBuilder() {
    if (finisher_.joinable()) finisher_.join();
    if (flight_.joinable()) flight_.join();
    if (catch_up_.joinable()) catch_up_.join();
    if (release_thread_.joinable()) release_thread_.join();
  }
  StreakBuilder(const StreakBuilder&) = delete;
  StreakBuilder& operator=(const StreakBuilder&) = delete;

  StreakReport run();

 private:
  void validate();
  double seed_speed_median(const std::vector<double>& params) const;
  // The s of the newest row (the seed's before the first): a new row takes them, so the strip
  // between them is all quads.
  std::vector<double> newest_params() const;
  // The row released at tau with these s, on the seed (ids not given yet).
  Row seed_row(double tau, const std::vector<double>& params) const;
  void release(double tau);
  // Rows released between breaks (releases_per_break > 1), moved from their release times to
  // the next break in one call, with what the call counted.
  struct Released {
    std::vector<Row> rows;
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
  // on a thread of their own, beside the move, the frame and the next break's landing;
  // take_released() admits them once the move has landed.
  void start_release(const std::vector<double>& taus);
  bool take_released();
  // New moving particles take slots of the resident set, in order (freed slots last first, then
  // new ones), and go there (while a move is in flight: they catch up and go there when it
  // lands); one leaving the rows gives its slot back (no-ops without a resident set).
  void enter(const std::vector<Particle*>& ps);
  void leave(Particle& p);
  // Stops the run at t_ for `error` (a read error; empty: none). Returns whether there was none.
  bool no_error(const std::string& error) {
    if (error.empty()) return true;
    report_.complete = false;
    report_.message = "stopped at t = " + number(t_) + ": " + error;
    return false;
  }
  bool advance(double t_to);
  // advance()'s move of the rows' moving particles: through the resident set, or all of them in
  // one advect_all call. Returns how many moved.
  std::size_t move_resident(double t_to, std::vector<std::array<std::size_t, 2>>& stopped);
  std::size_t move_all(double t_to, std::vector<std::array<std::size_t, 2>>& stopped);
  // Takes the resident set's positions and statuses into the rows. Particles entered while a move
  // was in flight are left as they are; with `fresh_at`, their indices go to (*fresh_at)[row].
  // Returns how many it took.
  std::size_t take_resident(std::vector<std::array<std::size_t, 2>>& stopped,
                            std::vector<std::vector<std::uint32_t>>* fresh_at = nullptr);
  // Overlapped advection: launch() sends the resident set on to t_to from a thread of its own
  // while the driver refines the rows at t_; particles entering meanwhile are marked fresh (with
  // their positions) and parks wait. start_catch_up() moves the fresh particles to t_to in one
  // call from another thread (after the move: the calls take turns), beside coarsening and the
  // frame. land() takes the positions of both, places the fresh particles still in the rows, and
  // makes t_to the current time. wait_flight() only waits for both.
  bool launch(double t_to);
  void start_catch_up();
  bool land();
  void wait_flight() {
    if (flight_.joinable()) flight_.join();
    if (catch_up_.joinable()) catch_up_.join();
  }
  bool fresh(const Particle& p) const { return p.slot() < fresh_.size() && fresh_[p.slot()] != 0; }
  // Counts the moves of one interval of advance() or land().
  void count_interval(std::size_t moved, double t_to,
                      const std::vector<std::array<std::size_t, 2>>& stopped);
  void adapt();
  // A particle to insert on a row, after its particle `after`.
  struct Insert {
    std::size_t after;
    Particle particle;
  };
  // What changed in a row since the last pass looked at it: all of it (a new row, or the first
  // pass), or the particles at `added` (indices, increasing). An edge or a row distance that a pass
  // found short stays short while its particles stay where they are, so the next pass looks only
  // at the edges beside added particles and updates the distances with them.
  struct RowChange {
    bool whole = true;
    std::vector<std::uint32_t> added;
    bool any() const { return whole || !added.empty(); }
  };
  // One pass of splits over the rows that changed since the last one; sets `change` for the next
  // pass. gap[r]: the distance of rows r and r + 1 where known (kUnmeasured otherwise), kept up to
  // date as rows change and reused by coarsen().
  bool refine_once(std::vector<RowChange>& change, std::vector<double>& gap);
  // The particles to insert on row r's edges longer than `long_edge`: all edges, or those beside
  // the particles `added`.
  std::vector<Insert> inserts_along(std::size_t r, double long_edge, const RowChange& change) const;
  // The row to insert between rows r and r + 1 when they are more than `long_edge` apart;
  // measures their distance into `gap` when it is not known (where they are that far apart, a
  // distance beyond long_edge, not necessarily the largest).
  std::optional<Row> row_between(std::size_t r, double long_edge, double& gap) const;
  // The distance of rows r and r + 1 after particles were added to them (`gap`: before).
  double grown_gap(std::size_t r, double gap, const RowChange& a, const RowChange& b) const;
  // Hands the faces between rows r and r + 1 to `face`, in order (see the definition).
  template <class F>
  void for_each_strip_face(std::size_t r, const std::vector<std::int32_t>& va,
                           const std::vector<std::int32_t>& vb, const F& face) const;
  bool release_and_advect(std::vector<Vec3>& x, const std::vector<double>& from,
                          std::vector<ParticleStatus>& status);
  void coarsen(std::vector<double>& gap);
  void emit(int index);
  // Quality, longest edge and the sink of the frame in finishing_ (built: the seconds its
  // vertices and faces took); an exception is kept for collect_frame().
  void finish_frame(double built);
  // Waits for the frame being finished aside, if any, and collects it.
  void join_finisher();
  // Rethrows what the finished frame's sink threw; files its record; keeps its mesh as spare.
  void collect_frame();
  // The largest distance between the particles of rows a and b that share a seed parameter;
  // or, as soon as one is longer than `stop` for certain, that one: callers only compare the
  // result with stop's limit, and rows that far apart are found out at their first pair beyond.
  double row_distance(const Row& a, const Row& b, const LengthLimit& stop) const;
  // The first particle of p (a row) that coarsening removes, looking from index `from` (>= 1)
  // on; p.size() - 1 or more where none does.
  std::size_t first_removable(const std::vector<Particle>& p, std::size_t from) const;
  Vec3 seed_point(double s) const {
    Vec3 p = seed_.point(s);
    if (flow_.dimension() == 2) p.z() = 0;
    return p;
  }
  std::size_t particle_count() const {
    std::size_t n = 0;
    for (const Row& r : rows_) n += r.p.size();
    return n;
  }
  std::string seed_name() const { return o_.seed_name.empty() ? "the seed curve" : "seed '" + o_.seed_name + "'"; }
  std::string field_name() const { return o_.field_name.empty() ? flow_.describe() : o_.field_name; }

  const StreakFlowAccess& access_;
  const UnsteadyField& flow_;
  const SeedCurve& seed_;
  StreakOptions o_;
  const StreakFrameSink& sink_;
  IntegratedFlowMap integrated_;
  const FlowMap& map_;
  StreakReport report_;
  std::vector<double> seed_params_;
  std::vector<Row> rows_;  // oldest first
  // The last frame's mesh, kept for its memory: a frame of millions of vertices written into
  // fresh arrays spends most of its time in page faults and zero fills.
  Mesh spare_mesh_;
  // The frame being finished (quality, sink) on a thread of its own while the particles move
  // on; its record and mesh come back when it is joined. frame_failed_: its sink threw.
  std::thread finisher_;
  StreakFrame finishing_;
  StreakFrameRecord finishing_record_;
  double finishing_seconds_ = 0;
  std::exception_ptr finisher_error_;
  std::atomic<bool> frame_failed_{false};
  std::unique_ptr<advect::ResidentParticles> resident_;
  std::vector<std::uint32_t> free_slots_;  // given back, taken last first
  std::uint32_t next_slot_ = 0;            // never handed out yet from here on
  // The resident set's move to flight_to_, running beside refinement and frames (launch/land).
  std::thread flight_;
  bool in_flight_ = false;
  double flight_to_ = 0;
  std::size_t flight_evaluations_ = 0;
  std::exception_ptr flight_error_;
  std::vector<std::uint32_t> fresh_;         // [slot]: 1 + its index in fresh_slots_, 0: not fresh
  std::vector<std::uint32_t> fresh_slots_;   // slots entered while a move was in flight
  std::vector<Vec3> fresh_x_;                // their positions then (at t_)
  std::thread catch_up_;
  bool catching_up_ = false;                 // start_catch_up() ran for this move
  std::vector<Vec3> catch_x_;                // the catch-up call's particles, as fresh_slots_
  std::vector<double> catch_from_;
  std::vector<ParticleStatus> catch_status_;
  std::vector<std::uint32_t> place_slots_;   // land(): the fresh particles still moving, to place
  std::vector<std::array<double, 3>> place_at_;
  std::size_t catch_up_evaluations_ = 0;
  double catch_up_call_seconds_ = 0;
  std::exception_ptr catch_up_error_;
  std::thread release_thread_;               // start_release()'s, joined by take_released()
  Released released_;
  std::exception_ptr release_error_;
  std::vector<std::uint32_t> flight_parks_;  // left while in flight: parked when it lands
  std::vector<std::uint32_t> flight_freed_;  // given back while in flight: free once it lands
  std::vector<Vec3> x_;
  std::vector<double> from_;
  std::vector<ParticleStatus> status_;
  double t_ = 0;
  std::int32_t next_id_ = 0;
  double min_ds_ = 0, min_dtau_ = 0;
  Clock::time_point start_;
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

namespace {

// Counts a particle's stop: [0] left the domain, [1] no data.
void count_stop(ParticleStatus status, std::array<std::size_t, 2>& stopped) {
  if (status == ParticleStatus::left_domain) ++stopped[0];
  if (status == ParticleStatus::no_data) ++stopped[1];
}

}  // namespace

std::vector<double> StreakBuilder::newest_params() const {
  if (rows_.empty()) return seed_params_;
  std::vector<double> s;
  s.reserve(rows_.back().p.size());
  for (const Particle& p : rows_.back().p) s.push_back(p.s);
  return s;
}

// (Reads only the field: it may run beside the driver.)
Row StreakBuilder::seed_row(double tau, const std::vector<double>& params) const {
  Row row;
  row.tau = tau;
  row.p.reserve(params.size());
  for (const double s : params) {
    Particle p;
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
  Row row = seed_row(tau, newest_params());
  for (Particle& p : row.p) p.id = next_id_++;
  std::vector<Particle*> entering(row.p.size());
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
  for (const Row& row : out.rows)
    for (const Particle& p : row.p)
      if (p.alive()) {
        x.push_back(p.x);
        from.push_back(row.tau);
      }
  std::vector<ParticleStatus> status(x.size());
  out.evaluations = map_.advect_all(x, from, to, status);
  std::size_t k = 0;
  for (Row& row : out.rows)
    for (Particle& p : row.p)
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
  std::vector<Particle*> entering;
  for (Row& row : released.rows) {
    ++report_.rows_released;
    ++report_.rows_released_between;
    for (Particle& p : row.p) p.id = next_id_++;
    rows_.push_back(std::move(row));  // the particles stay where they are: pointers hold
    for (Particle& p : rows_.back().p) entering.push_back(&p);
  }
  enter(entering);
  report_.release_call_seconds += seconds_since(since);
  report_.advect_seconds += seconds_since(since);
  return !access_.read_error || no_error(access_.read_error());
}

bool StreakBuilder::release_before(const std::vector<double>& taus) {
  const auto t0 = Clock::now();
  return admit(release_and_move(taus, newest_params(), t_), t0);
}

void StreakBuilder::start_release(const std::vector<double>& taus) {
  release_error_ = nullptr;
  release_thread_ = std::thread([this, taus, params = newest_params(), to = flight_to_] {
    try {
      released_ = release_and_move(taus, params, to);
    } catch (...) {
      release_error_ = std::current_exception();
    }
  });
}

bool StreakBuilder::take_released() {
  if (!release_thread_.joinable()) return true;
  const auto t0 = Clock::now();
  release_thread_.join();
  if (release_error_) std::rethrow_exception(std::exchange(release_error_, nullptr));
  return admit(std::exchange(released_, Released{}), t0);
}

bool StreakBuilder::advance(double t_to) {
  const auto t0 = Clock::now();
  if (access_.prepare && !no_error(access_.prepare(t_, t_to))) return false;
  const std::size_t nr = rows_.size();
  std::vector<std::array<std::size_t, 2>> stopped(nr, {0, 0});  // [r]: left the domain, no data
  const std::size_t n = resident_ ? move_resident(t_to, stopped) : move_all(t_to, stopped);
  count_interval(n, t_to, stopped);
  report_.advect_seconds += seconds_since(t0);
  return !access_.read_error || no_error(access_.read_error());
}

void StreakBuilder::count_interval(std::size_t moved, double t_to,
                                   const std::vector<std::array<std::size_t, 2>>& stopped) {
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

std::size_t StreakBuilder::move_all(double t_to, std::vector<std::array<std::size_t, 2>>& stopped) {
  // The moving particles, row after row (millions: each row finds its own, in parallel, at an
  // offset counted beforehand). Scratch buffers are members: they are reused every interval.
  const std::size_t nr = rows_.size();
  std::vector<std::size_t> first(nr + 1, 0);
  for_each_row(nr, [&](std::size_t r) {
    first[r + 1] = static_cast<std::size_t>(
        std::count_if(rows_[r].p.begin(), rows_[r].p.end(), [](const Particle& p) { return p.alive(); }));
  });
  for (std::size_t r = 0; r < nr; ++r) first[r + 1] += first[r];
  const std::size_t n = first[nr];
  x_.resize(n);
  from_.resize(n);
  status_.resize(n);
  for_each_row(nr, [&](std::size_t r) {
    std::size_t k = first[r];
    for (const Particle& p : rows_[r].p)
      if (p.alive()) {
        from_[k] = t_;
        x_[k++] = p.x;
      }
  });
  report_.evaluations += map_.advect_all(x_, from_, t_to, status_);
  for_each_row(nr, [&](std::size_t r) {
    std::size_t k = first[r];
    for (Particle& p : rows_[r].p) {
      if (!p.alive()) continue;
      p.x = x_[k];
      p.set_status(status_[k++]);
      count_stop(p.status(), stopped[r]);
    }
  });
  return n;
}

std::size_t StreakBuilder::move_resident(double t_to, std::vector<std::array<std::size_t, 2>>& stopped) {
  report_.evaluations += access_.bulk->advance(*resident_, t_, t_to);
  return take_resident(stopped);
}

std::size_t StreakBuilder::take_resident(std::vector<std::array<std::size_t, 2>>& stopped,
                                         std::vector<std::vector<std::uint32_t>>* fresh_at) {
  const auto t0 = Clock::now();
  const advect::ResidentParticles::View v = resident_->view();
  const std::size_t nr = rows_.size();
  std::vector<std::size_t> moved(nr, 0), unplaced(nr, 0);
  std::vector<std::vector<std::uint32_t>> freed(nr);  // slots of particles that stopped
  for_each_row(nr, [&](std::size_t r) {
    std::vector<Particle>& row = rows_[r].p;
    for (std::size_t i = 0; i < row.size(); ++i) {
      Particle& p = row[i];
      if (!p.alive()) continue;
      if (fresh(p)) {
        if (fresh_at) (*fresh_at)[r].push_back(static_cast<std::uint32_t>(i));
        continue;
      }
      if (p.slot() >= v.size) {
        ++unplaced[r];
        continue;
      }
      ++moved[r];
      p.x = Vec3(v.x[0][p.slot()], v.x[1][p.slot()], v.x[2][p.slot()]);
      p.set_status(v.status[p.slot()]);
      if (p.alive()) continue;
      count_stop(p.status(), stopped[r]);
      freed[r].push_back(p.slot());  // stopped there: nothing moves it again
      p.set_slot(kNoSlot);
    }
  });
  std::size_t n = 0;
  for (std::size_t r = 0; r < nr; ++r) {
    if (unplaced[r] > 0)
      throw Error("streak surface: " + std::to_string(unplaced[r]) +
                  " moving particles of a row have no place in the resident set");
    n += moved[r];
    free_slots_.insert(free_slots_.end(), freed[r].begin(), freed[r].end());
  }
  report_.take_seconds += seconds_since(t0);
  return n;
}

void StreakBuilder::enter(const std::vector<Particle*>& ps) {
  if (!resident_ || ps.empty()) return;
  // The k-th moving particle takes the k-th slot: the free slots from the back, then new ones.
  // Counted in blocks, then handed out block by block in parallel.
  constexpr std::size_t kBlock = 1 << 14;
  const std::size_t blocks = (ps.size() + kBlock - 1) / kBlock;
  std::vector<std::size_t> before(blocks + 1, 0);  // moving particles before each block
  const auto block_range = [&](std::size_t b) {
    return std::pair(b * kBlock, std::min(ps.size(), (b + 1) * kBlock));
  };
  const bool parallel = ps.size() >= kParallelParticles;
  for_each_row(blocks, [&](std::size_t b) {
    const auto [lo, hi] = block_range(b);
    before[b + 1] = static_cast<std::size_t>(std::count_if(ps.begin() + static_cast<std::ptrdiff_t>(lo),
                                                           ps.begin() + static_cast<std::ptrdiff_t>(hi),
                                                           [](const Particle* p) { return p->alive(); }));
  }, parallel);
  for (std::size_t b = 0; b < blocks; ++b) before[b + 1] += before[b];
  const std::size_t moving = before[blocks];
  if (moving == 0) return;
  if (in_flight_ && catching_up_) throw Error("streak surface: a particle entered after its catch-up started");
  const std::size_t free = free_slots_.size();
  if (moving > free && next_slot_ + (moving - free) > Particle::kSlots)
    throw Error("streak surface: " + std::to_string(next_slot_ + (moving - free)) +
                " slots of the resident set in use at once, more than the " +
                std::to_string(Particle::kSlots) + " it can number");
  const auto slot_of = [&](std::size_t k) {
    return k < free ? free_slots_[free - 1 - k] : next_slot_ + static_cast<std::uint32_t>(k - free);
  };
  // Where the moving particles go: the fresh lists while a move is in flight (they catch up and
  // are placed when it lands), else the set, in one call.
  const std::size_t base = fresh_slots_.size();
  std::vector<std::uint32_t> slots;
  std::vector<std::array<double, 3>> at;
  if (in_flight_) {
    fresh_slots_.resize(base + moving);
    fresh_x_.resize(base + moving);
  } else {
    slots.resize(moving);
    at.resize(moving);
  }
  for_each_row(blocks, [&](std::size_t b) {
    const auto [lo, hi] = block_range(b);
    std::size_t k = before[b];
    for (std::size_t i = lo; i < hi; ++i) {
      Particle& p = *ps[i];
      if (!p.alive()) continue;
      p.set_slot(slot_of(k));
      if (in_flight_) {
        fresh_slots_[base + k] = p.slot();
        fresh_x_[base + k] = p.x;
      } else {
        slots[k] = p.slot();
        at[k] = {p.x.x(), p.x.y(), p.x.z()};
      }
      ++k;
    }
  }, parallel);
  free_slots_.resize(free - std::min(free, moving));
  if (moving > free) next_slot_ += static_cast<std::uint32_t>(moving - free);
  if (in_flight_) {
    if (fresh_.size() < next_slot_) fresh_.resize(next_slot_, 0);
    for_each_row(blocks, [&](std::size_t b) {
      const std::size_t lo = base + std::min(moving, b * kBlock), hi = base + std::min(moving, (b + 1) * kBlock);
      for (std::size_t k = lo; k < hi; ++k) fresh_[fresh_slots_[k]] = static_cast<std::uint32_t>(k + 1);
    }, parallel);
  } else {
    resident_->place(slots, at);
  }
}

void StreakBuilder::leave(Particle& p) {
  if (p.slot() == kNoSlot) return;
  if (!in_flight_) {
    const std::uint32_t slot = p.slot();
    resident_->park(std::span<const std::uint32_t>(&slot, 1));
    free_slots_.push_back(p.slot());
  } else {
    // The set is moving: a fresh particle was never placed; an old one is parked on landing. The
    // slot is not handed out again before then.
    if (fresh(p)) {
      fresh_[p.slot()] = 0;
    } else {
      flight_parks_.push_back(p.slot());
    }
    flight_freed_.push_back(p.slot());
  }
  p.set_slot(kNoSlot);
}

bool StreakBuilder::launch(double t_to) {
  if (access_.prepare && !no_error(access_.prepare(t_, t_to))) return false;
  in_flight_ = true;
  flight_to_ = t_to;
  flight_evaluations_ = 0;
  flight_error_ = nullptr;
  flight_ = std::thread([this, t_from = t_, t_to] {
    try {
      flight_evaluations_ = access_.bulk->advance(*resident_, t_from, t_to);
    } catch (...) {
      flight_error_ = std::current_exception();
    }
  });
  return true;
}

void StreakBuilder::start_catch_up() {
  catching_up_ = true;
  catch_up_evaluations_ = 0;
  catch_up_call_seconds_ = 0;
  catch_up_error_ = nullptr;
  catch_x_.swap(fresh_x_);
  fresh_x_.clear();
  const std::size_t n = catch_x_.size();
  if (n == 0) return;
  catch_from_.assign(n, t_);
  catch_status_.assign(n, ParticleStatus::moving);
  ++report_.catch_up_calls;
  report_.catch_up_particles += n;
  // Each moves as it would have in the set (a call of particles with no step size yet: the same
  // bits).
  catch_up_ = std::thread([this, t_to = flight_to_] {
    const auto call = Clock::now();
    try {
      catch_up_evaluations_ = map_.advect_all(catch_x_, catch_from_, t_to, catch_status_);
    } catch (...) {
      catch_up_error_ = std::current_exception();
    }
    catch_up_call_seconds_ = seconds_since(call);
  });
}

bool StreakBuilder::land() {
  const auto t0 = Clock::now();
  if (!catching_up_) start_catch_up();
  if (flight_.joinable()) flight_.join();
  const auto c0 = Clock::now();
  wait_flight();
  in_flight_ = false;
  catching_up_ = false;
  if (flight_error_) std::rethrow_exception(std::exchange(flight_error_, nullptr));
  if (catch_up_error_) std::rethrow_exception(std::exchange(catch_up_error_, nullptr));
  report_.evaluations += flight_evaluations_ + catch_up_evaluations_;
  report_.catch_up_call_seconds += catch_up_call_seconds_;
  double catch_up_seconds = seconds_since(c0);
  const std::size_t nr = rows_.size();
  std::vector<std::array<std::size_t, 2>> stopped(nr, {0, 0});  // [r]: left the domain, no data
  std::vector<std::vector<std::uint32_t>> fresh_at(nr);  // [row]: its fresh particles
  std::size_t moved = take_resident(stopped, &fresh_at);
  if (!flight_parks_.empty()) resident_->park(flight_parks_);
  flight_parks_.clear();

  // The fresh particles still in the rows take their catch-up positions; those still moving go
  // into the set, the slots of those that stopped are free.
  const auto c1 = Clock::now();
  std::size_t n = 0;
  for (const std::vector<std::uint32_t>& f : fresh_at) n += f.size();
  if (n > 0) {
    std::vector<std::size_t> with;  // only the rows with fresh particles
    for (std::size_t r = 0; r < nr; ++r)
      if (!fresh_at[r].empty()) with.push_back(r);
    // Millions after a late break: the rows in parallel, the moving ones written where a count of
    // those before them puts them (no pass in turn over them), into arrays kept from the last.
    const bool parallel = n >= kParallelParticles;
    std::vector<std::size_t> kept(with.size() + 1, 0);  // [w + 1]: moving fresh particles of with[w]
    std::vector<std::vector<std::uint32_t>> freed(with.size());
    for_each_row(with.size(), [&](std::size_t w) {
      const std::size_t r = with[w];
      for (const std::uint32_t i : fresh_at[r]) {
        Particle& p = rows_[r].p[i];
        const std::size_t c = fresh_[p.slot()] - 1;
        p.x = catch_x_[c];
        p.set_status(catch_status_[c]);
        if (p.alive()) {
          ++kept[w + 1];
          continue;
        }
        count_stop(p.status(), stopped[r]);
        freed[w].push_back(p.slot());
        p.set_slot(kNoSlot);
      }
    }, parallel);
    for (std::size_t w = 0; w < with.size(); ++w) kept[w + 1] += kept[w];
    const std::size_t placed = kept.back();
    if (place_slots_.size() < placed) {
      place_slots_.resize(placed);
      place_at_.resize(placed);
    }
    for_each_row(with.size(), [&](std::size_t w) {
      const std::size_t r = with[w];
      std::size_t k = kept[w];
      for (const std::uint32_t i : fresh_at[r]) {
        const Particle& p = rows_[r].p[i];
        if (!p.alive()) continue;
        place_slots_[k] = p.slot();
        place_at_[k++] = {p.x.x(), p.x.y(), p.x.z()};
      }
    }, parallel);
    for (const std::vector<std::uint32_t>& f : freed) free_slots_.insert(free_slots_.end(), f.begin(), f.end());
    resident_->place(std::span(place_slots_.data(), placed), std::span(place_at_.data(), placed));
    moved += n;
  }
  // (A range below one grain runs on this thread.)
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, fresh_slots_.size(), 16384),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t k = range.begin(); k != range.end(); ++k) fresh_[fresh_slots_[k]] = 0;
                    });
  fresh_slots_.clear();
  free_slots_.insert(free_slots_.end(), flight_freed_.begin(), flight_freed_.end());
  flight_freed_.clear();
  catch_up_seconds += seconds_since(c1);
  report_.catch_up_seconds += catch_up_seconds;
  count_interval(moved, flight_to_, stopped);
  report_.advect_seconds += seconds_since(t0);
  return !access_.read_error || no_error(access_.read_error());
}

std::size_t StreakBuilder::first_removable(const std::vector<Particle>& p, std::size_t from) const {
  const std::size_t n = p.size();
  if (n <= 3) return n;  // a row keeps three particles
  const LengthLimit short_limit(o_.merge * o_.edge), long_limit(o_.split * o_.edge);
  std::size_t i = std::max<std::size_t>(from, 1);
  while (i + 1 < n && !removable(p[i - 1], p[i], p[i + 1], short_limit, long_limit)) ++i;
  return i;
}

double StreakBuilder::row_distance(const Row& a, const Row& b, const LengthLimit& stop) const {
  // A merge by s without branches on it (rows drift apart in s, so they would be mispredicted).
  const double beyond = stop.above_squared();
  double d = 0;
  std::size_t i = 0, k = 0;
  const std::size_t na = a.p.size(), nb = b.p.size();
  while (i < na && k < nb) {
    const Particle& pa = a.p[i];
    const Particle& pb = b.p[k];
    const double q = (pa.x - pb.x).squaredNorm();
    const bool pair = pa.s == pb.s && pa.alive() && pb.alive();
    d = pair && q > d ? q : d;
    if (d > beyond) break;
    i += pa.s <= pb.s;
    k += pb.s <= pa.s;
  }
  return std::sqrt(d);  // the largest root is the root of the largest square, bit for bit
}

namespace {

// Catmull-Rom at the middle of p1 and p2 (uniform parameter).
Vec3 cubic_middle(const Vec3& p0, const Vec3& p1, const Vec3& p2, const Vec3& p3) {
  return (-p0 + 9.0 * p1 + 9.0 * p2 - p3) / 16.0;
}

}  // namespace

// Moves particles released at from[i] (x[i] on the seed) to the current time.
bool StreakBuilder::release_and_advect(std::vector<Vec3>& x, const std::vector<double>& from,
                                       std::vector<ParticleStatus>& status) {
  // A streamed sweep moves the field's band and reads earlier steps: not while the set moves on
  // (it lands later; the particles inserted here are fresh and catch up then).
  if (access_.prepare) wait_flight();
  return no_error(advect_from_release(access_, map_, x, from, t_, status, report_.evaluations));
}

bool StreakBuilder::refine_once(std::vector<RowChange>& change, std::vector<double>& gap) {
  const double long_edge = o_.split * o_.edge;
  // Each row's (and each pair of rows') new particles are found independently, in parallel, and
  // gathered in row order: the particles, their ids and the mesh are those of a serial scan.
  std::vector<std::vector<Insert>> along(rows_.size());  // per row, by left particle
  std::vector<std::optional<Row>> across(rows_.size());  // [r]: the new row after row r
  // Row r and the pair (r, r + 1) in one task: row r is still in cache for the pair, and for
  // coarsening's search of a row looked at whole (particles do not move until it runs).
  for_each_row(rows_.size(), [&](std::size_t r) {
    if (change[r].any()) along[r] = inserts_along(r, long_edge, change[r]);
    if (change[r].whole) rows_[r].coarsen_from = first_removable(rows_[r].p, 1);
    if (r + 1 < rows_.size() && (change[r].any() || change[r + 1].any()))
      across[r] = row_between(r, long_edge, gap[r]);
  });
  std::size_t along_count = 0, across_count = 0;
  for (std::size_t r = 0; r < rows_.size(); ++r) {
    along_count += along[r].size();
    across_count += across[r].has_value();
  }
  if (along_count == 0 && across_count == 0) return false;

  // The new particles in order (along each row, then the new rows), gathered row by row in
  // parallel at offsets counted beforehand; ids follow that order.
  const std::size_t nr = rows_.size();
  std::vector<std::size_t> first(2 * nr + 1, 0);  // [r]: along row r; [nr + r]: the row after r
  for (std::size_t r = 0; r < nr; ++r) first[r + 1] = first[r] + along[r].size();
  for (std::size_t r = 0; r < nr; ++r) first[nr + r + 1] = first[nr + r] + (across[r] ? across[r]->p.size() : 0);
  std::vector<Particle*> fresh(first[2 * nr]);
  std::vector<double> from(fresh.size());
  const auto id0 = next_id_;
  for_each_row(nr, [&](std::size_t r) {
    std::size_t k = first[r];
    for (Insert& ins : along[r]) {
      fresh[k] = &ins.particle;
      from[k] = rows_[r].tau;
      ins.particle.id = id0 + static_cast<std::int32_t>(k++);
    }
    if (!across[r]) return;
    k = first[nr + r];
    for (Particle& q : across[r]->p) {
      fresh[k] = &q;
      from[k] = across[r]->tau;
      q.id = id0 + static_cast<std::int32_t>(k++);
    }
  }, fresh.size() >= kParallelParticles);
  next_id_ += static_cast<std::int32_t>(fresh.size());
  // Exact positions: every new particle released at its own (s, τ), moved to t in one batch.
  if (o_.insertion == ParticleInsertion::exact) {
    std::vector<Vec3> x(fresh.size());
    std::vector<ParticleStatus> status(fresh.size());
    for (std::size_t i = 0; i < fresh.size(); ++i) x[i] = seed_point(fresh[i]->s);
    if (!release_and_advect(x, from, status)) return false;
    for (std::size_t i = 0; i < fresh.size(); ++i) {
      fresh[i]->x = x[i];
      fresh[i]->set_status(status[i]);
    }
    report_.exact_insertions += fresh.size();
  } else {
    report_.interpolated_insertions += fresh.size();
  }
  enter(fresh);
  report_.s_insertions += along_count;
  report_.rows_inserted += across_count;
  for (const std::optional<Row>& row : across)
    if (row) report_.row_particles += row->p.size();

  // Insert along rows in place, from the back (each row grows once, in linear time, mostly in the
  // room it has), then the new rows. A new particle goes right after its left neighbour (the
  // closing edge of a closed row: after the last particle); its index is kept for the next pass.
  std::vector<RowChange> next(rows_.size() + across_count);
  std::vector<std::size_t> at(rows_.size());  // row r's index after the new rows
  for (std::size_t r = 0, k = 0; r < rows_.size(); ++r) {
    at[r] = k;
    k += across[r] ? 2 : 1;
  }
  for_each_row(rows_.size(), [&](std::size_t r) {
    const std::vector<Insert>& ins = along[r];
    RowChange& c = next[at[r]];
    c.whole = false;
    if (ins.empty()) return;
    std::vector<Particle>& p = rows_[r].p;
    const std::size_t old = p.size();
    // Particles before the first new one keep their neighbours (a row of three may lose one
    // only once it grows): `ins` is by increasing `after`, one each, and no particle moves
    // between refinement and coarsening.
    std::size_t& coarsen_from = rows_[r].coarsen_from;
    coarsen_from =
        old <= 3 ? 1 : std::max<std::size_t>(1, std::min(coarsen_from, ins.front().after));
    if (p.capacity() < old + ins.size()) {
      // Merged into the new array as it is copied, instead of copied and then moved up.
      std::vector<Particle> grown;
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
    std::vector<Row> rows;
    rows.reserve(rows_.size() + across_count);
    for (std::size_t r = 0; r < rows_.size(); ++r) {
      rows.push_back(std::move(rows_[r]));
      if (across[r]) rows.push_back(std::move(*across[r]));  // next[]: whole, as made
    }
    rows_.swap(rows);
  }
  // Distances: a new row has none measured; rows that only got particles grow theirs by those.
  std::vector<double> next_gap(rows_.size(), kUnmeasured);
  for_each_row(gap.size(), [&](std::size_t r) {
    if (across[r] || r + 1 >= gap.size() || gap[r] == kUnmeasured) return;
    const std::size_t a = at[r];
    next_gap[a] = grown_gap(a, gap[r], next[a], next[a + 1]);
  }, along_count >= kParallelParticles / 16);  // a search in a row for each
  change.swap(next);
  gap.swap(next_gap);
  return true;
}

double StreakBuilder::grown_gap(std::size_t r, double gap, const RowChange& a, const RowChange& b) const {
  if (a.added.empty() && b.added.empty()) return gap;
  // The largest square over the pairs the added particles make with the other row: the root of
  // the larger of it and gap² is row_distance's, bit for bit.
  double d = 0;
  const auto pairs = [&](const Row& with_added, const std::vector<std::uint32_t>& added, const Row& other) {
    const std::vector<Particle>& o = other.p;
    for (const std::uint32_t i : added) {
      const Particle& q = with_added.p[i];
      if (!q.alive()) continue;
      const auto it = std::lower_bound(o.begin(), o.end(), q.s, [](const Particle& x, double s) { return x.s < s; });
      if (it != o.end() && it->s == q.s && it->alive()) d = std::max(d, (q.x - it->x).squaredNorm());
    }
  };
  pairs(rows_[r], a.added, rows_[r + 1]);
  pairs(rows_[r + 1], b.added, rows_[r]);
  return std::max(gap, std::sqrt(d));
}

// The particles to insert on row r's edges longer than `long_edge`, by left particle.
std::vector<StreakBuilder::Insert> StreakBuilder::inserts_along(std::size_t r, double long_edge,
                                                                const RowChange& change) const {
  std::vector<Insert> along;
  const LengthLimit long_limit(long_edge);
  const bool closed = seed_.closed();
  const std::vector<Particle>& p = rows_[r].p;
  const std::size_t n = p.size();
  const std::size_t edges = closed ? n : n - 1;
  const auto edge = [&](std::size_t i) {  // i: the edge's left particle
    const Particle& a = p[i];
    const Particle& b = p[(i + 1) % n];
    if (!a.alive() || !b.alive()) return;
    const double sb = (i + 1 == n) ? b.s + 1.0 : b.s;
    if (sb - a.s <= min_ds_ || long_limit.not_longer(a.x - b.x)) return;
    Particle q;
    q.s = 0.5 * (a.s + sb);  // < 1: a closed row starts at s = 0, which is never removed
    if (o_.insertion == ParticleInsertion::interpolate) {
      const auto at = [&](std::ptrdiff_t j) -> const Particle* {
        const auto m = static_cast<std::ptrdiff_t>(n);
        if (closed) j = ((j % m) + m) % m;
        if (j < 0 || j >= m || !p[static_cast<std::size_t>(j)].alive()) return nullptr;
        return &p[static_cast<std::size_t>(j)];
      };
      const auto ii = static_cast<std::ptrdiff_t>(i);
      const Particle* p0 = at(ii - 1);
      const Particle* p3 = at(ii + 2);
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

// The row to insert between rows r and r + 1 when they are more than `long_edge` apart.
std::optional<Row> StreakBuilder::row_between(std::size_t r, double long_edge, double& gap) const {
  const Row& a = rows_[r];
  const Row& b = rows_[r + 1];
  if (b.tau - a.tau <= min_dtau_) return std::nullopt;
  // (Beyond long_edge the measure stops: the pair is split, and its distance dropped.)
  if (gap == kUnmeasured) gap = row_distance(a, b, LengthLimit(long_edge));
  if (gap <= long_edge) return std::nullopt;
  Row row;
  row.tau = 0.5 * (a.tau + b.tau);
  row.p.reserve(std::max(a.p.size(), b.p.size()));
  // The rows around, for cubic interpolation: the s asked for only grows along the walk, so a
  // cursor into each finds what a binary search would, without a search per particle (the rows
  // a stretching surface inserts hold thousands).
  const std::vector<Particle>* before = r >= 1 ? &rows_[r - 1].p : nullptr;
  const std::vector<Particle>* after = r + 2 < rows_.size() ? &rows_[r + 2].p : nullptr;
  std::size_t at_before = 0, at_after = 0;
  const auto find = [](const std::vector<Particle>* ps, std::size_t& at, double s) -> const Particle* {
    if (!ps) return nullptr;
    while (at < ps->size() && (*ps)[at].s < s) ++at;
    return at < ps->size() && (*ps)[at].s == s && (*ps)[at].alive() ? &(*ps)[at] : nullptr;
  };
  std::size_t i = 0, k = 0;
  while (i < a.p.size() || k < b.p.size()) {
    const bool take_a = k == b.p.size() || (i < a.p.size() && a.p[i].s <= b.p[k].s);
    const bool take_b = i == a.p.size() || (k < b.p.size() && b.p[k].s <= a.p[i].s);
    const bool common = take_a && take_b;
    Particle q;
    q.s = take_a ? a.p[i].s : b.p[k].s;
    if (o_.insertion == ParticleInsertion::exact) {
      row.p.push_back(q);
    } else if (common) {
      // Cubic across rows where the rows around carry this s too, linear otherwise.
      const Particle& pa = a.p[i];
      const Particle& pb = b.p[k];
      if (pa.alive() && pb.alive()) {
        const Particle* p0 = find(before, at_before, q.s);
        const Particle* p3 = find(after, at_after, q.s);
        q.x = (p0 && p3) ? cubic_middle(p0->x, pa.x, pb.x, p3->x) : 0.5 * (pa.x + pb.x);
      } else {
        q.set_status(ParticleStatus::left_domain);
      }
      row.p.push_back(q);
    }
    if (take_a) ++i;
    if (take_b) ++k;
  }
  return row;
}

void StreakBuilder::coarsen(std::vector<double>& gap) {
  const double short_edge = o_.merge * o_.edge;
  const double long_edge = o_.split * o_.edge;
  const LengthLimit short_limit(short_edge), long_limit(long_edge);
  // Along rows: a particle whose two edges are short goes (never a row's ends, and a row keeps
  // three particles), unless its neighbours would then be too far apart. Rows in parallel.
  std::vector<std::size_t> removed(rows_.size(), 0);
  std::vector<std::vector<Particle>> gone(resident_ ? rows_.size() : 0);  // their slots go back
  for_each_row(rows_.size(), [&](std::size_t r) {
    std::vector<Particle>& p = rows_[r].p;
    // Most rows lose nothing: find the first particle that goes before moving any (refinement's
    // first pass has mostly found it). The kept particles close up in place: p[0, w) are kept,
    // and p[i + 1] is not moved yet.
    const std::size_t n = p.size();
    const std::size_t first = first_removable(p, std::exchange(rows_[r].coarsen_from, 1));
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
  for (std::size_t r = 0; r < rows_.size(); ++r) {
    if (removed[r] == 0) continue;
    report_.s_removals += removed[r];
    gap[r] = kUnmeasured;
    if (r > 0) gap[r - 1] = kUnmeasured;
  }
  for (std::vector<Particle>& row : gone)
    for (Particle& p : row) leave(p);
  // Across rows: a row between two close ones goes (never the oldest or the newest). Which row
  // goes depends on the rows kept before it, so the walk is serial; the distances between
  // neighbouring rows, which it mostly asks, are measured beforehand in parallel.
  if (rows_.size() > 2) {
    std::vector<double> next_distance(rows_.size() - 1);  // [r]: rows r and r + 1
    for_each_row(next_distance.size(), [&](std::size_t r) {
      next_distance[r] = gap[r] != kUnmeasured ? gap[r] : row_distance(rows_[r], rows_[r + 1], short_limit);
    });
    std::vector<Row> kept;
    kept.reserve(rows_.size());
    kept.push_back(std::move(rows_[0]));
    bool previous_kept = true;  // kept.back() is rows_[r - 1]
    for (std::size_t r = 1; r + 1 < rows_.size(); ++r) {
      const Row& a = kept.back();
      const Row& m = rows_[r];
      const Row& b = rows_[r + 1];
      const double am = previous_kept ? next_distance[r - 1] : row_distance(a, m, short_limit);
      if (am < short_edge && next_distance[r] < short_edge && row_distance(a, b, long_limit) < long_edge) {
        ++report_.rows_removed;
        for (Particle& p : rows_[r].p) leave(p);
        previous_kept = false;
        continue;
      }
      kept.push_back(std::move(rows_[r]));
      previous_kept = true;
    }
    kept.push_back(std::move(rows_.back()));
    rows_.swap(kept);
  }
  // Rows whose particles have all stopped carry nothing any more.
  std::erase_if(rows_, [](const Row& r) {
    return std::none_of(r.p.begin(), r.p.end(), [](const Particle& p) { return p.alive(); });
  });
}

void StreakBuilder::adapt() {
  if (!o_.adaptive) return;
  const auto t0 = Clock::now();
  std::vector<RowChange> change(rows_.size());  // the first pass looks at every row
  std::vector<double> gap(rows_.size(), kUnmeasured);
  for (int round = 0; round < o_.max_refinement_rounds; ++round) {
    if (!refine_once(change, gap)) break;
    if (particle_count() > o_.max_vertices) break;
  }
  if (in_flight_) start_catch_up();  // the inserted particles move on beside coarsening
  const auto c0 = Clock::now();
  coarsen(gap);
  report_.coarsen_seconds += seconds_since(c0);
  report_.refine_seconds += seconds_since(t0);
}

void StreakBuilder::join_finisher() {
  if (!finisher_.joinable()) return;
  finisher_.join();
  collect_frame();
}

void StreakBuilder::collect_frame() {
  if (finisher_error_) std::rethrow_exception(std::exchange(finisher_error_, nullptr));
  report_.frame_finish_seconds += finishing_seconds_;
  report_.frames.push_back(finishing_record_);
  spare_mesh_ = std::move(finishing_.mesh);
}

void StreakBuilder::emit(int index) {
  const auto t0 = Clock::now();
  join_finisher();  // its mesh becomes this frame's
  const auto t_build = Clock::now();
  StreakFrame frame;
  frame.index = index;
  frame.time = t_;
  frame.rows = rows_.size();
  frame.mesh = std::move(spare_mesh_);
  Mesh& mesh = frame.mesh;
  // Vertices: the live particles, row after row; faces: the strips between neighbouring rows, in
  // row order. Both are counted first (a row's live particles numbered from 0, and the faces of
  // the strips, which need only which particles live), so that every array is sized at once,
  // side by side, and the rows and strips then fill them in parallel at offsets counted before.
  const std::size_t nr = rows_.size();
  const std::size_t strips = nr > 0 ? nr - 1 : 0;
  // [r][i]: particle i's vertex, -1 where it stopped (its number within the row until the vertex
  // pass below adds the row's first vertex).
  std::vector<std::vector<std::int32_t>> vertex(nr);
  std::vector<std::size_t> first(nr + 1, 0);
  for_each_row(nr, [&](std::size_t r) {
    const std::vector<Particle>& p = rows_[r].p;
    vertex[r].resize(p.size());
    std::int32_t v = 0;
    for (std::size_t i = 0; i < p.size(); ++i) vertex[r][i] = p[i].alive() ? v++ : -1;
    first[r + 1] = static_cast<std::size_t>(v);
  });
  std::vector<std::size_t> first_face(strips + 1, 0);
  for_each_row(strips, [&](std::size_t r) {
    std::size_t n = 0;
    for_each_strip_face(r, vertex[r], vertex[r + 1], [&n](const Face&) { ++n; });
    first_face[r + 1] = n;
  });
  std::size_t dead = 0;
  for (std::size_t r = 0; r < nr; ++r) {
    dead += rows_[r].p.size() - first[r + 1];
    first[r + 1] += first[r];
  }
  for (std::size_t r = 0; r < strips; ++r) first_face[r + 1] += first_face[r];
  const std::size_t nv = first[nr];
  // Side by side: an array that must grow is zero-filled anew (see grow()), one thread each.
  tbb::parallel_invoke([&] { grow(mesh.positions, nv); }, [&] { grow(mesh.s, nv); },
                       [&] { grow(mesh.release_time, nv); }, [&] { grow(mesh.age, nv); },
                       [&] { grow(mesh.speed, nv); }, [&] { grow(mesh.particle_id, nv); },
                       [&] { grow(mesh.faces, first_face.back()); });
  for_each_row(nr, [&](std::size_t r) {
    const Row& row = rows_[r];
    const auto offset = static_cast<std::int32_t>(first[r]);
    for (std::size_t i = 0; i < row.p.size(); ++i) {
      const Particle& p = row.p[i];
      if (!p.alive()) continue;
      const auto v = static_cast<std::size_t>(vertex[r][i] += offset);
      mesh.positions[v] = p.x;
      mesh.s[v] = p.s;
      mesh.release_time[v] = row.tau;
      mesh.age[v] = t_ - row.tau;
      Vec3 u = Vec3::Zero();
      if (flow_.velocity(p.x, t_, u) != FieldStatus::inside) u.setZero();
      if (flow_.dimension() == 2) u.z() = 0;
      mesh.speed[v] = u.norm();
      mesh.particle_id[v] = p.id;
    }
  });
  for_each_row(strips, [&](std::size_t r) {
    Face* out = mesh.faces.data() + first_face[r];
    for_each_strip_face(r, vertex[r], vertex[r + 1], [&out](const Face& f) { *out++ = f; });
  });
  StreakFrameRecord rec;
  rec.index = index;
  rec.time = t_;
  rec.vertices = mesh.vertex_count();
  rec.faces = mesh.face_count();
  rec.rows = rows_.size();
  rec.dead_particles = dead;
  rec.build_seconds = seconds_since(t_build);
  const double built = seconds_since(t0);
  report_.frame_seconds += built;
  // The rest needs the mesh only: it runs while the particles move on (its parallel loops share
  // the threads with theirs).
  finishing_ = std::move(frame);
  finishing_record_ = rec;
  if (o_.finish_frames_aside) {
    finisher_ = std::thread([this, built] { finish_frame(built); });
  } else {
    finish_frame(built);
    report_.frame_seconds += finishing_seconds_;
    collect_frame();
  }
}

void StreakBuilder::finish_frame(double built) {
  const auto t1 = Clock::now();
  try {
    finishing_.quality = measure_quality(finishing_.mesh);
    finishing_record_.quality = finishing_.quality;
    finishing_record_.max_edge = finishing_.quality.longest_edge;
    if (sink_) sink_(finishing_);
  } catch (...) {
    finisher_error_ = std::current_exception();
    frame_failed_ = true;
  }
  finishing_seconds_ = seconds_since(t1);
  finishing_record_.finish_seconds = finishing_seconds_;
  finishing_record_.seconds = built + finishing_seconds_;
}

// The faces between rows r and r + 1 (`va`, `vb`: their particles' vertices, -1 for stopped
// ones): walk both rows in s; a shared s closes a quad, otherwise the row whose next s comes
// first gives a triangle. Faces with a stopped particle are left out.
template <class F>
void StreakBuilder::for_each_strip_face(std::size_t r, const std::vector<std::int32_t>& va,
                                        const std::vector<std::int32_t>& vb, const F& face) const {
  const bool closed = seed_.closed();
  const auto& A = rows_[r].p;
  const auto& B = rows_[r + 1].p;
  const std::size_t na = A.size(), nb = B.size();
  const std::size_t ea = closed ? na : na - 1, eb = closed ? nb : nb - 1;
  const auto sa = [&](std::size_t i) { return i >= na ? A[i - na].s + 1.0 : A[i].s; };
  const auto sb = [&](std::size_t k) { return k >= nb ? B[k - nb].s + 1.0 : B[k].s; };
  std::size_t i = 0, k = 0;
  while (i < ea || k < eb) {
    const std::int32_t a0 = va[i % na], b0 = vb[k % nb];
    const bool step_a = i < ea && (k == eb || sa(i + 1) <= sb(k + 1));
    const bool step_b = k < eb && (i == ea || sb(k + 1) <= sa(i + 1));
    if (step_a && step_b) {
      const std::int32_t a1 = va[(i + 1) % na], b1 = vb[(k + 1) % nb];
      if (a0 >= 0 && a1 >= 0 && b1 >= 0 && b0 >= 0) face(Face{{a0, a1, b1, b0}, 4});
      ++i, ++k;
    } else if (step_a) {
      const std::int32_t a1 = va[(i + 1) % na];
      if (a0 >= 0 && a1 >= 0 && b0 >= 0) face(Face{{a0, a1, b0, -1}, 3});
      ++i;
    } else {
      const std::int32_t b1 = vb[(k + 1) % nb];
      if (a0 >= 0 && b1 >= 0 && b0 >= 0) face(Face{{a0, b1, b0, -1}, 3});
      ++k;
    }
  }
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
  const double median = seed_speed_median(seed_params_);
  const double span = o_.release_end - o_.release_begin;
  double step = o_.release_step > 0 ? o_.release_step : (median > 0 ? o_.edge / median : span / 100);
  const double rows = std::clamp(std::round(span / step), 1.0, 1e7);
  step = span / rows;
  report_.release_step = step;
  min_ds_ = 1e-12;
  min_dtau_ = step * 1e-9;

  // Break points: releases, observations, and (streamed) the series' steps.
  // Observation times inside the release interval release a row too: the surface then reaches
  // the seed curve in every frame.
  std::vector<double> releases;
  for (double j = 0; j <= rows; ++j) releases.push_back(j == rows ? o_.release_end : o_.release_begin + step * j);
  for (const double f : o_.frames)
    if (f < o_.release_end) releases.push_back(f);
  std::sort(releases.begin(), releases.end());
  releases.erase(std::unique(releases.begin(), releases.end()), releases.end());
  const double t_last = o_.frames.back();
  // Every k-th release stops the particles (and the last; the frames and steps below do too);
  // the rows released between go from their release times to the next stop in one call.
  std::vector<double> breaks;
  const auto per_break = static_cast<std::size_t>(o_.releases_per_break);
  for (std::size_t j = 0; j < releases.size(); ++j)
    if (j % per_break == 0 || j + 1 == releases.size()) breaks.push_back(releases[j]);
  breaks.insert(breaks.end(), o_.frames.begin(), o_.frames.end());
  for (const double t : access_.step_times)
    if (t > o_.release_begin && t < t_last) breaks.push_back(t);
  std::erase_if(breaks, [&](double t) { return t > t_last; });
  std::sort(breaks.begin(), breaks.end());
  breaks.erase(std::unique(breaks.begin(), breaks.end()), breaks.end());

  t_ = o_.release_begin;
  std::size_t next_release = 0, next_frame = 0;
  // The releases not made yet before time t (taken: they are made by the caller).
  const auto releases_before = [&](double t) {
    std::vector<double> taus;
    while (next_release < releases.size() && releases[next_release] < t)
      taus.push_back(releases[next_release++]);
    return taus;
  };
  const auto stop = [&](const std::string& why) {
    report_.complete = false;
    report_.message = why;
  };
  // With overlap, the particles move on to the next break while this one is refined (a row
  // released here goes with them: it needs no catch-up).
  const bool overlap = resident_ && o_.overlap_advection;
  for (std::size_t i = 0; i < breaks.size(); ++i) {
    const double b = breaks[i];
    if (in_flight_) {
      if (!land()) break;
    } else if (b > t_) {
      if (!advance(b)) break;
    }
    if (!take_released()) break;
    const std::vector<double> before = releases_before(b);  // since the last stop (in turn)
    if (!before.empty() && !release_before(before)) break;
    if (next_release < releases.size() && releases[next_release] == b) {
      release(b);
      ++next_release;
    }
    if (overlap && i + 1 < breaks.size() && !launch(breaks[i + 1])) break;
    adapt();
    if (!report_.complete) break;  // a read error while inserting
    if (in_flight_) {
      // The rows released before the move lands go there beside it (their s are the newest
      // row's now: nothing changes them before it lands).
      const std::vector<double> ahead = releases_before(flight_to_);
      if (!ahead.empty()) start_release(ahead);
    }
    report_.max_particles = std::max(report_.max_particles, particle_count());
    if (particle_count() > o_.max_vertices) {
      stop("stopped at t = " + number(t_) + ": " + std::to_string(particle_count()) +
           " particles exceed the cap of " + std::to_string(o_.max_vertices));
      break;
    }
    if (next_frame < o_.frames.size() && o_.frames[next_frame] == b) {
      emit(static_cast<int>(next_frame));
      ++next_frame;
    }
    if (frame_failed_) join_finisher();  // the sink threw: stop here
    if (o_.progress) {
      StreakProgress p;
      p.t = t_;
      p.t_end = t_last;
      p.frames_written = next_frame;
      p.frames = o_.frames.size();
      p.particles = particle_count();
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
  wait_flight();  // a run stopped early: that move's positions are not taken
  if (release_thread_.joinable()) release_thread_.join();  // nor the rows released before it
  const auto t_join = Clock::now();
  join_finisher();
  report_.frame_seconds += seconds_since(t_join);
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
