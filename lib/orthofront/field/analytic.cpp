#include "orthofront/field/analytic.h"

#include <array>
#include <charconv>
#include <cmath>
#include <limits>
#include <numbers>
#include <span>
#include <system_error>
#include <utility>

#include "orthofront/error.h"
#include "orthofront/field/abc_flow.h"
#include "orthofront/field/field_registry.h"
#include "orthofront/field/field_spec.h"

namespace orthofront {
namespace {

constexpr double kPi = std::numbers::pi;

// Each model is a plain struct with velocity(x, v) and velocity_jacobian(x, v, J); the wrapper
// adds the domain check, so the models' formulas stay free of bookkeeping and inline fully.
template <class Model>
class AnalyticField final : public Field3 {
 public:
  AnalyticField(const Model& model, const Box<3>& box, std::string description)
      : model_(model), box_(box), description_(std::move(description)) {}

  FieldStatus velocity(const Vec3& x, Vec3& v) const override {
    if (!box_.contains(x)) return FieldStatus::outside;
    model_.velocity(x, v);
    return FieldStatus::inside;
  }
  FieldStatus velocity_jacobian(const Vec3& x, Vec3& v, Mat3& J) const override {
    if (!box_.contains(x)) return FieldStatus::outside;
    model_.velocity_jacobian(x, v, J);
    return FieldStatus::inside;
  }
  Box<3> domain() const override { return box_; }
  std::string describe() const override { return description_; }

 private:
  Model model_;
  Box<3> box_;
  std::string description_;
};

// --- models ----------------------------------------------------------------------------------

// v = (x, -y, 0): stream lines x y = const.
struct Saddle {
  void velocity(const Vec3& x, Vec3& v) const { v = Vec3(x[0], -x[1], 0.0); }
  void velocity_jacobian(const Vec3& x, Vec3& v, Mat3& J) const {
    velocity(x, v);
    J << 1, 0, 0,  //
        0, -1, 0,  //
        0, 0, 0;
  }
};

// v = (x, -y, z): stream surfaces y z = const.
struct Saddle3d {
  void velocity(const Vec3& x, Vec3& v) const { v = Vec3(x[0], -x[1], x[2]); }
  void velocity_jacobian(const Vec3& x, Vec3& v, Mat3& J) const {
    velocity(x, v);
    J << 1, 0, 0,  //
        0, -1, 0,  //
        0, 0, 1;
  }
};

// v = (amplitude sin(y)^power + slope y, 1, 0).
struct Sinus {
  double amplitude;
  double slope;
  int power;  // >= 1

  // sin(y)^(power - 1) by squaring: exact integer power, cheaper than std::pow.
  double sin_power_minus_one(double s) const {
    double result = 1.0;
    double base = s;
    for (int e = power - 1; e > 0; e >>= 1) {
      if (e & 1) result *= base;
      base *= base;
    }
    return result;
  }
  void velocity(const Vec3& x, Vec3& v) const {
    const double s = std::sin(x[1]);
    v = Vec3(amplitude * sin_power_minus_one(s) * s + slope * x[1], 1.0, 0.0);
  }
  void velocity_jacobian(const Vec3& x, Vec3& v, Mat3& J) const {
    const double s = std::sin(x[1]);
    const double c = std::cos(x[1]);
    const double sp = sin_power_minus_one(s);
    v = Vec3(amplitude * sp * s + slope * x[1], 1.0, 0.0);
    J << 0, amplitude * power * sp * c + slope, 0,  //
        0, 0, 0,                                    //
        0, 0, 0;
  }
};

// v = (-a x - y, x - a y, -b z): a focus spiralling into the z axis, contracting in z.
struct FocusSink {
  double a;
  double b;
  void velocity(const Vec3& x, Vec3& v) const {
    v = Vec3(-a * x[0] - x[1], x[0] - a * x[1], -b * x[2]);
  }
  void velocity_jacobian(const Vec3& x, Vec3& v, Mat3& J) const {
    velocity(x, v);
    J << -a, -1, 0,  //
        1, -a, 0,    //
        0, 0, -b;
  }
};

// sign * (sigma (y - x), x (rho - z) - y, x y - beta z); sign = -1 grows stable manifolds.
struct Lorenz {
  double sigma;
  double rho;
  double beta;
  double sign;
  void velocity(const Vec3& x, Vec3& v) const {
    v = sign * Vec3(sigma * (x[1] - x[0]), x[0] * (rho - x[2]) - x[1], x[0] * x[1] - beta * x[2]);
  }
  void velocity_jacobian(const Vec3& x, Vec3& v, Mat3& J) const {
    velocity(x, v);
    J << -sign * sigma, sign * sigma, 0,           //
        sign * (rho - x[2]), -sign, -sign * x[0],  //
        sign * x[1], sign * x[0], -sign * beta;
  }
};

// u e_x - m (x, y, 0) / (x^2 + y^2 + eps^2): uniform flow plus a regularised point sink.
// Critical points on the x axis solve x^2 - (m/u) x + eps^2 = 0: a stable node near eps^2 u/m
// (the sink) and a saddle at x_s = (m/u + sqrt((m/u)^2 - 4 eps^2)) / 2.
struct Stalling {
  double u;
  double m;
  double eps2;
  void velocity(const Vec3& x, Vec3& v) const {
    const double k = m / (x[0] * x[0] + x[1] * x[1] + eps2);
    v = Vec3(u - k * x[0], -k * x[1], 0.0);
  }
  void velocity_jacobian(const Vec3& x, Vec3& v, Mat3& J) const {
    const double r2 = x[0] * x[0] + x[1] * x[1] + eps2;
    const double k = m / r2;
    const double q = 2.0 * k / r2;
    v = Vec3(u - k * x[0], -k * x[1], 0.0);
    const double xy = q * x[0] * x[1];
    J << q * x[0] * x[0] - k, xy, 0,  //
        xy, q * x[1] * x[1] - k, 0,   //
        0, 0, 0;
  }
};

// diag(l1, l2, l3) x: with l1, l2 > 0 > l3 a repelling node saddle (2D unstable manifold z = 0
// is a node, 1D stable manifold is the z axis).
struct Diagonal {
  Vec3 lambda;
  void velocity(const Vec3& x, Vec3& v) const { v = lambda.cwiseProduct(x); }
  void velocity_jacobian(const Vec3& x, Vec3& v, Mat3& J) const {
    velocity(x, v);
    J << lambda[0], 0, 0,  //
        0, lambda[1], 0,   //
        0, 0, lambda[2];
  }
};

// --- registry --------------------------------------------------------------------------------

using Kind = ParameterKind;

using FieldSpec = FieldEntry<Field3>;

template <class Model>
std::unique_ptr<Field3> wrap(const Model& model, const Box<3>& box, std::string description) {
  return std::make_unique<AnalyticField<Model>>(model, box, std::move(description));
}

double stalling_saddle_x(double u, double m, double eps) {
  const double l = m / u;
  return 0.5 * (l + std::sqrt(l * l - 4.0 * eps * eps));
}

const std::vector<FieldSpec>& registry() {
  static const std::vector<FieldSpec> fields = {
      {"saddle",
       "v = (x, -y, 0); planar saddle at the origin, stream lines x y = const",
       "[-3,3] x [-3,3] x [-1,1]",
       {},
       [](std::span<const double>, std::string d) {
         return wrap(Saddle{}, make_box(-3, 3, -3, 3, -1, 1), std::move(d));
       }},
      {"saddle3d",
       "v = (x, -y, z); 3D saddle at the origin, stream surfaces y z = const",
       "[-4,4]^3",
       {},
       [](std::span<const double>, std::string d) {
         return wrap(Saddle3d{}, make_box(-4, 4, -4, 4, -4, 4), std::move(d));
       }},
      {"sinus",
       "v = (amplitude sin(y)^power + slope y, 1, 0)",
       "[-10,10] x [-1,12] x [-1,1]",
       {{"amplitude", 5, "factor of sin(y)^power"},
        {"power", 7, "integer exponent of sin(y), 1 to 1000", Kind::integer, 1, 1000},
        {"slope", 1, "coefficient of y in v_x"}},
       [](std::span<const double> p, std::string d) {
         return wrap(Sinus{p[0], p[2], static_cast<int>(p[1])}, make_box(-10, 10, -1, 12, -1, 1),
                     std::move(d));
       }},
      {"focus-sink",
       "v = (-a x - y, x - a y, -b z); spiral sink at the origin",
       "[-4,4]^3",
       {{"a", 0.15, "radial decay rate in the x-y plane"}, {"b", 0.3, "decay rate along z"}},
       [](std::span<const double> p, std::string d) {
         return wrap(FocusSink{p[0], p[1]}, make_box(-4, 4, -4, 4, -4, 4), std::move(d));
       }},
      {"lorenz",
       "v = s (sigma (y - x), x (rho - z) - y, x y - beta z), s = -1 if reverse else 1",
       "[-80,80] x [-80,80] x [-60,120]",
       {{"sigma", 10, "Prandtl number"},
        {"rho", 28, "Rayleigh number"},
        {"beta", 8.0 / 3.0, "geometric factor"},
        {"reverse", 0, "1: negate v (grows the stable manifold of the origin)", Kind::flag}},
       [](std::span<const double> p, std::string d) {
         return wrap(Lorenz{p[0], p[1], p[2], p[3] != 0 ? -1.0 : 1.0},
                     make_box(-80, 80, -80, 80, -60, 120), std::move(d));
       }},
      {"stalling",
       "v = (u, 0, 0) - m (x, y, 0) / (x^2 + y^2 + eps^2); uniform flow into a regularised sink "
       "(stable node near x = eps^2 u/m), saddle at (x_s, 0), x_s = (L + sqrt(L^2 - 4 eps^2))/2, "
       "L = m/u; needs L > 2 eps",
       "[-3L, x_s] x [-2L, 2L] x [-1,1], saddle on the right boundary (x_s = 0.989898 for the "
       "defaults)",
       {{"u", 1, "speed of the uniform flow", Kind::positive},
        {"m", 1, "strength of the sink", Kind::positive},
        {"eps", 0.1, "regularisation radius of the sink", Kind::positive}},
       [](std::span<const double> p, std::string d) {
         const double u = p[0], m = p[1], eps = p[2];
         if (!(m / u > 2.0 * eps)) {
           throw InvalidArgument("analytic field 'stalling': m/u = " + format_parameter(m / u) +
                                 " must exceed 2 eps = " + format_parameter(2.0 * eps) +
                                 ", otherwise there is no saddle");
         }
         const double l = m / u;
         return wrap(Stalling{u, m, eps * eps},
                     make_box(-3 * l, stalling_saddle_x(u, m, eps), -2 * l, 2 * l, -1, 1),
                     std::move(d));
       }},
      {"repelling-node-saddle",
       "v = (l1 x, l2 y, l3 z); l1, l2 > 0 > l3: repelling node saddle at the origin (unstable "
       "node in the plane z = 0, stable direction along z)",
       "[-3,3]^3",
       {{"l1", 1, "eigenvalue along x"},
        {"l2", 2, "eigenvalue along y"},
        {"l3", -1, "eigenvalue along z"}},
       [](std::span<const double> p, std::string d) {
         return wrap(Diagonal{Vec3(p[0], p[1], p[2])}, make_box(-3, 3, -3, 3, -3, 3), std::move(d));
       }},
      {"abc",
       "v = (a sin z + c cos y, b sin x + a cos z, c sin y + b cos x); ABC flow",
       "[-2pi, 4pi]^3 (three periods per axis)",
       {{"a", std::sqrt(3.0), "coefficient A"},
        {"b", std::sqrt(2.0), "coefficient B"},
        {"c", 1, "coefficient C"}},
       [](std::span<const double> p, std::string d) {
         return wrap(AbcFlow{p[0], p[1], p[2]},
                     make_box(-2 * kPi, 4 * kPi, -2 * kPi, 4 * kPi, -2 * kPi, 4 * kPi),
                     std::move(d));
       }},
  };
  return fields;
}

}  // namespace

const std::vector<AnalyticFieldInfo>& analytic_fields() {
  static const std::vector<AnalyticFieldInfo> infos = describe_fields(registry());
  return infos;
}

std::unique_ptr<Field3> make_analytic_field(std::string_view spec) {
  return make_field(registry(), spec, "analytic field", "known fields");
}

}  // namespace orthofront
