#pragma once
/// The Arnold-Beltrami-Childress flow: the steady analytic field `abc` and, with its first
/// coefficient varying in time, `unsteady-abc` evaluate the same formulas.
#include <cmath>

#include "orthofront/types.h"

namespace orthofront {

struct AbcFlow {
  double a;
  double b;
  double c;
  void velocity(const Vec3& x, Vec3& v) const {
    v = Vec3(a * std::sin(x[2]) + c * std::cos(x[1]), b * std::sin(x[0]) + a * std::cos(x[2]),
             c * std::sin(x[1]) + b * std::cos(x[0]));
  }
  void velocity_jacobian(const Vec3& x, Vec3& v, Mat3& J) const {
    const double sx = std::sin(x[0]), cx = std::cos(x[0]);
    const double sy = std::sin(x[1]), cy = std::cos(x[1]);
    const double sz = std::sin(x[2]), cz = std::cos(x[2]);
    v = Vec3(a * sz + c * cy, b * sx + a * cz, c * sy + b * cx);
    J << 0, -c * sy, a * cz,  //
        b * cx, 0, -a * sz,   //
        -b * sx, c * cy, 0;
  }
};

}  // namespace orthofront
