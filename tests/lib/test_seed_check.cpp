// The shared seed check: at least two seed vertices inside with data, messages that tell no data
// from outside and name seed, field, time and domain.
#include <catch2/catch.hpp>

#include "orthofront/error.h"
#include "orthofront/seed/seed_check.h"

using namespace orthofront;
using Catch::Matchers::Contains;

namespace {

SeedContext context() {
  SeedContext c;
  c.seed = "seed 'line:0,0,0:1,0,0'";
  c.field = "field 'f'";
  c.when = " at t0 = 1";
  c.domain = describe_box(Box<3>{Vec3(0, 0, 0), Vec3(2, 1, 1)}, 2);
  c.dimension = 2;
  return c;
}

}  // namespace

TEST_CASE("seed check: counts, and which message a seed gets", "[seed]") {
  SeedSurvey s;
  s.add(Vec3(5, 5, 0), FieldStatus::outside, Vec3::Zero());
  s.add(Vec3(0.5, 0.5, 0), FieldStatus::inside, Vec3(1, 0, 0));
  CHECK(s.vertices == 2);
  CHECK(s.inside == 1);
  CHECK(s.outside == 1);
  CHECK_THROWS_WITH(require_seed_inside(s, context(), true),
                    Contains("seed 'line:0,0,0:1,0,0' lies outside the domain of field 'f' at "
                             "t0 = 1 (1 of 2 seed vertices inside, at least 2 needed; e.g. the "
                             "point (5, 5) is outside the domain [0, 2] x [0, 1])"));

  SeedSurvey holes;
  holes.add(Vec3(0.25, 0.5, 0), FieldStatus::no_data, Vec3::Zero());
  holes.add(Vec3(0.5, 0.5, 0), FieldStatus::no_data, Vec3::Zero());
  CHECK_THROWS_WITH(require_seed_inside(holes, context(), true),
                    Contains("lies where field 'f' has no data at t0 = 1") &&
                        Contains("e.g. at the point (0.25, 0.5)"));

  SeedSurvey still;
  still.add(Vec3(0, 0, 0), FieldStatus::inside, Vec3::Zero());
  still.add(Vec3(1, 0, 0), FieldStatus::inside, Vec3::Zero());
  CHECK(still.still == 2);
  CHECK_THROWS_WITH(require_seed_inside(still, context(), true),
                    Contains("field 'f' has zero velocity at every vertex of seed"));
  CHECK_NOTHROW(require_seed_inside(still, context(), false));

  SeedSurvey fine;
  fine.add(Vec3(0, 0, 0), FieldStatus::inside, Vec3(1, 0, 0));
  fine.add(Vec3(1, 0, 0), FieldStatus::outside, Vec3::Zero());
  fine.add(Vec3(2, 0, 0), FieldStatus::inside, Vec3::Zero());
  CHECK_NOTHROW(require_seed_inside(fine, context(), true));
}
