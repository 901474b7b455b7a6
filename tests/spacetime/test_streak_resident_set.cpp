// StreakResidentSet: the rows' moving particles kept with the CPU bulk advection backend; slots
// handed out and given back, and a move in flight with particles entering and leaving meanwhile,
// whose positions equal those of moves in turn, bit for bit.
#include <catch2/catch.hpp>

#include <memory>
#include <vector>

#include "orthofront/advect/batch_advector.h"
#include "orthofront/error.h"
#include "orthofront/field/unsteady.h"
#include "orthofront/spacetime/brick_cache.h"
#include "orthofront/spacetime/bulk_flow_map.h"
#include "orthofront/spacetime/sampled_series.h"
#include "orthofront/spacetime/streak_resident_set.h"

using namespace orthofront;
using namespace orthofront::spacetime;

namespace {

struct Gyre {
  std::unique_ptr<UnsteadyField> flow = make_unsteady_field("double-gyre");
  SampledTimeSeries series{*flow, uniform_grid(flow->domain(), 2, 101), uniform_times(0, 2, 9)};
  BrickCache cache{series, [] {
                     CacheOptions co;
                     co.whole_steps = true;
                     return co;
                   }()};
  CachedSteps steps{cache};
  BulkFlowMap bulk{steps, advect::make_advector(advect::Device::cpu), [] {
                     advect::MethodOptions m;
                     m.method = advect::Method::dopri5;
                     return m;
                   }()};
};

StreakParticle particle(double x, double y) {
  StreakParticle p;
  p.x = Vec3(x, y, 0);
  return p;
}

// Where the bulk map takes x from t0 to t1, alone.
Vec3 moved(const BulkFlowMap& bulk, const Vec3& x, double t0, double t1) {
  std::vector<Vec3> xs{x};
  std::vector<double> from{t0};
  std::vector<ParticleStatus> status(1);
  bulk.advect_all(xs, from, t1, status);
  return xs[0];
}

std::vector<StreakParticle*> pointers(StreakRow& row, std::size_t from = 0) {
  std::vector<StreakParticle*> ps;
  for (std::size_t i = from; i < row.p.size(); ++i) ps.push_back(&row.p[i]);
  return ps;
}

}  // namespace

TEST_CASE("resident set: slots in order, given back last first, moves in turn as the flow map",
          "[spacetime][streak][advect]") {
  Gyre g;
  StreakResidentSet set(g.bulk);
  std::vector<StreakRow> rows(1);
  for (int i = 0; i < 5; ++i) rows[0].p.push_back(particle(0.2 + 0.3 * i, 0.5));
  rows[0].p[3].set_status(ParticleStatus::left_domain);  // stopped: takes no slot
  set.enter(pointers(rows[0]));
  const std::vector<std::uint32_t> slots{0, 1, 2, kNoSlot, 3};
  for (std::size_t i = 0; i < 5; ++i) CHECK(rows[0].p[i].slot() == slots[i]);

  std::vector<Vec3> start;
  for (const StreakParticle& p : rows[0].p) start.push_back(p.x);
  StreakResidentSet::Stops stopped(1, {0, 0});
  CHECK(set.advance(rows, 0, 0.5, stopped) == 4);
  for (const std::size_t i : {0, 1, 2, 4}) CHECK(rows[0].p[i].x == moved(g.bulk, start[i], 0, 0.5));
  CHECK(rows[0].p[3].x == start[3]);  // stopped: not moved

  set.leave(rows[0].p[1]);
  set.leave(rows[0].p[2]);
  CHECK(rows[0].p[1].slot() == kNoSlot);
  rows[0].p.erase(rows[0].p.begin() + 1, rows[0].p.begin() + 3);
  rows[0].p.push_back(particle(1.5, 0.25));
  rows[0].p.push_back(particle(1.6, 0.25));
  rows[0].p.push_back(particle(1.7, 0.25));
  set.enter(pointers(rows[0], 3));
  CHECK(rows[0].p[3].slot() == 2);  // given back last: handed out first
  CHECK(rows[0].p[4].slot() == 1);
  CHECK(rows[0].p[5].slot() == 4);  // then new ones
  CHECK(set.counts().evaluations > 0);
}

TEST_CASE("resident set: particles entering and leaving during a move land where moves in turn "
          "put them, and slots given back meanwhile wait for the landing",
          "[spacetime][streak][advect]") {
  Gyre g;
  StreakResidentSet set(g.bulk);
  std::vector<StreakRow> rows(2);
  for (int i = 0; i < 4; ++i) rows[0].p.push_back(particle(0.3 + 0.4 * i, 0.4));
  set.enter(pointers(rows[0]));
  std::vector<Vec3> at_launch;
  for (const StreakParticle& p : rows[0].p) at_launch.push_back(p.x);

  set.launch(0.5, 1.0);
  CHECK(set.in_flight());
  CHECK(set.flight_to() == 1.0);
  set.leave(rows[0].p[0]);  // old: parked when the move lands; its slot waits till then
  rows[0].p.erase(rows[0].p.begin());
  at_launch.erase(at_launch.begin());
  for (int i = 0; i < 3; ++i) rows[1].p.push_back(particle(0.5 + 0.5 * i, 0.7));
  set.enter(pointers(rows[1]));  // fresh: they catch up
  CHECK(rows[1].p[0].slot() == 4);  // slot 0 is not handed out while the set moves
  set.leave(rows[1].p[2]);          // fresh and gone before the landing
  rows[1].p.pop_back();
  set.start_catch_up();
  std::vector<StreakParticle> late{particle(1, 0.5)};
  std::vector<StreakParticle*> late_ptr{&late[0]};
  CHECK_THROWS_AS(set.enter(late_ptr), Error);  // after the catch-up started

  StreakResidentSet::Stops stopped(2, {0, 0});
  CHECK(set.land(rows, stopped) == 3 + 2);
  CHECK_FALSE(set.in_flight());
  for (std::size_t i = 0; i < 3; ++i) CHECK(rows[0].p[i].x == moved(g.bulk, at_launch[i], 0.5, 1.0));
  CHECK(rows[1].p[0].x == moved(g.bulk, Vec3(0.5, 0.7, 0), 0.5, 1.0));
  CHECK(rows[1].p[1].x == moved(g.bulk, Vec3(1.0, 0.7, 0), 0.5, 1.0));
  CHECK(set.counts().catch_up_calls == 1);
  CHECK(set.counts().catch_up_particles == 3);

  // The caught-up particles are in the set now: the next move takes them along.
  const Vec3 fresh_at_one = rows[1].p[0].x;
  std::fill(stopped.begin(), stopped.end(), std::array<std::size_t, 2>{0, 0});
  CHECK(set.advance(rows, 1.0, 1.5, stopped) == 5);
  CHECK(rows[1].p[0].x == moved(g.bulk, fresh_at_one, 1.0, 1.5));
  // Slots given back during the move are free after it.
  std::vector<StreakParticle> more{particle(1, 0.5), particle(1.1, 0.5)};
  std::vector<StreakParticle*> more_ptr{&more[0], &more[1]};
  set.enter(more_ptr);
  CHECK(more[0].slot() == 6);  // the fresh particle's, given back last
  CHECK(more[1].slot() == 0);
}
