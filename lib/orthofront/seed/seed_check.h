#pragma once
/// Whether a seed lies where a surface can start from it: the one check that stream, path and
/// streak surfaces share, with a message that names the seed, the field, the time and the domain,
/// and tells a seed without data (NaN, fill values, zero vectors) from one outside.
#include <cstddef>
#include <string>

#include "orthofront/field/field.h"
#include "orthofront/types.h"

namespace orthofront {

/// Where a seed's vertices fall, added one vertex at a time.
struct SeedSurvey {
  std::size_t vertices = 0, inside = 0, no_data = 0, outside = 0;
  std::size_t still = 0;  ///< inside, with velocity exactly zero
  Vec3 first_outside = Vec3::Zero(), first_no_data = Vec3::Zero(), first_still = Vec3::Zero();

  /// Counts a seed vertex at x with the field's status there and its velocity (read only when
  /// the status is inside).
  void add(const Vec3& x, FieldStatus status, const Vec3& velocity);
};

/// How the messages name things.
struct SeedContext {
  std::string seed = "the seed curve";  ///< e.g. "seed 'line:0,0,0:1,1,0'"
  std::string field = "the field";      ///< e.g. "field 'saddle3d'"
  std::string when;                     ///< e.g. " at t0 = 1", or empty for a steady field
  std::string domain;                   ///< e.g. "[0, 2] x [0, 1], t in [0, 5]", or empty
  std::string about;                    ///< the field's own description, or empty
  int dimension = 3;                    ///< coordinates printed per point
};

/// Throws InvalidArgument unless at least two seed vertices lie inside the domain with data and,
/// when `need_flow`, the velocity is not zero at all of them.
void require_seed_inside(const SeedSurvey& survey, const SeedContext& context, bool need_flow);

/// "[lo0, hi0] x [lo1, hi1] ..." over the first `dimension` axes, numbers as %g.
std::string describe_box(const Box<3>& box, int dimension);

}  // namespace orthofront
