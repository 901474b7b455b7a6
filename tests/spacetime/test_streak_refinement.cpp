// StreakRefinement: splits of long edges and row distances, and coarsening of short ones, on
// rows laid out in the plane of their labels (a particle at (s, τ) sits at x = (s, τ, 0)), where
// the result is known exactly.
#include <catch2/catch.hpp>

#include <set>
#include <vector>

#include "orthofront/spacetime/streak_refinement.h"

using namespace orthofront;
using namespace orthofront::spacetime;

namespace {

StreakRow row(double tau, const std::vector<double>& s) {
  StreakRow r;
  r.tau = tau;
  for (const double v : s) {
    StreakParticle p;
    p.s = v;
    p.x = Vec3(v, tau, 0);
    r.p.push_back(p);
  }
  return r;
}

// Places exact particles where their label puts them (the flow map of a flow at rest, with the
// seed along x and release times along y); records what enters and leaves.
struct LabelPlane final : StreakRefinement::Owner {
  std::vector<std::size_t> entered;  // per call
  std::size_t left = 0;
  bool fail = false;
  bool place_exact(std::span<StreakParticle* const> fresh, std::span<const double> from) override {
    if (fail) return false;
    for (std::size_t i = 0; i < fresh.size(); ++i) fresh[i]->x = Vec3(fresh[i]->s, from[i], 0);
    return true;
  }
  void enter(const std::vector<StreakParticle*>& fresh) override { entered.push_back(fresh.size()); }
  void leave(StreakParticle&) override { ++left; }
};

StreakRefinement::Limits limits(ParticleInsertion insertion) {
  StreakRefinement::Limits l;
  l.edge = 0.3;  // splits above 0.45, merges below 0.15
  l.split = 1.5;
  l.merge = 0.5;
  l.insertion = insertion;
  l.min_dtau = 1e-9;
  return l;
}

}  // namespace

TEST_CASE("streak refinement: a long edge is halved pass after pass, ids in order",
          "[spacetime][streak]") {
  StreakRefinement refinement(limits(ParticleInsertion::interpolate));
  std::vector<StreakRow> rows{row(0, {0, 1})};
  rows[0].p[0].id = 0;
  rows[0].p[1].id = 1;
  std::int32_t next_id = 2;
  LabelPlane owner;
  refinement.begin(rows);
  CHECK(refinement.refine_once(rows, next_id, owner));   // s = 0.5
  CHECK(refinement.refine_once(rows, next_id, owner));   // s = 0.25, 0.75
  CHECK_FALSE(refinement.refine_once(rows, next_id, owner));
  REQUIRE(rows.size() == 1);
  REQUIRE(rows[0].p.size() == 5);
  const std::vector<double> s{0, 0.25, 0.5, 0.75, 1};
  const std::vector<std::int32_t> ids{0, 3, 2, 4, 1};
  for (std::size_t i = 0; i < 5; ++i) {
    CHECK(rows[0].p[i].s == s[i]);
    CHECK(rows[0].p[i].x == Vec3(s[i], 0, 0));  // midpoints of collinear particles
    CHECK(rows[0].p[i].id == ids[i]);
  }
  CHECK(next_id == 5);
  CHECK(owner.entered == std::vector<std::size_t>{1, 2});
  CHECK(refinement.counts().s_insertions == 3);
  CHECK(refinement.counts().interpolated_insertions == 3);
  CHECK(refinement.counts().exact_insertions == 0);
}

TEST_CASE("streak refinement: rows far apart get rows between them, down to a grid of spacing "
          "within split·ℓ, every particle placed at its label",
          "[spacetime][streak]") {
  StreakRefinement refinement(limits(ParticleInsertion::exact));
  std::vector<StreakRow> rows{row(0, {0, 1}), row(1, {0, 1})};
  for (std::int32_t k = 0; k < 4; ++k) rows[static_cast<std::size_t>(k / 2)].p[static_cast<std::size_t>(k % 2)].id = k;
  std::int32_t next_id = 4;
  LabelPlane owner;
  refinement.begin(rows);
  int passes = 0;
  while (refinement.refine_once(rows, next_id, owner)) ++passes;
  CHECK(passes == 3);
  const std::vector<double> grid{0, 0.25, 0.5, 0.75, 1};
  REQUIRE(rows.size() == 5);
  std::set<std::int32_t> ids;
  for (std::size_t r = 0; r < 5; ++r) {
    INFO("row " << r);
    CHECK(rows[r].tau == grid[r]);
    REQUIRE(rows[r].p.size() == 5);
    for (std::size_t i = 0; i < 5; ++i) {
      CHECK(rows[r].p[i].s == grid[i]);
      CHECK(rows[r].p[i].x == Vec3(grid[i], grid[r], 0));
      ids.insert(rows[r].p[i].id);
    }
  }
  CHECK(ids.size() == 25);  // each id once
  CHECK(next_id == 25);
  const StreakRefinement::Counts& c = refinement.counts();
  CHECK(c.rows_inserted == 3);
  CHECK(c.s_insertions + c.row_particles == 21);
  CHECK(c.exact_insertions == 21);

  // A placement that fails: nothing is inserted, the pass says so.
  std::vector<StreakRow> more{row(0, {0, 1})};
  owner.fail = true;
  refinement.begin(more);
  CHECK_FALSE(refinement.refine_once(more, next_id, owner));
  CHECK(more[0].p.size() == 2);
}

TEST_CASE("streak refinement: coarsening removes every other particle of a crowded row, a row "
          "between two close ones, and a row that has stopped",
          "[spacetime][streak]") {
  StreakRefinement refinement(limits(ParticleInsertion::interpolate));
  std::vector<double> crowded;
  for (int k = 0; k <= 10; ++k) crowded.push_back(k / 10.0);
  std::vector<StreakRow> rows{row(0, crowded)};
  LabelPlane owner;
  refinement.coarsen(rows, owner);
  REQUIRE(rows.size() == 1);
  std::vector<double> kept;
  for (const StreakParticle& p : rows[0].p) kept.push_back(p.s);
  CHECK(kept == std::vector<double>{0, 0.2, 0.4, 0.6, 0.8, 1});
  CHECK(refinement.counts().s_removals == 5);
  CHECK(owner.left == 0);  // none had a slot in a resident set

  // Rows 0.05 apart: the middle one goes (never the oldest or the newest); a row of three keeps
  // its particles.
  std::vector<StreakRow> close{row(0, {0, 0.5, 1}), row(0.05, {0, 0.5, 1}), row(0.1, {0, 0.5, 1})};
  refinement.coarsen(close, owner);
  REQUIRE(close.size() == 2);
  CHECK(close[0].tau == 0);
  CHECK(close[1].tau == 0.1);
  CHECK(close[0].p.size() == 3);
  CHECK(refinement.counts().rows_removed == 1);
  CHECK(owner.left == 3);  // the removed row's particles

  // A row whose particles have all stopped carries nothing: it goes.
  std::vector<StreakRow> stopped{row(0, {0, 0.5, 1}), row(1, {0, 0.5, 1})};
  for (StreakParticle& p : stopped[0].p) p.set_status(advect::ParticleStatus::left_domain);
  refinement.coarsen(stopped, owner);
  REQUIRE(stopped.size() == 1);
  CHECK(stopped[0].tau == 1);
}
