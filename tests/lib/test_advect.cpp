// The advect stage on hand-made fronts: which vertices have usable flow, and every vertex moved
// by its own α-time along its stream line, per vertex or through a bulk backend.
#include <atomic>
#include <catch2/catch.hpp>
#include <cmath>
#include <span>
#include <string>
#include <vector>

#include "lib/uniform_field.h"
#include "orthofront/engine/advect.h"

using namespace orthofront;

namespace {

/// v = (1, 0, 0) where x < 1; no flow (zero) for x in [1, 2); outside the domain past x = 5.
class StepField final : public Field3 {
 public:
  FieldStatus velocity(const Vec3& x, Vec3& v) const override {
    if (!domain().contains(x)) return FieldStatus::outside;
    v = x.x() < 1 || x.x() >= 2 ? Vec3(1, 0, 0) : Vec3::Zero();
    return FieldStatus::inside;
  }
  FieldStatus velocity_jacobian(const Vec3& x, Vec3& v, Mat3& j) const override {
    j.setZero();
    return velocity(x, v);
  }
  Box<3> domain() const override { return Box<3>{Vec3(-5, -5, -5), Vec3(5, 5, 5)}; }
  std::string describe() const override { return "step"; }
};

Front<3> front_at(const std::vector<Vec3>& points) {
  Front<3> f;
  for (const Vec3& p : points) {
    FrontVertex<3> fv;
    fv.x = fv.anchor = p;
    fv.t = 0.25;
    f.v.push_back(fv);
  }
  return f;
}

/// A bulk backend that moves each point by tau along +x, counting its calls; declines when told.
class ShiftIntegrator final : public FrontIntegrator<3> {
 public:
  explicit ShiftIntegrator(bool decline) : decline_(decline) {}
  std::size_t min_vertices() const override { return 3; }
  bool integrate(std::span<const Vec3> x, std::span<const double> tau,
                 std::span<IntegrationResult<3>> out) override {
    ++calls;
    if (decline_) return false;
    set_unmoved<3>(x, out);
    for (std::size_t i = 0; i < x.size(); ++i) {
      out[i].x = x[i] + Vec3(tau[i], 0, 0);
      out[i].reached = tau[i];
      out[i].evaluations = 1;
    }
    return true;
  }
  int calls = 0;

 private:
  bool decline_;
};

struct Stage {
  StreamSurfaceOptions options;
  Tolerance tolerance{1e-9, 1e-9};
  StopRequest stop;
  std::atomic<bool> stopping{false};
  SurfaceReport report;
};

}  // namespace

TEST_CASE("sampling marks the vertices without usable flow", "[engine][advect]") {
  const StepField field;
  Stage s;
  FrontAdvect<3> advect(field, s.options, s.tolerance, s.stop, s.stopping, s.report);
  SECTION("flow everywhere") {
    const Front<3> f = front_at({Vec3(0, 0, 0), Vec3(0, 1, 0), Vec3(3, 0, 0)});
    std::vector<char> keep(3, 1);
    std::size_t exits = 0;
    CHECK(advect.sample(f, keep, exits));
    CHECK(keep == std::vector<char>{1, 1, 1});
    CHECK(advect.velocities()[2] == Vec3(1, 0, 0));
    CHECK(advect.speeds() == std::vector<double>{1, 1, 1});
    CHECK(s.report.field_evaluations == 3);
  }
  SECTION("outside the domain, and no flow") {
    const Front<3> f =
        front_at({Vec3(0, 0, 0), Vec3(1.5, 0, 0), Vec3(0, 1, 0), Vec3(6, 0, 0), Vec3(3, 0, 0)});
    std::vector<char> keep(5, 1);
    std::size_t exits = 0;
    CHECK_FALSE(advect.sample(f, keep, exits));
    CHECK(keep == std::vector<char>{1, 0, 1, 0, 1});
    CHECK(advect.state(1) == VertexState::zero_speed);
    CHECK(advect.state(3) == VertexState::outside);
    CHECK(exits == 1);
    CHECK(s.report.domain_exits == 1);
    CHECK(s.report.zero_velocity_cuts == 1);
  }
}

TEST_CASE("advancing moves each vertex by its own alpha-time", "[engine][advect]") {
  const test::UniformField field;
  Stage s;
  FrontAdvect<3> advect(field, s.options, s.tolerance, s.stop, s.stopping, s.report);
  const Front<3> f = front_at({Vec3(0, 0, 0), Vec3(0, 1, 0), Vec3(0, 2, 0), Vec3(0, 3, 0)});
  const std::vector<double> alpha{1.0, 0.5, 0.0, 2.0};
  const double h = 0.1;
  const auto check_moved = [&](const Front<3>& moved) {
    REQUIRE(moved.v.size() == 4);
    for (std::size_t i = 0; i < 4; ++i) {
      CHECK(std::abs(moved.v[i].x.x() - alpha[i] * h) < 1e-12);
      CHECK(moved.v[i].x.y() == f.v[i].x.y());
      CHECK(std::abs(moved.v[i].t - (0.25 + alpha[i] * h)) < 1e-12);
      CHECK(moved.v[i].origin == static_cast<std::int32_t>(i));
      CHECK(moved.v[i].anchor == f.v[i].anchor);  // the mesh vertex it stands on is the old one
    }
  };
  SECTION("per vertex") {
    std::vector<char> keep(4, 1);
    std::size_t exits = 0;
    check_moved(advect.advance(f, alpha, h, keep, exits, {}));
    CHECK(keep == std::vector<char>(4, 1));
    CHECK(s.report.vertex_steps == 4);
  }
  SECTION("through a bulk backend, and per vertex where it declines") {
    for (const bool decline : {false, true}) {
      ShiftIntegrator bulk(decline);
      advect.set_front_integrator(&bulk);
      std::vector<char> keep(4, 1);
      std::size_t exits = 0;
      check_moved(advect.advance(f, alpha, h, keep, exits, {}));
      CHECK(bulk.calls == 1);
      CHECK(keep == std::vector<char>(4, 1));
    }
  }
  SECTION("a stream line that leaves the domain ends at its edge") {
    const StepField bounded;  // its domain ends at x = 5
    FrontAdvect<3> at_edge(bounded, s.options, s.tolerance, s.stop, s.stopping, s.report);
    const Front<3> near_edge = front_at({Vec3(4.9, 0, 0), Vec3(4.9, 1, 0)});
    std::vector<char> keep(2, 1);
    std::size_t exits = 0;
    const Front<3> moved = at_edge.advance(near_edge, {1.0, 0.01}, 1.0, keep, exits, {});
    CHECK(keep == std::vector<char>{0, 1});
    CHECK(exits == 1);
    CHECK(s.report.domain_exits == 1);
    CHECK(moved.v[0].x.x() <= 5.0);
    CHECK(moved.v[0].x.x() > 4.9);
    CHECK(std::abs(moved.v[1].x.x() - 4.91) < 1e-12);
  }
  SECTION("a run that stops leaves every vertex where it was") {
    s.stopping = true;
    std::vector<char> keep(4, 1);
    std::size_t exits = 0;
    const Front<3> moved = advect.advance(f, alpha, h, keep, exits, {});
    CHECK(keep == std::vector<char>(4, 0));
    for (std::size_t i = 0; i < 4; ++i) CHECK(moved.v[i].x == f.v[i].x);
  }
}
