#include "orthofront/field/unsteady.h"

#include <array>
#include <charconv>
#include <cmath>
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

// Each model is a plain struct with velocity(x, t, v) and velocity_jacobian(x, t, v, J, dvdt);
// the wrapper adds the domain and time checks.
template <class Model>
class AnalyticUnsteadyField final : public UnsteadyField {
 public:
  AnalyticUnsteadyField(const Model& model, int dimension, const Box<3>& box, TimeRange times,
                        std::string description)
      : model_(model),
        dimension_(dimension),
        box_(box),
        times_(times),
        description_(std::move(description)) {}

  int dimension() const override { return dimension_; }
  FieldStatus velocity(const Vec3& x, double t, Vec3& v) const override {
    if (!inside(x, t)) return FieldStatus::outside;
    model_.velocity(x, t, v);
    return FieldStatus::inside;
  }
  FieldStatus velocity_jacobian(const Vec3& x, double t, Vec3& v, Mat3& J,
                                Vec3& dvdt) const override {
    if (!inside(x, t)) return FieldStatus::outside;
    model_.velocity_jacobian(x, t, v, J, dvdt);
    return FieldStatus::inside;
  }
  Box<3> domain() const override { return box_; }
  TimeRange time_range() const override { return times_; }
  std::string describe() const override { return description_; }
  bool exact_flow_map(const Vec3& x0, double t0, double t, Vec3& x) const override {
    if constexpr (requires { model_.flow_map(x0, t0, t, x); }) {
      model_.flow_map(x0, t0, t, x);
      return true;
    } else {
      return false;
    }
  }

 private:
  bool inside(const Vec3& x, double t) const {
    if (!times_.contains(t)) return false;
    for (int a = 0; a < dimension_; ++a)
      if (!(x[a] >= box_.lo[a] && x[a] <= box_.hi[a])) return false;
    return true;
  }

  Model model_;
  int dimension_;
  Box<3> box_;
  TimeRange times_;
  std::string description_;
};

// --- models ----------------------------------------------------------------------------------

// Shadden et al. (2005): ψ = A sin(π f(x, t)) sin(π y), f = a(t) x² + b(t) x,
// a = ε sin ωt, b = 1 - 2ε sin ωt; u = -∂ψ/∂y, v = ∂ψ/∂x. Optional third component (the 3D
// extension): w = B sin(π z) cos(π y) cos(ω t), which vanishes on z = 0 and z = 1, so the slab
// [0, 2] x [0, 1] x [0, 1] stays invariant while particles move up and down between the gyres.
struct DoubleGyre {
  double A;
  double eps;
  double omega;
  double B;  // 0 for the 2D field
  bool three_d;

  void velocity(const Vec3& x, double t, Vec3& v) const {
    const double s = std::sin(omega * t);
    const double a = eps * s, b = 1.0 - 2.0 * eps * s;
    const double f = (a * x[0] + b) * x[0];
    const double fx = 2.0 * a * x[0] + b;
    const double sy = std::sin(kPi * x[1]), cy = std::cos(kPi * x[1]);
    v[0] = -kPi * A * std::sin(kPi * f) * cy;
    v[1] = kPi * A * std::cos(kPi * f) * sy * fx;
    v[2] = three_d ? B * std::sin(kPi * x[2]) * cy * std::cos(omega * t) : 0.0;
  }
  void velocity_jacobian(const Vec3& x, double t, Vec3& v, Mat3& J, Vec3& dvdt) const {
    const double s = std::sin(omega * t), co = std::cos(omega * t);
    const double a = eps * s, b = 1.0 - 2.0 * eps * s;
    const double at = eps * omega * co, bt = -2.0 * eps * omega * co;
    const double f = (a * x[0] + b) * x[0];
    const double fx = 2.0 * a * x[0] + b;
    const double ft = (at * x[0] + bt) * x[0];
    const double fxt = 2.0 * at * x[0] + bt;
    const double sf = std::sin(kPi * f), cf = std::cos(kPi * f);
    const double sy = std::sin(kPi * x[1]), cy = std::cos(kPi * x[1]);
    const double pa = kPi * A, ppa = kPi * kPi * A;
    v[0] = -pa * sf * cy;
    v[1] = pa * cf * sy * fx;
    J.setZero();
    J(0, 0) = -ppa * cf * fx * cy;
    J(0, 1) = ppa * sf * sy;
    J(1, 0) = pa * sy * (-kPi * sf * fx * fx + cf * 2.0 * a);
    J(1, 1) = ppa * cf * cy * fx;
    dvdt[0] = -ppa * cf * ft * cy;
    dvdt[1] = pa * sy * (-kPi * sf * ft * fx + cf * fxt);
    v[2] = 0;
    dvdt[2] = 0;
    if (three_d) {
      const double sz = std::sin(kPi * x[2]), cz = std::cos(kPi * x[2]);
      v[2] = B * sz * cy * co;
      J(2, 1) = -B * kPi * sz * sy * co;
      J(2, 2) = B * kPi * cz * cy * co;
      dvdt[2] = -B * omega * sz * cy * s;
    }
  }
};

// ABC flow with a time-dependent first coefficient (as in the unsteady-ABC literature):
// a(t) = a0 + amp (1 - e^{-decay t}) sin(ω t).
struct UnsteadyAbc {
  double a0, b, c, amp, decay, omega;

  double coefficient(double t) const {
    return a0 + amp * (1.0 - std::exp(-decay * t)) * std::sin(omega * t);
  }
  double coefficient_rate(double t) const {
    const double e = std::exp(-decay * t);
    return amp * (decay * e * std::sin(omega * t) + (1.0 - e) * omega * std::cos(omega * t));
  }
  void velocity(const Vec3& x, double t, Vec3& v) const {
    AbcFlow{coefficient(t), b, c}.velocity(x, v);
  }
  void velocity_jacobian(const Vec3& x, double t, Vec3& v, Mat3& J, Vec3& dvdt) const {
    AbcFlow{coefficient(t), b, c}.velocity_jacobian(x, v, J);
    const double at = coefficient_rate(t);
    dvdt = Vec3(at * std::sin(x[2]), at * std::cos(x[2]), 0.0);
  }
};

// v = g(t) M (x - c(t)) + c'(t): a spiral (rate σ in the plane, -λ along z) around a centre that
// circles the origin, c(t) = r (cos νt, sin νt, 0), with a pulsating rate g(t) = 1 + β sin ωt.
// With y = x - c(t): y' = g M y, so y(t) = exp(M (G(t) - G(t0))) y(t0), G(t) = ∫_0^t g: the path
// lines are known in closed form. Path lines differ from stream lines (the centre moves).
struct MovingSpiral {
  double sigma, lambda, beta, omega, r, nu;
  bool three_d;

  Vec3 centre(double t) const { return Vec3(r * std::cos(nu * t), r * std::sin(nu * t), 0.0); }
  Vec3 centre_rate(double t) const {
    return Vec3(-r * nu * std::sin(nu * t), r * nu * std::cos(nu * t), 0.0);
  }
  Vec3 centre_acceleration(double t) const {
    return Vec3(-r * nu * nu * std::cos(nu * t), -r * nu * nu * std::sin(nu * t), 0.0);
  }
  double rate(double t) const { return 1.0 + beta * std::sin(omega * t); }
  double rate_integral(double t) const { return t - beta / omega * (std::cos(omega * t) - 1.0); }
  Mat3 matrix() const {
    Mat3 M;
    M << sigma, -1, 0,  //
        1, sigma, 0,    //
        0, 0, three_d ? -lambda : 0.0;
    return M;
  }
  void velocity(const Vec3& x, double t, Vec3& v) const {
    v = rate(t) * (matrix() * (x - centre(t))) + centre_rate(t);
    if (!three_d) v[2] = 0;
  }
  void velocity_jacobian(const Vec3& x, double t, Vec3& v, Mat3& J, Vec3& dvdt) const {
    const Mat3 M = matrix();
    const double g = rate(t);
    const Vec3 y = x - centre(t);
    v = g * (M * y) + centre_rate(t);
    J = g * M;
    const double gt = beta * omega * std::cos(omega * t);
    dvdt = gt * (M * y) - g * (M * centre_rate(t)) + centre_acceleration(t);
    if (!three_d) v[2] = dvdt[2] = 0;
  }
  void flow_map(const Vec3& x0, double t0, double t, Vec3& x) const {
    const double dg = rate_integral(t) - rate_integral(t0);
    const Vec3 y0 = x0 - centre(t0);
    const double grow = std::exp(sigma * dg);
    const double cs = std::cos(dg), sn = std::sin(dg);
    Vec3 y(grow * (cs * y0[0] - sn * y0[1]), grow * (sn * y0[0] + cs * y0[1]),
           three_d ? std::exp(-lambda * dg) * y0[2] : x0[2] - centre(t0)[2]);
    x = centre(t) + y;
  }
};

// --- registry (the spec syntax of make_analytic_field) ----------------------------------------

using Kind = ParameterKind;

using FieldSpec = FieldEntry<UnsteadyField>;

template <class Model>
std::unique_ptr<UnsteadyField> wrap(const Model& model, int dimension, const Box<3>& box,
                                    TimeRange times, std::string description) {
  return std::make_unique<AnalyticUnsteadyField<Model>>(model, dimension, box, times,
                                                        std::move(description));
}

const std::vector<FieldSpec>& registry() {
  static const std::vector<FieldSpec> fields = {
      {"double-gyre",
       "2D: psi = A sin(pi f) sin(pi y), f = a(t) x^2 + b(t) x, a = eps sin(omega t), "
       "b = 1 - 2 eps sin(omega t); u = -dpsi/dy, v = dpsi/dx",
       "[0,2] x [0,1], all t",
       {{"A", 0.1, "amplitude"},
        {"eps", 0.25, "amplitude of the gyres' oscillation"},
        {"omega", 2 * kPi / 10, "angular frequency (period 10)"}},
       [](std::span<const double> p, std::string d) {
         return wrap(DoubleGyre{p[0], p[1], p[2], 0.0, false}, 2, make_box(0, 2, 0, 1, -1, 1),
                     TimeRange{}, std::move(d));
       }},
      {"double-gyre-3d",
       "3D: (u, v) of the double gyre, w = B sin(pi z) cos(pi y) cos(omega t) (w = 0 on z = 0 "
       "and z = 1: the slab is invariant)",
       "[0,2] x [0,1] x [0,1], all t",
       {{"A", 0.1, "amplitude"},
        {"eps", 0.25, "amplitude of the gyres' oscillation"},
        {"omega", 2 * kPi / 10, "angular frequency (period 10)"},
        {"B", 0.1, "amplitude of the vertical component"}},
       [](std::span<const double> p, std::string d) {
         return wrap(DoubleGyre{p[0], p[1], p[2], p[3], true}, 3, make_box(0, 2, 0, 1, 0, 1),
                     TimeRange{}, std::move(d));
       }},
      {"unsteady-abc",
       "ABC flow with a(t) = a + amp (1 - exp(-decay t)) sin(omega t): "
       "(a(t) sin z + c cos y, b sin x + a(t) cos z, c sin y + b cos x)",
       "[-2pi, 4pi]^3, t >= 0",
       {{"a", std::sqrt(3.0), "base of the coefficient A(t)"},
        {"b", std::sqrt(2.0), "coefficient B"},
        {"c", 1, "coefficient C"},
        {"amp", 1, "amplitude of the oscillation of A(t)"},
        {"decay", 0.1, "rate at which the oscillation switches on", Kind::positive},
        {"omega", 1, "angular frequency of A(t)"}},
       [](std::span<const double> p, std::string d) {
         return wrap(UnsteadyAbc{p[0], p[1], p[2], p[3], p[4], p[5]}, 3,
                     make_box(-2 * kPi, 4 * kPi, -2 * kPi, 4 * kPi, -2 * kPi, 4 * kPi),
                     TimeRange{0.0, std::numeric_limits<double>::infinity()}, std::move(d));
       }},
      {"moving-spiral",
       "v = g(t) M (x - c(t)) + c'(t), M = [[sigma,-1,0],[1,sigma,0],[0,0,-lambda]], "
       "g = 1 + beta sin(omega t), c(t) = r (cos nu t, sin nu t, 0); path lines in closed form: "
       "x(t) = c(t) + exp(M (G(t) - G(t0))) (x0 - c(t0)), G = integral of g",
       "[-4,4]^3 ([-4,4]^2 for dim=2), all t",
       {{"sigma", -0.1, "radial rate in the x-y plane (< 0: spiral in)"},
        {"lambda", 0.2, "decay rate along z (dim=3)"},
        {"beta", 0.5, "amplitude of the rate's pulsation"},
        {"omega", 1, "angular frequency of the pulsation", Kind::positive},
        {"r", 0.5, "radius of the centre's circle"},
        {"nu", 0.5, "angular speed of the centre"},
        {"dim", 3, "spatial dimension, 2 or 3", Kind::integer, 2, 3}},
       [](std::span<const double> p, std::string d) {
         const bool three_d = p[6] == 3;
         return wrap(MovingSpiral{p[0], p[1], p[2], p[3], p[4], p[5], three_d}, three_d ? 3 : 2,
                     make_box(-4, 4, -4, 4, -4, 4), TimeRange{}, std::move(d));
       }},
  };
  return fields;
}


}  // namespace

const std::vector<AnalyticFieldInfo>& unsteady_fields() {
  static const std::vector<AnalyticFieldInfo> infos = describe_fields(registry());
  return infos;
}

bool is_unsteady_field_name(std::string_view spec) {
  return find_field(registry(), field_spec_name(spec)) != nullptr;
}

std::unique_ptr<UnsteadyField> make_unsteady_field(std::string_view spec) {
  return make_field(registry(), spec, "unsteady field", "known unsteady fields");
}

}  // namespace orthofront
