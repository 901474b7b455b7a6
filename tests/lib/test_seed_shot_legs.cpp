// Seed-shot legs started a step ahead (engine/seed_shot_legs.h): a leg found among them is the
// leg integrated in place, bit for bit, whoever integrated it and whenever; legs of an older
// step are not found; and a surface built with legs ahead is the one built without.
#include <tbb/task_arena.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "lib/surface_checks.h"
#include "orthofront/engine/seed_shot_legs.h"
#include "orthofront/engine/stream_surface.h"
#include "orthofront/field/analytic.h"

using namespace orthofront;

namespace {

bool same_result(const IntegrationResult<3>& a, const IntegrationResult<3>& b) {
  return std::memcmp(a.x.data(), b.x.data(), sizeof(Vec3)) == 0 && a.status == b.status &&
         a.evaluations == b.evaluations && a.reached == b.reached &&
         a.interrupted == b.interrupted && a.exhausted == b.exhausted;
}

struct Setup {
  std::unique_ptr<Field3> field = make_analytic_field("abc");
  Seed<3> seed = make_seed(SeedCurve::line(Vec3(0, 0, 1), Vec3(3, 3, 1)), 20);
  Tolerance tolerance{1e-9, 1e-9};
  StopRequest stop = [] { return false; };

  IntegrationResult<3> in_place(double s, double t1) const {
    return integrate_dopri5(*field, seed.point(s), t1, tolerance, 0, &stop);
  }

  /// Legs of increasing length (the last ones take a while), so that some are done, some in
  /// flight and some not begun when they are asked for.
  static std::vector<std::pair<double, double>> keys() {
    std::vector<std::pair<double, double>> k;
    for (int i = 0; i < 24; ++i) k.emplace_back(0.01 + 0.04 * i, 0.5 + 2.0 * i);
    return k;
  }
};

}  // namespace

TEST_CASE("a leg started ahead is the leg integrated in place, bit for bit",
          "[engine][adapt][threads]") {
  Setup setup;
  const auto keys = Setup::keys();
  std::vector<IntegrationResult<3>> reference;
  for (const auto& [s, t1] : keys) reference.push_back(setup.in_place(s, t1));
  tbb::task_arena arena(2);
  arena.execute([&] {
    for (const int wait_us : {0, 50, 2000, 200000}) {
      INFO("asked for " << wait_us << " us after the start");
      SeedShotLegs<3> legs(*setup.field, setup.seed, setup.tolerance, setup.stop);
      REQUIRE(legs.can_run_ahead());
      // Two starts in one step (two fronts), the second with a key the first had already.
      legs.start_ahead({keys.begin(), keys.begin() + 12});
      legs.start_ahead({keys.begin() + 11, keys.end()});
      CHECK(legs.started() == keys.size());
      legs.begin_step();
      std::this_thread::sleep_for(std::chrono::microseconds(wait_us));
      for (std::size_t k = 0; k < keys.size(); ++k)
        CHECK(same_result(legs.leg(keys[k].first, keys[k].second), reference[k]));
      // Used: those a task had integrated or was integrating; the rest were claimed here.
      const std::size_t used = legs.used();
      CHECK(used <= keys.size());
      if (wait_us == 200000) CHECK(used > 0);
      // A leg not started, and a started s with another t1: integrated in place.
      CHECK(same_result(legs.leg(0.5, 3.0), setup.in_place(0.5, 3.0)));
      CHECK(same_result(legs.leg(keys[3].first, 1.25), setup.in_place(keys[3].first, 1.25)));
      CHECK(legs.used() == used);
    }
  });
}

TEST_CASE("legs ahead: only the last step's are found, and none outlives its owner",
          "[engine][adapt][threads]") {
  Setup setup;
  const auto keys = Setup::keys();
  tbb::task_arena arena(2);
  arena.execute([&] {
    {
      SeedShotLegs<3> legs(*setup.field, setup.seed, setup.tolerance, setup.stop);
      legs.start_ahead(keys);
      legs.begin_step();  // the legs become this step's
      legs.begin_step();  // and are dropped: a step later no insertion asks for them
      CHECK(same_result(legs.leg(keys[5].first, keys[5].second),
                        setup.in_place(keys[5].first, keys[5].second)));
      CHECK(legs.used() == 0);
      // Started and left at once: the destructor waits for the leg in flight (ASan would see
      // a task integrating with a field reference that no longer lives).
      legs.start_ahead(keys);
    }
    {
      SeedShotLegs<3> legs(*setup.field, setup.seed, setup.tolerance, setup.stop);
      legs.start_ahead(keys);
      legs.begin_step();
      legs.drop_pending();  // the surface is finished
      CHECK(same_result(legs.leg(keys[0].first, keys[0].second),
                        setup.in_place(keys[0].first, keys[0].second)));
    }
  });
  // In an arena of one thread no leg can run ahead: none is started.
  tbb::task_arena one(1);
  one.execute([&] {
    SeedShotLegs<3> legs(*setup.field, setup.seed, setup.tolerance, setup.stop);
    CHECK_FALSE(legs.can_run_ahead());
  });
}

TEST_CASE("legs give up after their evaluations, ahead as in place",
          "[engine][adapt][threads]") {
  Setup setup;
  const auto keys = Setup::keys();
  constexpr int cap = 400;
  const auto capped = [&](double s, double t1) {
    return integrate_dopri5(*setup.field, setup.seed.point(s), t1, setup.tolerance, 0,
                            &setup.stop, cap);
  };
  std::size_t exhausted = 0;
  for (const auto& [s, t1] : keys) {
    const IntegrationResult<3> r = capped(s, t1);
    const IntegrationResult<3> full = setup.in_place(s, t1);
    INFO("leg " << t1 << " long: " << full.evaluations << " evaluations in full");
    CHECK(r.exhausted == (full.evaluations > cap));
    CHECK_FALSE(full.exhausted);
    if (!r.exhausted) {
      CHECK(same_result(r, full));
      continue;
    }
    ++exhausted;
    CHECK(r.status == FieldStatus::no_data);
    CHECK_FALSE(r.interrupted);
    CHECK(r.evaluations <= cap + 6);  // the step that went over
    CHECK(std::abs(r.reached) < std::abs(t1));
  }
  CHECK(exhausted > 0);
  CHECK(exhausted < keys.size());
  tbb::task_arena arena(2);
  arena.execute([&] {
    SeedShotLegs<3> legs(*setup.field, setup.seed, setup.tolerance, setup.stop, cap);
    legs.start_ahead(keys);
    legs.begin_step();
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    for (const auto& [s, t1] : keys) CHECK(same_result(legs.leg(s, t1), capped(s, t1)));
  });
}

namespace {

/// abc, but a sample above z = 4 throws (a reader failing part-way, say).
class ThrowingField final : public Field3 {
 public:
  FieldStatus velocity(const Vec3& x, Vec3& v) const override {
    if (x.z() > 4) throw std::runtime_error("no sample above z = 4");
    return abc_->velocity(x, v);
  }
  FieldStatus velocity_jacobian(const Vec3& x, Vec3& v, Mat3& J) const override {
    if (x.z() > 4) throw std::runtime_error("no sample above z = 4");
    return abc_->velocity_jacobian(x, v, J);
  }
  Box<3> domain() const override { return abc_->domain(); }
  std::string describe() const override { return "throwing abc"; }

 private:
  std::unique_ptr<Field3> abc_ = make_analytic_field("abc");
};

}  // namespace

TEST_CASE("an error in a leg run ahead surfaces where the leg is asked for, and nothing hangs",
          "[engine][adapt][threads]") {
  ThrowingField field;
  Setup setup;
  // From z = 1 along abc, a stream line climbs past z = 4 within t = 20 (checked here in place).
  const double s = 0.3, long_t1 = 40, short_t1 = 0.2;
  REQUIRE_THROWS(integrate_dopri5(field, setup.seed.point(s), long_t1, setup.tolerance, 0,
                                  &setup.stop));
  tbb::task_arena arena(2);
  arena.execute([&] {
    for (const int wait_us : {0, 100000}) {
      SeedShotLegs<3> legs(field, setup.seed, setup.tolerance, setup.stop);
      legs.start_ahead({{s, long_t1}, {0.6, short_t1}});
      legs.begin_step();
      std::this_thread::sleep_for(std::chrono::microseconds(wait_us));
      CHECK_THROWS_WITH(legs.leg(s, long_t1), "no sample above z = 4");
      // The other leg is unharmed, and the failed one can be asked for again.
      CHECK(same_result(legs.leg(0.6, short_t1), setup.in_place(0.6, short_t1)));
      CHECK_THROWS(legs.leg(s, long_t1));
    }
  });
}

TEST_CASE("a surface built with seed-shot legs ahead is the one built without",
          "[engine][adapt][threads]") {
  const test_support::SurfaceCase cases[] = {
      {"saddle3d", SeedCurve::line(Vec3(-1, 2, 0.1), Vec3(1, 2, 0.1)), 0.05, 60},
      {"abc", SeedCurve::line(Vec3(0, 0, 1), Vec3(3, 3, 1)), 0.1, 120},
  };
  for (const test_support::SurfaceCase& c : cases) {
    INFO(c.field);
    const auto [ahead, in_place] =
        test_support::built_with_and_without(c, {}, &StreamSurfaceOptions::shots_ahead);
    INFO(ahead.report.legs_started_ahead << " legs started ahead, "
                                         << ahead.report.legs_used_ahead << " used, of "
                                         << ahead.report.streamline_insertions
                                         << " stream-line insertions");
    CHECK(ahead.report.legs_started_ahead > 20);
    CHECK(in_place.report.legs_started_ahead == 0);
    test_support::check_identical(ahead, in_place);
    CHECK(ahead.report.field_evaluations == in_place.report.field_evaluations);
    CHECK(ahead.report.streamline_insertions == in_place.report.streamline_insertions);
  }
}
