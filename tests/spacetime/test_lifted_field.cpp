#include <catch2/catch.hpp>

#include "orthofront/error.h"
#include "orthofront/field/unsteady.h"
#include "orthofront/spacetime/lifted_field.h"

using namespace orthofront;
using orthofront::spacetime::LiftedField;

namespace {
template <int N>
void check_jacobian(const LiftedField<N>& f, const Vec<N>& X) {
  Vec<N> V = Vec<N>::Zero(), V2 = Vec<N>::Zero();
  Mat<N> J = Mat<N>::Zero();
  REQUIRE(f.velocity_jacobian(X, V, J) == FieldStatus::inside);
  REQUIRE(f.velocity(X, V2) == FieldStatus::inside);
  CHECK((V - V2).norm() == 0.0);
  CHECK(V[N - 1] == f.time_scale());
  const double h = 1e-6;
  for (int c = 0; c < N; ++c) {
    Vec<N> e = Vec<N>::Zero();
    e[c] = h;
    Vec<N> vp = Vec<N>::Zero(), vm = Vec<N>::Zero();
    REQUIRE(f.velocity(X + e, vp) == FieldStatus::inside);
    REQUIRE(f.velocity(X - e, vm) == FieldStatus::inside);
    const Vec<N> numeric = (vp - vm) / (2 * h);
    INFO("column " << c << ": numeric " << numeric.transpose() << ", exact "
                   << J.col(c).transpose());
    CHECK((numeric - J.col(c)).norm() < 1e-7 * (1 + J.norm()));
  }
  CHECK(J.row(N - 1).norm() == 0.0);
}
}  // namespace

TEST_CASE("lifted field: Jacobian is [[dv/dx, (1/c) dv/dt], [0, 0]]", "[spacetime]") {
  const auto gyre = make_unsteady_field("double-gyre");
  for (double c : {0.3, 1.0, 4.0}) {
    const LiftedField<3> f(*gyre, c, TimeRange{0, 20});
    check_jacobian<3>(f, f.lift(Vec3(0.7, 0.3, 0), 2.5));
    check_jacobian<3>(f, f.lift(Vec3(1.6, 0.8, 0), 11.0));
    // The last column is dv/dt divided by c (chain rule for tau = c t).
    Vec3 v, dvdt;
    Mat3 j;
    gyre->velocity_jacobian(Vec3(0.7, 0.3, 0), 2.5, v, j, dvdt);
    Vec3 V;
    Mat3 J;
    f.velocity_jacobian(f.lift(Vec3(0.7, 0.3, 0), 2.5), V, J);
    CHECK(J(0, 2) == Approx(dvdt[0] / c));
    CHECK(J(1, 2) == Approx(dvdt[1] / c));
  }
  const auto abc = make_unsteady_field("unsteady-abc");
  const LiftedField<4> f4(*abc, 2.5, TimeRange{0, 10});
  check_jacobian<4>(f4, f4.lift(Vec3(0.4, 1.1, -0.7), 3.3));
}

TEST_CASE("lifted field: domain spans c [t_begin, t_end] and rejects bad input", "[spacetime]") {
  const auto gyre = make_unsteady_field("double-gyre");
  const LiftedField<3> f(*gyre, 2.0, TimeRange{1, 5});
  CHECK(f.domain().lo[2] == 2.0);
  CHECK(f.domain().hi[2] == 10.0);
  CHECK(f.time(f.lift(Vec3(1, 0.5, 0), 3.25)) == 3.25);
  Vec3 V;
  CHECK(f.velocity(f.lift(Vec3(1, 0.5, 0), 5.5), V) == FieldStatus::outside);
  CHECK(f.velocity(f.lift(Vec3(1, 0.5, 0), 0.5), V) == FieldStatus::outside);
  CHECK_THROWS_AS(LiftedField<4>(*gyre, 1.0, TimeRange{0, 1}), InvalidArgument);
  CHECK_THROWS_WITH(LiftedField<3>(*gyre, 0.0, TimeRange{0, 1}),
                    Catch::Contains("time scale must be finite and > 0"));
  const auto abc = make_unsteady_field("unsteady-abc");
  CHECK_THROWS_AS(LiftedField<4>(*abc, 1.0, TimeRange{-5, -1}), InvalidArgument);
}
