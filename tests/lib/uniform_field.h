#pragma once
// A steady test field: v = (1, 0, 0) everywhere in [-10, 10]^3, zero Jacobian.
#include <string>

#include "orthofront/field/field.h"

namespace orthofront::test {

class UniformField final : public Field3 {
 public:
  FieldStatus velocity(const Vec3&, Vec3& v) const override {
    v = Vec3(1, 0, 0);
    return FieldStatus::inside;
  }
  FieldStatus velocity_jacobian(const Vec3& x, Vec3& v, Mat3& j) const override {
    j.setZero();
    return velocity(x, v);
  }
  Box<3> domain() const override { return Box<3>{Vec3::Constant(-10), Vec3::Constant(10)}; }
  std::string describe() const override { return "uniform"; }
};

}  // namespace orthofront::test
