#include "orthofront/advect/steady_front_integrator.h"

#include <algorithm>
#include <limits>

namespace orthofront::advect {

MethodOptions front_method(const StreamSurfaceOptions& engine, double time_scale) {
  MethodOptions method;
  if (engine.integrator == IntegratorKind::rk4) {
    method.method = Method::rk4;
    method.rk4_step = engine.edge / time_scale / std::max(engine.rk4_substeps, 1);
  } else {
    method.method = Method::dopri5;
    method.absolute = engine.tolerance * engine.edge;
    method.relative = engine.tolerance;
  }
  return method;
}

SteadySteps::SteadySteps(const GridField& field) : field_(field) {}

SteadyFrontIntegrator::SteadyFrontIntegrator(const GridField& field,
                                             SteadyBackendFactory make_backend,
                                             MethodOptions method, std::size_t min_vertices)
    : steps_(field), make_backend_(std::move(make_backend)), method_(method),
      min_vertices_(min_vertices) {
  check_method(method_);
}

bool SteadyFrontIntegrator::integrate(std::span<const Vec<3>> x, std::span<const double> tau,
                                      std::span<IntegrationResult<3>> out) {
  if (!backend_ && make_backend_) {
    backend_ = make_backend_();
    make_backend_ = nullptr;  // asked once
    if (!backend_) min_vertices_ = std::numeric_limits<std::size_t>::max();
  }
  if (!backend_) return false;
  set_unmoved<3>(x, out);
  run(x, tau, out, true);
  run(x, tau, out, false);
  return true;
}

// Every particle starts at t = 0 and stops at its own τ: a steady field does not care when.
void SteadyFrontIntegrator::run(std::span<const Vec<3>> x, std::span<const double> tau,
                                std::span<IntegrationResult<3>> out, bool forward) {
  index_.clear();
  for (std::size_t i = 0; i < x.size(); ++i)
    if (forward ? tau[i] > 0 : tau[i] < 0) index_.push_back(i);
  if (index_.empty()) return;
  const std::size_t n = index_.size();
  batch_.stop.clear();
  batch_.resize(n);
  batch_.stop.resize(n);
  double horizon = 0;
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t i = index_[k];
    for (int a = 0; a < 3; ++a) batch_.x[static_cast<std::size_t>(a)][k] = x[i][a];
    batch_.t[k] = 0;
    batch_.h[k] = 0;
    batch_.evaluations[k] = 0;
    batch_.status[k] = ParticleStatus::moving;
    batch_.stop[k] = std::clamp(tau[i], -SteadySteps::kSteadyHorizon, SteadySteps::kSteadyHorizon);
    horizon = forward ? std::max(horizon, batch_.stop[k]) : std::min(horizon, batch_.stop[k]);
  }
  total_ += backend_->advect(steps_, batch_, horizon, method_);
  ++calls_;
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t i = index_[k];
    IntegrationResult<3>& r = out[i];
    for (int a = 0; a < 3; ++a) r.x[a] = batch_.x[static_cast<std::size_t>(a)][k];
    r.evaluations = static_cast<int>(std::min<std::uint32_t>(
        batch_.evaluations[k], static_cast<std::uint32_t>(std::numeric_limits<int>::max())));
    const ParticleStatus st = batch_.status[k];
    r.status = st == ParticleStatus::moving    ? FieldStatus::inside
               : st == ParticleStatus::no_data ? FieldStatus::no_data
                                               : FieldStatus::outside;
    r.reached = st == ParticleStatus::moving ? tau[i] : batch_.t[k];
  }
}

}  // namespace orthofront::advect
