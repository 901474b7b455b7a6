#include "orthofront/seed/seed_check.h"

#include "orthofront/error.h"
#include "orthofront/field/field_spec.h"

namespace orthofront {

namespace {

std::string number(double value) { return format_parameter(value); }

std::string point(const Vec3& x, int dimension) {
  std::string text = "(";
  for (int a = 0; a < dimension; ++a) text += (a ? ", " : "") + number(x[a]);
  return text + ")";
}

}  // namespace

void SeedSurvey::add(const Vec3& x, FieldStatus status, const Vec3& velocity) {
  ++vertices;
  if (status == FieldStatus::inside) {
    ++inside;
    if (velocity.squaredNorm() == 0 && still++ == 0) first_still = x;
  } else if (status == FieldStatus::no_data) {
    if (no_data++ == 0) first_no_data = x;
  } else if (outside++ == 0) {
    first_outside = x;
  }
}

std::string describe_box(const Box<3>& box, int dimension) {
  std::string text;
  for (int a = 0; a < dimension; ++a)
    text += (a ? " x [" : "[") + number(box.lo[a]) + ", " + number(box.hi[a]) + "]";
  return text;
}

void require_seed_inside(const SeedSurvey& s, const SeedContext& c, bool need_flow) {
  const std::string about = c.about.empty() ? "" : "; " + c.about;
  const std::string of_all = " of " + std::to_string(s.vertices) + " seed vertices";
  if (s.inside < 2) {
    if (s.no_data > 0 && s.outside == 0)
      throw InvalidArgument(c.seed + " lies where " + c.field + " has no data" + c.when +
                            " (NaN, fill values or zero vectors; " + std::to_string(s.inside) +
                            of_all + " with data, at least 2 needed; e.g. at the point " +
                            point(s.first_no_data, c.dimension) +
                            (c.domain.empty() ? "" : "; domain " + c.domain) + about + ")");
    throw InvalidArgument(c.seed + " lies outside the domain of " + c.field + c.when + " (" +
                          std::to_string(s.inside) + of_all +
                          " inside, at least 2 needed; e.g. the point " +
                          point(s.first_outside, c.dimension) + " is outside" +
                          (c.domain.empty() ? "" : " the domain " + c.domain) + about + ")");
  }
  // A flow that stands still along the whole seed moves no front: nothing to build.
  if (need_flow && s.still == s.inside)
    throw InvalidArgument(c.field + " has zero velocity at every vertex of " + c.seed +
                          " inside its domain" + c.when + " (" + std::to_string(s.inside) + of_all +
                          " inside; e.g. at the point " + point(s.first_still, c.dimension) +
                          "): no flow to build a surface from");
}

}  // namespace orthofront
