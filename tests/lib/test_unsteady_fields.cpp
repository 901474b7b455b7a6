#include <catch2/catch.hpp>

#include <cmath>
#include <string>

#include "orthofront/error.h"
#include "orthofront/field/unsteady.h"
#include "orthofront/integrate/runge_kutta.h"

using namespace orthofront;

namespace {

// The unsteady field as the steady field (v, 1) over (x, t), for an independent DOPRI5 check.
class TimeAsCoordinate final : public Field<4> {
 public:
  explicit TimeAsCoordinate(const UnsteadyField& f) : f_(f) {}
  FieldStatus velocity(const Vec<4>& x, Vec<4>& v) const override {
    Vec3 w;
    const FieldStatus st = f_.velocity(x.head<3>(), x[3], w);
    v << w, 1.0;
    return st;
  }
  FieldStatus velocity_jacobian(const Vec<4>& x, Vec<4>& v, Mat<4>& J) const override {
    Vec3 w, dt;
    Mat3 j;
    const FieldStatus st = f_.velocity_jacobian(x.head<3>(), x[3], w, j, dt);
    v << w, 1.0;
    J.setZero();
    J.topLeftCorner<3, 3>() = j;
    J.block<3, 1>(0, 3) = dt;
    return st;
  }
  Box<4> domain() const override { return Box<4>{}; }
  std::string describe() const override { return f_.describe(); }

 private:
  const UnsteadyField& f_;
};

void check_derivatives(const UnsteadyField& f, const Vec3& x, double t) {
  Vec3 v, dvdt;
  Mat3 J;
  REQUIRE(f.velocity_jacobian(x, t, v, J, dvdt) == FieldStatus::inside);
  Vec3 v2;
  REQUIRE(f.velocity(x, t, v2) == FieldStatus::inside);
  CHECK((v - v2).norm() < 1e-14 * (1 + v.norm()));
  const double h = 1e-6;
  const int d = f.dimension();
  for (int c = 0; c < 3; ++c) {
    Vec3 vp, vm;
    Vec3 e = Vec3::Zero();
    e[c] = h;
    f.velocity(x + e, t, vp);
    f.velocity(x - e, t, vm);
    const Vec3 numeric = (vp - vm) / (2 * h);
    if (c >= d) {
      CHECK(J.col(c).norm() == 0.0);  // 2D fields do not depend on z
      continue;
    }
    INFO(f.describe() << " column " << c << " numeric " << numeric.transpose() << " exact "
                      << J.col(c).transpose());
    CHECK((numeric - J.col(c)).norm() < 1e-7 * (1 + J.norm()));
  }
  Vec3 vp, vm;
  f.velocity(x, t + h, vp);
  f.velocity(x, t - h, vm);
  const Vec3 numeric = (vp - vm) / (2 * h);
  INFO(f.describe() << " dv/dt numeric " << numeric.transpose() << " exact " << dvdt.transpose());
  CHECK((numeric - dvdt).norm() < 1e-7 * (1 + dvdt.norm()));
  if (d == 2) {
    CHECK(v[2] == 0.0);
    CHECK(dvdt[2] == 0.0);
  }
}

}  // namespace

TEST_CASE("unsteady fields: Jacobians and dv/dt match central differences", "[unsteady]") {
  const char* specs[] = {"double-gyre", "double-gyre-3d:B=0.3", "unsteady-abc",
                         "moving-spiral", "moving-spiral:dim=2,sigma=0.05"};
  for (const char* spec : specs) {
    const auto f = make_unsteady_field(spec);
    const Box<3> box = f->domain();
    for (int k = 0; k < 7; ++k) {
      const Vec3 u(0.13 + 0.11 * k, 0.71 - 0.09 * k, 0.37 + 0.05 * k);
      const Vec3 x = box.lo + u.cwiseProduct(box.extent());
      check_derivatives(*f, x, 0.3 + 1.7 * k);
    }
  }
}

TEST_CASE("unsteady fields: double gyre values", "[unsteady]") {
  const auto f = make_unsteady_field("double-gyre:A=0.1,eps=0.25,omega=0.6283");
  CHECK(f->dimension() == 2);
  Vec3 v;
  // At t = 0: f = x, u = -pi A sin(pi x) cos(pi y), v = pi A cos(pi x) sin(pi y).
  REQUIRE(f->velocity(Vec3(0.5, 0.25, 7.0), 0.0, v) == FieldStatus::inside);
  CHECK(v[0] == Approx(-std::numbers::pi * 0.1 * std::cos(std::numbers::pi * 0.25)));
  CHECK(v[1] == Approx(0.0).margin(1e-15));
  CHECK(f->velocity(Vec3(2.1, 0.5, 0), 0.0, v) == FieldStatus::outside);
  const auto g = make_unsteady_field("double-gyre-3d");
  CHECK(g->dimension() == 3);
  REQUIRE(g->velocity(Vec3(0.3, 0.2, 0.0), 1.0, v) == FieldStatus::inside);
  CHECK(v[2] == 0.0);  // the slab's floor is invariant
}

TEST_CASE("unsteady fields: closed-form path lines match DOPRI5", "[unsteady]") {
  for (const char* spec : {"moving-spiral", "moving-spiral:dim=2", "moving-spiral:beta=0.9,nu=2"}) {
    const auto f = make_unsteady_field(spec);
    const TimeAsCoordinate lifted(*f);
    for (int k = 0; k < 5; ++k) {
      const Vec3 x0(-1.0 + 0.5 * k, 0.8 - 0.3 * k, 0.5 + 0.1 * k);
      const double t0 = 0.4 * k, t1 = t0 + 6.0;
      Vec3 exact;
      REQUIRE(f->exact_flow_map(x0, t0, t1, exact));
      Vec<4> start;
      start << x0, t0;
      const auto r = integrate_dopri5<4>(lifted, start, t1 - t0, Tolerance{1e-12, 1e-12});
      REQUIRE(r.status == FieldStatus::inside);
      INFO(spec << " x0 " << x0.transpose());
      CHECK((r.x.head<3>() - exact).norm() < 1e-8 * (1 + exact.norm()));
      CHECK(r.x[3] == Approx(t1));
      Vec3 same;
      f->exact_flow_map(x0, t0, t0, same);
      CHECK((same - x0).norm() < 1e-15);
    }
  }
  Vec3 x;
  CHECK_FALSE(make_unsteady_field("double-gyre")->exact_flow_map(Vec3::Zero(), 0, 1, x));
}

TEST_CASE("unsteady fields: specs are parsed and errors name the fault", "[unsteady]") {
  CHECK(make_unsteady_field("double-gyre:A=0.2")->describe() ==
        "double-gyre:A=0.2,eps=0.25,omega=0.628319");
  CHECK(is_unsteady_field_name("unsteady-abc:a=1"));
  CHECK_FALSE(is_unsteady_field_name("abc"));
  auto message = [](const char* spec) {
    try {
      make_unsteady_field(spec);
    } catch (const InvalidArgument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  CHECK_THAT(message("gyre"), Catch::Contains("unknown unsteady field 'gyre'"));
  CHECK_THAT(message("double-gyre:Q=1"), Catch::Contains("no parameter 'Q'"));
  CHECK_THAT(message("double-gyre:A=x"), Catch::Contains("'A' has value 'x'"));
  CHECK_THAT(message("moving-spiral:dim=4"), Catch::Contains("'dim' has value '4'"));
  CHECK_THAT(message("unsteady-abc:decay=-1"), Catch::Contains("expected a number > 0"));
  CHECK(unsteady_fields().size() == 4);
  Vec3 v;
  CHECK(make_unsteady_field("unsteady-abc")->velocity(Vec3::Zero(), -1.0, v) ==
        FieldStatus::outside);
}
