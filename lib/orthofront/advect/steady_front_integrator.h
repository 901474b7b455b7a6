#pragma once
/// The front advance of a stream surface of a gridded steady field by bulk advection: the
/// front's vertices move as particles through the grid, all in one call of an advect::
/// BatchAdvector (CPU or CUDA). The grid is a series of two equal steps spanning every time a
/// front reaches, so a sample is the grid's multilinear value (the time weight is 1/2 to the last
/// bit). Plugs into the engine at its FrontIntegrator seam.
#include <cstddef>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "orthofront/advect/batch_advector.h"
#include "orthofront/engine/front_integrator.h"
#include "orthofront/engine/options.h"
#include "orthofront/field/grid_field.h"

namespace orthofront::advect {

/// The bulk method that matches the engine's per-vertex integration of a front step: RK4 with the
/// engine's substeps of a step spanning ℓ / time_scale in time, or DOPRI5 with its tolerances.
MethodOptions front_method(const StreamSurfaceOptions& engine, double time_scale = 1);

/// The grid of a GridField as a StepSource of two equal steps at times ±kSteadyHorizon.
class SteadySteps final : public StepSource {
 public:
  static constexpr double kSteadyHorizon = 1e30;
  /// Non-owning: `field` must outlive it.
  explicit SteadySteps(const GridField& field);
  const GridGeometry& geometry() const override { return field_.grid().geometry; }
  int components() const override { return field_.grid().components; }
  bool zero_is_no_data() const override { return field_.options().zero_is_no_data; }
  const std::vector<double>& times() const override { return times_; }
  const float* acquire(std::size_t) override { return field_.grid().values.data(); }
  void release(std::size_t) override {}

 private:
  const GridField& field_;
  std::vector<double> times_{-kSteadyHorizon, kSteadyHorizon};
};

/// Makes the backend when the first large enough front comes; nullptr: none (per vertex).
using SteadyBackendFactory = std::function<std::shared_ptr<BatchAdvector>()>;

class SteadyFrontIntegrator final : public FrontIntegrator<3> {
 public:
  /// Non-owning: `field` must outlive it. Fronts below `min_vertices` stay per vertex.
  SteadyFrontIntegrator(const GridField& field, SteadyBackendFactory make_backend,
                        MethodOptions method, std::size_t min_vertices);
  std::size_t min_vertices() const override { return min_vertices_; }
  bool integrate(std::span<const Vec<3>> x, std::span<const double> tau,
                 std::span<IntegrationResult<3>> out) override;
  std::string backend_name() const { return backend_ ? backend_->name() : std::string(); }
  const AdvectionStatistics& statistics() const { return total_; }
  std::size_t calls() const { return calls_; }

 private:
  void run(std::span<const Vec<3>> x, std::span<const double> tau,
           std::span<IntegrationResult<3>> out, bool forward);

  SteadySteps steps_;
  SteadyBackendFactory make_backend_;
  std::shared_ptr<BatchAdvector> backend_;
  MethodOptions method_;
  std::size_t min_vertices_;
  ParticleBatch batch_;
  std::vector<std::size_t> index_;
  AdvectionStatistics total_;
  std::size_t calls_ = 0;
};

}  // namespace orthofront::advect
