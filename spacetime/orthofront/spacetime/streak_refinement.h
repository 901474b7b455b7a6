#pragma once
/// Refinement and coarsening of a streak surface's rows, once per break of the particles.
/// Refinement inserts a particle on every edge of a row longer than split·ℓ (at its s
/// midpoint) and a row between every two rows more than split·ℓ apart (at their τ midpoint, with
/// the s of both), pass after pass until none is long; coarsening then removes a particle whose
/// two edges are both below merge·ℓ and a row between two close rows, where that leaves no long
/// edge. Each pass looks only at what changed since the pass before: an edge or a row distance
/// found short stays short while its particles stay where they are.
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "orthofront/spacetime/streak_rows.h"
#include "orthofront/spacetime/streak_surface.h"

namespace orthofront::spacetime {

class StreakRefinement {
 public:
  struct Limits {
    double edge = 0.05;      ///< ℓ
    double split = 1.5;      ///< edges and row distances above split·ℓ are split
    double merge = 0.5;      ///< particles and rows with both sides below merge·ℓ may go
    ParticleInsertion insertion = ParticleInsertion::exact;
    bool closed = false;     ///< rows of a closed seed curve: the last particle joins the first
    double min_ds = 1e-12;   ///< edges no longer than this in s are never split
    double min_dtau = 0;     ///< rows no farther apart than this in τ are never split
  };

  /// What the rows' owner does for refinement: places exact particles, and keeps the resident
  /// set (if any) told of the moving particles that come and go.
  class Owner {
   public:
    /// Exact insertion: the particles `fresh` (their s set) released at from[i] get their
    /// position and status at the current time. false: a read error, which stops the run (the
    /// particles are dropped, their ids spent).
    virtual bool place_exact(std::span<StreakParticle* const> fresh, std::span<const double> from) = 0;
    /// New particles, placed; they enter the rows (pointers hold until the rows change again).
    virtual void enter(const std::vector<StreakParticle*>& fresh) = 0;
    /// A particle about to be removed from the rows.
    virtual void leave(StreakParticle& p) = 0;

   protected:
    ~Owner() = default;
  };

  struct Counts {
    std::size_t s_insertions = 0;                       ///< particles inserted along rows
    std::size_t rows_inserted = 0, row_particles = 0;   ///< rows inserted, their particles
    std::size_t exact_insertions = 0, interpolated_insertions = 0;
    std::size_t s_removals = 0, rows_removed = 0;
  };

  explicit StreakRefinement(const Limits& limits) : limits_(limits) {}

  /// A new break: the first pass looks at every row whole, and knows no distance.
  void begin(const std::vector<StreakRow>& rows);
  /// One pass of splits over what changed since the last pass; new particles get ids from
  /// next_id on, in row order (along each row, then the new rows). Returns whether it inserted
  /// anything (false also where placing failed).
  bool refine_once(std::vector<StreakRow>& rows, std::int32_t& next_id, Owner& owner);
  /// Removes particles along rows (never a row's ends; a row keeps three), then rows (never the
  /// oldest or newest), then rows whose particles have all stopped.
  void coarsen(std::vector<StreakRow>& rows, Owner& owner);

  const Counts& counts() const { return counts_; }

 private:
  // A particle to insert on a row, after its particle `after`.
  struct Insert {
    std::size_t after;
    StreakParticle particle;
  };
  // What changed in a row since the last pass looked at it: all of it (a new row, or the first
  // pass), or the particles at `added` (indices, increasing).
  struct RowChange {
    bool whole = true;
    std::vector<std::uint32_t> added;
    bool any() const { return whole || !added.empty(); }
  };
  // The particles to insert on row r's edges longer than `long_edge`: all edges, or those beside
  // the particles `added`.
  std::vector<Insert> inserts_along(const std::vector<StreakRow>& rows, std::size_t r, double long_edge,
                                    const RowChange& change) const;
  // The row to insert between rows r and r + 1 when they are more than `long_edge` apart;
  // measures their distance into `gap` when it is not known (where they are that far apart, a
  // distance beyond long_edge, not necessarily the largest).
  std::optional<StreakRow> row_between(const std::vector<StreakRow>& rows, std::size_t r, double long_edge,
                                       double& gap) const;
  // The distance of rows r and r + 1 after particles were added to them (`gap`: before).
  double grown_gap(const std::vector<StreakRow>& rows, std::size_t r, double gap, const RowChange& a,
                   const RowChange& b) const;
  // The first particle of p (a row) that coarsening removes, looking from index `from` (>= 1)
  // on; p.size() - 1 or more where none does.
  std::size_t first_removable(const std::vector<StreakParticle>& p, std::size_t from) const;

  Limits limits_;
  Counts counts_;
  std::vector<RowChange> change_;  // [r]: since the last pass
  // [r]: the distance of rows r and r + 1 where known (kUnmeasured otherwise), kept up to date
  // as rows change and reused by coarsen().
  std::vector<double> gap_;
};

}  // namespace orthofront::spacetime
