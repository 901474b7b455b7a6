#pragma once
/// The seam through which the engine moves a whole front along its stream lines in one call (the
/// front advance): a bulk backend (many particles at once, on a device) plugs in here. Without
/// one, or for fronts smaller than it asks for, the engine integrates each vertex through its
/// Field<N>.
#include <cstddef>
#include <span>

#include "orthofront/integrate/runge_kutta.h"

namespace orthofront {

template <int N>
class FrontIntegrator {
 public:
  virtual ~FrontIntegrator() = default;
  /// Fronts with fewer vertices than this go through the engine's per-vertex integration (where
  /// one call of the backend costs more than it saves).
  virtual std::size_t min_vertices() const = 0;
  /// out[i]: x[i] moved along its stream line by the signed parameter tau[i] (tau[i] = 0: not
  /// moved, status inside), or as far as it got (status outside or no_data). Called from the
  /// engine's thread; each result must not depend on the others. False: declined (the backend
  /// turned out to be unavailable), out untouched; the engine then integrates per vertex.
  virtual bool integrate(std::span<const Vec<N>> x, std::span<const double> tau,
                         std::span<IntegrationResult<N>> out) = 0;
};

/// Every result as "not moved": out[i].x = x[i], inside, nothing reached, no evaluations (what a
/// bulk backend's results start from before its calls fill them).
template <int N>
void set_unmoved(std::span<const Vec<N>> x, std::span<IntegrationResult<N>> out) {
  for (std::size_t i = 0; i < x.size(); ++i) {
    out[i].x = x[i];
    out[i].status = FieldStatus::inside;
    out[i].reached = 0;
    out[i].evaluations = 0;
    out[i].interrupted = false;
  }
}

}  // namespace orthofront
