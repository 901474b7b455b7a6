#pragma once
/// The α step (paper §4): per-vertex speed factors α_i that make the advanced front orthogonal to
/// the flow, with the damping choice of μ, a closed front's rotation, negative-α clamping (by
/// cause) and the lag bound of path surfaces.
#include <cmath>
#include <cstddef>
#include <vector>

#include "orthofront/engine/for_range.h"
#include "orthofront/engine/front.h"
#include "orthofront/engine/front_samples.h"
#include "orthofront/engine/options.h"
#include "orthofront/engine/report.h"
#include "orthofront/field/field.h"
#include "orthofront/mesh/mesh.h"
#include "orthofront/solve/alpha_solver.h"

namespace orthofront {

/// The largest front step in α-time that damping κ allows: h* = -ln(1 - κ).
inline double damping_step(double damping) { return -std::log(1.0 - damping); }

/// The α system solved, before anything is applied to its front: a function of the segments'
/// terms and the vertices' speeds alone, so it can be taken ahead (samples_ahead.h).
struct AlphaSolution {
  /// A closed front: ln |Π -p_i/q_i| round it and the product's sign, and the rotation (by
  /// `shift` vertices) that makes its equation of smallest |r| the dropped closing one.
  double log_product = 0;
  bool negative = false;
  std::size_t shift = 0;
  bool ok = false;                  ///< full rank (else the front advances uniformly)
  std::vector<double> aln, kernel;  ///< α^L and k, in the rotated order
  bool damped = false;              ///< μ chosen by damping: `choice`
  DampingChoice choice;
  std::vector<double> p, q, r, speed;  ///< scratch: the rotated terms and speeds
};

/// Solves p_i α_i + q_i α_{i+1} = -r_i for `n` vertices (`speed` at each; the terms of n
/// segments on a closed front, n - 1 on an open one), with μ chosen by damping where `damping`
/// (fastest vertex at `speed_limit`).
void solve_alpha_system(const std::vector<double>& p, const std::vector<double>& q,
                        const std::vector<double>& r, const std::vector<double>& speed,
                        std::size_t n, bool closed, bool damping, double speed_limit,
                        AlphaSolver& solver, AlphaSolution& out);

template <int N>
class AlphaStep {
 public:
  enum class Outcome { solved, cut };

  /// Counts go to `report`, per-step figures to `record`, vertex errors to `mesh` (all owned by
  /// the engine and outliving this).
  AlphaStep(const Field<N>& field, const StreamSurfaceOptions& options, Mesh& mesh,
            SurfaceReport& report, StepRecord& record);

  /// The largest front step in α-time that damping allows: h* = -ln(1 - κ).
  double h_star() const { return h_star_; }

  /// Starts a step's orthogonality tally.
  void begin_step();
  /// Mean |cos(front tangent, v)| over the segments seen this step.
  double orthogonality_mean() const;

  /// Builds the equations p_i α_i + q_i α_{i+1} = -r_i from the velocities `vel` (speeds
  /// `speed`) and solves them into `alpha`. A segment whose midpoint has no flow marks cut[i] and
  /// returns `cut`. A closed front drops its equation of smallest |r| and is rotated (with `vel`
  /// and `speed`) so that it becomes the closing segment; where no closed orthogonal front exists
  /// it is opened there. The rotation trades the storage of f.v, `vel` and `speed` with this
  /// object's scratch: pointers into them do not survive the call. `terms` and `solution`: the
  /// equations' terms and their solution taken already (samples_ahead.h), whose vectors this
  /// trades with its own.
  Outcome solve(Front<N>& f, std::vector<Vec<N>>& vel, std::vector<double>& speed,
                std::vector<double>& alpha, std::vector<char>& cut,
                SegmentTerms<N>* terms = nullptr, AlphaSolution* solution = nullptr);

  /// The timeline baseline's orthogonality figures (it solves nothing).
  void measure_orthogonality(const Front<N>& f, const std::vector<Vec<N>>& vel);

  /// α < 0 becomes 0 (NegativeAlpha::clamp), counted by cause: slow flow, the end of an open
  /// front, an infeasible damping step (the last solve's), or ahead of its neighbours.
  void clamp_negative(const Front<N>& f, std::vector<double>& alpha,
                      const std::vector<double>& speed);

  /// The lag bound: vertices behind the lead along lag_axis have their α raised towards the
  /// front's largest α, smoothly from lag (1 - lag_ramp)·max_lag to all of it at max_lag, so they
  /// keep pace instead of falling further behind while neighbours' α differ little (a step in α
  /// between neighbours tilts the front and folds it; see StreamSurfaceOptions::max_lag).
  void raise_lagging(const Front<N>& f, std::vector<double>& alpha);

 private:
  const Field<N>& field_;
  const StreamSurfaceOptions& opt_;
  Mesh& mesh_;
  SurfaceReport& report_;
  StepRecord& record_;
  double h_star_ = 0;
  bool damping_infeasible_ = false;  ///< the last solve's damping target could not be met
  double ortho_sum_ = 0;
  std::size_t ortho_count_ = 0;
  AlphaSolver solver_;
  CheapLoop segment_loop_;  ///< v and J at the segments' midpoints
  // Scratch, reused between fronts and steps.
  SegmentTerms<N> terms_;
  AlphaSolution solution_;
  // Room for rotating a closed front and its per-vertex arrays.
  std::vector<FrontVertex<N>> front_scratch_;
  std::vector<Vec<N>> vel_scratch_;
  std::vector<double> value_scratch_;
};

extern template class AlphaStep<3>;
extern template class AlphaStep<4>;

}  // namespace orthofront
