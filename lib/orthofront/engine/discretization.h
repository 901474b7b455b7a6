#pragma once
/// How the front's vertices advance in one step, chosen once by StreamSurfaceOptions::method: the
/// flow-orthogonal front lines, or the paper's timeline baseline (every vertex the same time step
/// along its stream line). The engine's driver asks it for α and the step; what it allows beyond
/// the paper's method (rips, row skipping, the fold guard, the stall cut, gap closing) it says
/// once, so the driver has no branches on the method.
#include <memory>
#include <vector>

#include "orthofront/engine/alpha_step.h"
#include "orthofront/engine/front.h"

namespace orthofront {

template <int N>
class Discretization {
 public:
  /// Counts go to `report`, per-step figures to `record`, vertex errors to `mesh` (all owned by
  /// the engine and outliving this).
  Discretization(const Field<N>& field, const StreamSurfaceOptions& options, Mesh& mesh,
                 SurfaceReport& report, StepRecord& record)
      : field_(field), opt_(options), report_(report), alpha_step_(field, options, mesh, report, record) {}
  virtual ~Discretization() = default;
  Discretization(const Discretization&) = delete;
  Discretization& operator=(const Discretization&) = delete;

  /// Called once with the seed's fronts.
  virtual void begin(const std::vector<Front<N>>& fronts) = 0;

  /// α per vertex into `alpha` (sized to the front and filled with 1 by the caller) from the
  /// velocities `vel` and speeds `speed` at the front's vertices; false when the segments it
  /// marked in `cut` must be cut first. `terms`, `solution`: the α system's terms and solution
  /// taken already (samples_ahead.h), traded for the discretization's own scratch; null:
  /// computed here.
  virtual bool alpha(Front<N>& f, std::vector<Vec<N>>& vel, std::vector<double>& speed,
                     std::vector<double>& alpha, std::vector<char>& cut, SegmentTerms<N>* terms,
                     AlphaSolution* solution) = 0;

  /// The front step h in α-time once α is final; negative when no vertex moves.
  virtual double step(const Front<N>& f, std::vector<double>& alpha,
                      const std::vector<double>& speed) = 0;

  /// Whether the project's safeguards apply: rips, row skipping, the fold guard, the stall cut
  /// and gap closing (the timeline baseline is kept as the paper has it).
  virtual bool safeguarded() const = 0;

  /// The step's orthogonality tally (StepRecord::orthogonality_mean).
  void begin_step() { alpha_step_.begin_step(); }
  double orthogonality_mean() const { return alpha_step_.orthogonality_mean(); }

 protected:
  const Field<N>& field_;
  const StreamSurfaceOptions& opt_;
  SurfaceReport& report_;
  AlphaStep<N> alpha_step_;
};

/// The discretization StreamSurfaceOptions::method names.
template <int N>
std::unique_ptr<Discretization<N>> make_discretization(const Field<N>& field,
                                                       const StreamSurfaceOptions& options,
                                                       Mesh& mesh, SurfaceReport& report,
                                                       StepRecord& record);

extern template std::unique_ptr<Discretization<3>> make_discretization(
    const Field<3>&, const StreamSurfaceOptions&, Mesh&, SurfaceReport&, StepRecord&);
extern template std::unique_ptr<Discretization<4>> make_discretization(
    const Field<4>&, const StreamSurfaceOptions&, Mesh&, SurfaceReport&, StepRecord&);

}  // namespace orthofront
