#pragma once
/// The moving particles of a streak surface's rows, kept with the bulk advection backend from
/// interval to interval (device memory for CUDA): only particles placed anew go up, positions and
/// statuses come down. Each moving particle holds a slot of the set; slots given back are handed
/// out again, last first, before new ones.
///
/// The set can move on to the next break as a task (launch) while the rows are refined at the
/// current one. Particles entering meanwhile are fresh: they are moved to the move's end in one
/// catch-up call of their own (start_catch_up, another task, beside coarsening and the frame),
/// and placed in the set when it lands. Each moves as it would have in the set, so the frames are
/// those of moves in turn, bit for bit.
#include <array>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <memory>
#include <vector>

#include "orthofront/advect/resident_particles.h"
#include "orthofront/spacetime/aside_task.h"
#include "orthofront/spacetime/bulk_flow_map.h"
#include "orthofront/spacetime/streak_rows.h"

namespace orthofront::spacetime {

class StreakResidentSet {
 public:
  /// Per row: particles that stopped during a move, [0] left the domain, [1] no data.
  using Stops = std::vector<std::array<std::size_t, 2>>;
  struct Counts {
    std::size_t evaluations = 0;     ///< of the moves and catch-ups
    std::size_t catch_up_calls = 0, catch_up_particles = 0;
    double take_seconds = 0;         ///< taking the set's positions into the rows
    double catch_up_seconds = 0;     ///< landing: waiting for the catch-up and placing its particles
    double catch_up_call_seconds = 0;  ///< the catch-up calls on their task
  };

  /// Non-owning: `bulk` must outlive the set.
  explicit StreakResidentSet(const BulkFlowMap& bulk);
  /// Waits for a move and a catch-up in flight (their positions are not taken).
  ~StreakResidentSet() = default;
  StreakResidentSet(const StreakResidentSet&) = delete;
  StreakResidentSet& operator=(const StreakResidentSet&) = delete;

  /// The moving ones of `ps` take slots, in order (while in flight they are fresh; they must
  /// enter before the catch-up starts). Throws Error when the slots would run out.
  void enter(const std::vector<StreakParticle*>& ps);
  /// A particle leaving the rows gives its slot back (none: nothing to do). While in flight the
  /// slot is handed out again only once the move lands.
  void leave(StreakParticle& p);

  /// Moves the set from t_from to t_to, in turn, and takes its positions and statuses into
  /// `rows`; returns how many particles moved. stopped[r] counts row r's particles that stopped.
  std::size_t advance(std::vector<StreakRow>& rows, double t_from, double t_to, Stops& stopped);

  /// Sends the set on from t_from to t_to as a task.
  void launch(double t_from, double t_to);
  bool in_flight() const { return in_flight_; }
  /// The time the move in flight (or the last) goes to.
  double flight_to() const { return flight_to_; }
  /// Moves the fresh particles to the move's end as a task of its own; no particle enters after.
  void start_catch_up();
  /// Waits for the move and the catch-up (starting it if not started), rethrows what they threw,
  /// takes the positions into `rows`, places the fresh particles still moving and frees the slots
  /// given back meanwhile. Returns how many particles moved (fresh ones included).
  std::size_t land(std::vector<StreakRow>& rows, Stops& stopped);
  /// Waits for the move and the catch-up; their positions are taken, and what they threw is
  /// rethrown, by land() (a run that stops before then drops both). Inserting exact particles
  /// through a streamed field moves its band: not while the set moves through it.
  void wait_flight();

  const Counts& counts() const { return counts_; }

 private:
  bool fresh(const StreakParticle& p) const { return p.slot() < fresh_.size() && fresh_[p.slot()] != 0; }
  // Takes the set's positions and statuses into the rows. Particles entered while a move was in
  // flight are left as they are; with `fresh_at`, their indices go to (*fresh_at)[row].
  std::size_t take(std::vector<StreakRow>& rows, Stops& stopped,
                   std::vector<std::vector<std::uint32_t>>* fresh_at = nullptr);

  const BulkFlowMap& bulk_;
  std::unique_ptr<advect::ResidentParticles> set_;
  Counts counts_;
  std::vector<std::uint32_t> free_slots_;  // given back, taken last first
  std::uint32_t next_slot_ = 0;            // never handed out yet from here on
  bool in_flight_ = false;
  double flight_from_ = 0, flight_to_ = 0;
  std::size_t flight_evaluations_ = 0;
  std::exception_ptr flight_error_;
  std::vector<std::uint32_t> fresh_;         // [slot]: 1 + its index in fresh_slots_, 0: not fresh
  std::vector<std::uint32_t> fresh_slots_;   // slots entered while a move was in flight
  std::vector<Vec3> fresh_x_;                // their positions then
  bool catching_up_ = false;                 // start_catch_up() ran for this move
  std::vector<Vec3> catch_x_;                // the catch-up call's particles, as fresh_slots_
  std::vector<double> catch_from_;
  std::vector<ParticleStatus> catch_status_;
  std::size_t catch_up_evaluations_ = 0;
  double catch_up_call_seconds_ = 0;
  std::exception_ptr catch_up_error_;
  std::vector<std::uint32_t> place_slots_;   // land(): the fresh particles still moving, to place
  std::vector<std::array<double, 3>> place_at_;
  std::vector<std::uint32_t> flight_parks_;  // left while in flight: parked when it lands
  std::vector<std::uint32_t> flight_freed_;  // given back while in flight: free once it lands
  // Last: destroyed first, so tasks in flight are waited for while what they use is still there.
  AsideTask flight_, catch_up_;
};

}  // namespace orthofront::spacetime
