#include <Eigen/Eigenvalues>
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "orthofront/error.h"
#include "orthofront/field/analytic.h"
#include "orthofront/field/scaled.h"

using namespace orthofront;

namespace {

// The message of the InvalidArgument thrown by make_analytic_field(spec), or "" if none.
std::string error_of(const std::string& spec) {
  try {
    make_analytic_field(spec);
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  return "";
}

Vec3 velocity_of(const Field3& field, const Vec3& x) {
  Vec3 v = Vec3::Zero();
  REQUIRE(field.velocity(x, v) == FieldStatus::inside);
  return v;
}

// Uniform random points of the box shrunk by `margin` of its extent on each side.
std::vector<Vec3> interior_points(const Box<3>& box, int count, double margin, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<Vec3> points;
  for (int i = 0; i < count; ++i) {
    Vec3 x;
    for (int c = 0; c < 3; ++c) {
      const double t = margin + (1.0 - 2.0 * margin) * unit(rng);
      x[c] = box.lo[c] + t * (box.hi[c] - box.lo[c]);
    }
    points.push_back(x);
  }
  return points;
}

// Central difference of v, column c with step 1e-5 max(1, |x_c|).
Mat3 finite_difference_jacobian(const Field3& field, const Vec3& x) {
  Mat3 J;
  for (int c = 0; c < 3; ++c) {
    const double h = 1e-5 * std::max(1.0, std::abs(x[c]));
    Vec3 xp = x, xm = x;
    xp[c] += h;
    xm[c] -= h;
    J.col(c) = (velocity_of(field, xp) - velocity_of(field, xm)) / (xp[c] - xm[c]);
  }
  return J;
}

}  // namespace

TEST_CASE("analytic fields are listed in a stable order with their parameters", "[field]") {
  std::vector<std::string> names;
  for (const auto& info : analytic_fields()) {
    names.push_back(info.name);
    CHECK_FALSE(info.formula.empty());
    CHECK_FALSE(info.domain.empty());
    for (const auto& param : info.parameters) CHECK_FALSE(param.help.empty());
  }
  CHECK(names == std::vector<std::string>{"saddle", "saddle3d", "sinus", "focus-sink", "lorenz",
                                          "stalling", "repelling-node-saddle", "abc"});
}

TEST_CASE("every analytic field has a Jacobian matching central differences", "[field]") {
  std::vector<std::string> specs;
  for (const auto& info : analytic_fields()) specs.push_back(info.name);
  specs.push_back("lorenz:reverse=1");
  specs.push_back("sinus:power=1");
  specs.push_back("sinus:power=4");

  for (const std::string& spec : specs) {
    SECTION(spec) {
      const auto field = make_analytic_field(spec);
      CHECK(field->describe().rfind(spec.substr(0, spec.find(':')), 0) == 0);
      for (const Vec3& x : interior_points(field->domain(), 200, 1e-3, 12345)) {
        Vec3 v, v2;
        Mat3 J;
        REQUIRE(field->velocity_jacobian(x, v, J) == FieldStatus::inside);
        REQUIRE(field->velocity(x, v2) == FieldStatus::inside);
        CHECK((v - v2).norm() <= 1e-14 * std::max(1.0, v.norm()));
        const Mat3 fd = finite_difference_jacobian(*field, x);
        INFO("x = " << x.transpose() << "\nJ =\n" << J << "\nfinite difference =\n" << fd);
        CHECK((J - fd).norm() <= 1e-6 * std::max(1.0, J.norm()));
      }
    }
  }
}

TEST_CASE("analytic fields take known values", "[field]") {
  const double pi = std::numbers::pi;
  CHECK(velocity_of(*make_analytic_field("saddle"), Vec3(1, 2, 0.5)).isApprox(Vec3(1, -2, 0)));
  CHECK(velocity_of(*make_analytic_field("saddle3d"), Vec3(1, 2, 3)).isApprox(Vec3(1, -2, 3)));
  CHECK(velocity_of(*make_analytic_field("lorenz"), Vec3(1, 1, 1))
            .isApprox(Vec3(0, 26, 1 - 8.0 / 3.0), 1e-14));
  CHECK(velocity_of(*make_analytic_field("sinus"), Vec3(0.3, pi / 2, 0))
            .isApprox(Vec3(5 + pi / 2, 1, 0), 1e-14));
  CHECK(velocity_of(*make_analytic_field("focus-sink"), Vec3(1, 2, 3))
            .isApprox(Vec3(-0.15 - 2, 1 - 0.3, -0.9), 1e-14));
  CHECK(velocity_of(*make_analytic_field("repelling-node-saddle"), Vec3(1, 1, 1))
            .isApprox(Vec3(1, 2, -1)));
  CHECK(velocity_of(*make_analytic_field("abc"), Vec3(0, 0, 0))
            .isApprox(Vec3(1, std::sqrt(3.0), std::sqrt(2.0)), 1e-14));
  CHECK(velocity_of(*make_analytic_field("stalling"), Vec3(-1, 0, 0))
            .isApprox(Vec3(1 + 1 / 1.01, 0, 0), 1e-14));

  // Exact stream surfaces: y z = const for saddle3d, x y = const for saddle.
  Vec3 v;
  Mat3 J;
  const Vec3 x(0.7, -1.3, 2.1);
  make_analytic_field("saddle3d")->velocity_jacobian(x, v, J);
  CHECK(std::abs(v[1] * x[2] + x[1] * v[2]) < 1e-15);
  const Vec3 p = x.cwiseMin(0.9);
  make_analytic_field("saddle")->velocity_jacobian(p, v, J);
  CHECK(std::abs(v[0] * p[1] + p[0] * v[1]) < 1e-15);
}

TEST_CASE("lorenz reverse=1 flips the sign of v and J", "[field]") {
  const auto forward = make_analytic_field("lorenz");
  const auto backward = make_analytic_field("lorenz:reverse=1");
  CHECK(backward->describe() == "lorenz:sigma=10,rho=28,beta=2.66667,reverse=1");
  for (const Vec3& x : interior_points(forward->domain(), 20, 0.0, 7)) {
    Vec3 vf, vb;
    Mat3 Jf, Jb;
    forward->velocity_jacobian(x, vf, Jf);
    backward->velocity_jacobian(x, vb, Jb);
    CHECK(vb == -vf);
    CHECK(Jb == -Jf);
  }
}

TEST_CASE("analytic fields report points outside their domain", "[field]") {
  for (const auto& info : analytic_fields()) {
    const auto field = make_analytic_field(info.name);
    const Box<3> box = field->domain();
    const Vec3 centre = 0.5 * (box.lo + box.hi);
    Vec3 v;
    Mat3 J;
    for (int c = 0; c < 3; ++c) {
      for (double side : {-1.0, 1.0}) {
        Vec3 x = centre;
        x[c] = (side < 0 ? box.lo[c] : box.hi[c]) + side * 1e-9 * (1 + std::abs(x[c]));
        INFO(info.name << " x = " << x.transpose());
        CHECK(field->velocity(x, v) == FieldStatus::outside);
        CHECK(field->velocity_jacobian(x, v, J) == FieldStatus::outside);
      }
    }
    CHECK(field->velocity(box.lo, v) == FieldStatus::inside);
    CHECK(field->velocity(box.hi, v) == FieldStatus::inside);
    CHECK(field->velocity(Vec3(NAN, centre[1], centre[2]), v) == FieldStatus::outside);
  }
  const auto lorenz = make_analytic_field("lorenz");
  CHECK(lorenz->domain().lo.isApprox(Vec3(-80, -80, -60)));
  CHECK(lorenz->domain().hi.isApprox(Vec3(80, 80, 120)));
}

TEST_CASE("stalling has a saddle on its right boundary and a sink inside", "[field]") {
  const double xs = 0.5 * (1 + std::sqrt(1 - 4 * 0.01));  // (L + sqrt(L^2 - 4 eps^2)) / 2
  const double xn = 0.5 * (1 - std::sqrt(1 - 4 * 0.01));
  const auto field = make_analytic_field("stalling");
  const Box<3> box = field->domain();
  CHECK(box.hi[0] == Approx(xs).epsilon(1e-15));
  CHECK(box.lo[0] == -3);
  CHECK(box.lo[1] == -2);
  CHECK(box.hi[1] == 2);

  Vec3 v;
  Mat3 J;
  REQUIRE(field->velocity_jacobian(Vec3(box.hi[0], 0, 0), v, J) == FieldStatus::inside);
  CHECK(v.norm() < 1e-14);
  Eigen::EigenSolver<Eigen::Matrix2d> saddle(J.topLeftCorner<2, 2>());
  const Eigen::Vector2d ls = saddle.eigenvalues().real();
  CHECK(saddle.eigenvalues().imag().norm() == 0);
  CHECK(ls.maxCoeff() > 0.1);
  CHECK(ls.minCoeff() < -0.1);

  REQUIRE(field->velocity_jacobian(Vec3(xn, 0, 0), v, J) == FieldStatus::inside);
  CHECK(v.norm() < 1e-12);
  Eigen::EigenSolver<Eigen::Matrix2d> sink(J.topLeftCorner<2, 2>());
  CHECK(sink.eigenvalues().real().maxCoeff() < -1);

  // The main flow goes left to right away from the sink.
  CHECK(velocity_of(*field, Vec3(-3, 1.9, 0))[0] > 0.5);

  // Scaled parameters move the saddle with the boundary.
  const auto other = make_analytic_field("stalling:u=2,m=3,eps=0.2");
  const double l = 1.5;
  const double xs2 = 0.5 * (l + std::sqrt(l * l - 4 * 0.04));
  CHECK(other->domain().hi[0] == Approx(xs2).epsilon(1e-15));
  CHECK(velocity_of(*other, Vec3(other->domain().hi[0], 0, 0)).norm() < 1e-13);
  CHECK(error_of("stalling:eps=0.6").find("eps") != std::string::npos);
}

TEST_CASE("repelling-node-saddle has eigenvalues l1, l2 > 0 > l3", "[field]") {
  const auto field = make_analytic_field("repelling-node-saddle");
  Vec3 v;
  Mat3 J;
  field->velocity_jacobian(Vec3(0.1, 0.2, 0.3), v, J);
  CHECK(J == Mat3(Vec3(1, 2, -1).asDiagonal()));
  field->velocity_jacobian(Vec3::Zero(), v, J);
  CHECK(v == Vec3::Zero());
}

TEST_CASE("analytic field specs apply parameters", "[field][spec]") {
  const Vec3 x(1, 2, 3);
  CHECK(velocity_of(*make_analytic_field("lorenz:rho=10"), x)[1] == 1 * (10 - 3) - 2);
  CHECK(velocity_of(*make_analytic_field("lorenz"), x)[1] == 1 * (28 - 3) - 2);
  CHECK(make_analytic_field("lorenz:rho=10")->describe() ==
        "lorenz:sigma=10,rho=10,beta=2.66667,reverse=0");
  CHECK(make_analytic_field(" lorenz : beta = 1 , sigma=+2 ")->describe() ==
        "lorenz:sigma=2,rho=28,beta=1,reverse=0");
  CHECK(make_analytic_field("saddle")->describe() == "saddle");
  CHECK(make_analytic_field("sinus")->describe() == "sinus:amplitude=5,power=7,slope=1");
  CHECK(velocity_of(*make_analytic_field("sinus:amplitude=2,power=3,slope=0"), Vec3(0, 1, 0))[0] ==
        Approx(2 * std::pow(std::sin(1.0), 3)).epsilon(1e-14));
  CHECK(velocity_of(*make_analytic_field("focus-sink:a=1e-1,b=2"), x)
            .isApprox(Vec3(-0.1 - 2, 1 - 0.2, -6), 1e-14));
  CHECK(velocity_of(*make_analytic_field("abc:a=0,b=0,c=2"), Vec3(0, 0, 0))
            .isApprox(Vec3(2, 0, 0), 1e-14));
  CHECK(velocity_of(*make_analytic_field("repelling-node-saddle:l1=3,l3=-2"), x) == Vec3(3, 4, -6));
}

TEST_CASE("analytic field specs reject bad names, keys and values", "[field][spec]") {
  const std::string unknown = error_of("lorentz");
  CHECK(unknown.find("'lorentz'") != std::string::npos);
  CHECK(unknown.find("lorenz") != std::string::npos);
  CHECK(unknown.find("repelling-node-saddle") != std::string::npos);
  CHECK(error_of("") != "");
  CHECK(error_of(":rho=1") != "");

  const std::string key = error_of("lorenz:rh=10");
  CHECK(key.find("'rh'") != std::string::npos);
  CHECK(key.find("sigma, rho, beta, reverse") != std::string::npos);
  CHECK(error_of("saddle:x=1").find("'x'") != std::string::npos);

  for (const char* value : {"abc", "1.5x", "", "nan", "inf", "1e999", "--1", "+-1", "0x10"}) {
    INFO("value '" << value << "'");
    const std::string message = error_of(std::string("lorenz:rho=") + value);
    CHECK(message.find("'rho'") != std::string::npos);
    CHECK(message.find(std::string("'") + value + "'") != std::string::npos);
  }
  CHECK(error_of("lorenz:reverse=2").find("'2'") != std::string::npos);
  CHECK(error_of("lorenz:reverse=0.5").find("'0.5'") != std::string::npos);
  CHECK(error_of("sinus:power=2.5").find("'2.5'") != std::string::npos);
  CHECK(error_of("sinus:power=0").find("'power'") != std::string::npos);
  CHECK(error_of("stalling:u=-1").find("'-1'") != std::string::npos);
  CHECK(error_of("lorenz:rho").find("'rho'") != std::string::npos);
  CHECK(error_of("lorenz:rho=1,rho=2").find("'rho'") != std::string::npos);
  CHECK(error_of("lorenz:") != "");
  CHECK(error_of("lorenz:rho=1,") != "");
  CHECK(error_of("lorenz:reverse=1") == "");
}

TEST_CASE("ScaledField scales velocity, Jacobian and domain", "[field][scaled]") {
  const auto base = make_analytic_field("lorenz");
  for (const auto& [a, l] : std::vector<std::pair<double, double>>{{10, 1}, {10, 10}, {1, 3}}) {
    const ScaledField scaled(*base, a, l);
    CHECK(scaled.domain().lo.isApprox(l * base->domain().lo));
    CHECK(scaled.domain().hi.isApprox(l * base->domain().hi));
    CHECK(scaled.describe().find(base->describe()) != std::string::npos);
    for (const Vec3& x : interior_points(scaled.domain(), 50, 0.0, 99)) {
      Vec3 v, vb;
      Mat3 J, Jb;
      REQUIRE(scaled.velocity_jacobian(x, v, J) == FieldStatus::inside);
      REQUIRE(base->velocity_jacobian(x / l, vb, Jb) == FieldStatus::inside);
      CHECK(v.isApprox(a * vb, 1e-15));
      CHECK(J.isApprox(a / l * Jb, 1e-15));
      Vec3 v2;
      REQUIRE(scaled.velocity(x, v2) == FieldStatus::inside);
      CHECK(v2 == v);
    }
    Vec3 v;
    Mat3 J;
    CHECK(scaled.velocity(scaled.domain().hi, v) == FieldStatus::inside);
    CHECK(scaled.velocity(scaled.domain().lo, v) == FieldStatus::inside);
    CHECK(scaled.velocity(scaled.domain().hi * (1 + 1e-12), v) == FieldStatus::outside);
    CHECK(scaled.velocity_jacobian(scaled.domain().lo * (1 + 1e-12), v, J) == FieldStatus::outside);
  }

  // A = L on a linear field: the same flow in other length units.
  const auto saddle = make_analytic_field("saddle3d");
  const ScaledField same(*saddle, 7, 7);
  const Vec3 x(10, -5, 20);
  CHECK(velocity_of(same, x).isApprox(Vec3(10, 5, 20), 1e-15));

  CHECK_THROWS_AS(ScaledField(*base, 0, 1), InvalidArgument);
  CHECK_THROWS_AS(ScaledField(*base, 1, -1), InvalidArgument);
  CHECK_THROWS_AS(ScaledField(*base, 1, NAN), InvalidArgument);
}
