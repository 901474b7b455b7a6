#include "orthofront/engine/discretization.h"

#include <algorithm>
#include <cmath>

#include "orthofront/error.h"

namespace orthofront {

namespace {

/// Flow-orthogonal front lines: α from the orthogonality equations (alpha_step.h), negative α
/// clamped, the lag bound, and a step that moves the fastest vertex by ℓ (at most h*).
template <int N>
class OrthogonalFronts final : public Discretization<N> {
 public:
  using Discretization<N>::Discretization;
  void begin(const std::vector<Front<N>>&) override {}
  bool alpha(Front<N>& f, std::vector<Vec<N>>& vel, std::vector<double>& speed,
             std::vector<double>& alpha, std::vector<char>& cut, SegmentTerms<N>* terms,
             AlphaSolution* solution) override {
    return this->alpha_step_.solve(f, vel, speed, alpha, cut, terms, solution) ==
           AlphaStep<N>::Outcome::solved;
  }
  double step(const Front<N>& f, std::vector<double>& alpha,
              const std::vector<double>& speed) override {
    const StreamSurfaceOptions& o = this->opt_;
    this->alpha_step_.clamp_negative(f, alpha, speed);
    if (o.lag_axis >= 0 && o.lag_axis < N && o.max_lag > 0)
      this->alpha_step_.raise_lagging(f, alpha);
    double max_speed = 0;
    for (std::size_t i = 0; i < f.v.size(); ++i)
      max_speed = std::max(max_speed, std::abs(alpha[i]) * speed[i]);
    if (!(max_speed > 0)) return -1;
    return std::min(o.edge / max_speed,
                    o.mu_mode == MuMode::damping ? this->alpha_step_.h_star() : o.paper_max_step);
  }
  bool safeguarded() const override { return true; }
};

/// The paper's timeline baseline: α = 1 and one time step for every vertex (the option, or ℓ over
/// the seed's median speed); its orthogonality is measured, not corrected.
template <int N>
class TimelineFronts final : public Discretization<N> {
 public:
  using Discretization<N>::Discretization;
  void begin(const std::vector<Front<N>>& fronts) override {
    this->report_.timeline_step = time_step(fronts);
  }
  bool alpha(Front<N>& f, std::vector<Vec<N>>& vel, std::vector<double>&, std::vector<double>&,
             std::vector<char>&, SegmentTerms<N>*, AlphaSolution*) override {
    this->alpha_step_.measure_orthogonality(f, vel);
    return true;
  }
  double step(const Front<N>&, std::vector<double>&, const std::vector<double>&) override {
    return this->report_.timeline_step;
  }
  bool safeguarded() const override { return false; }

 private:
  double time_step(const std::vector<Front<N>>& fronts) const {
    if (this->opt_.timeline_step > 0) return this->opt_.timeline_step;
    std::vector<double> speeds;
    for (const auto& fr : fronts)
      for (const auto& fv : fr.v) {
        Vec<N> v;
        if (this->field_.velocity(fv.x, v) == FieldStatus::inside) speeds.push_back(v.norm());
      }
    const double median = median_of(std::move(speeds));
    if (!(median > 0))
      throw InvalidArgument("velocity is zero along the seed; the timeline step is undefined");
    return this->opt_.edge / median;
  }
};

}  // namespace

template <int N>
std::unique_ptr<Discretization<N>> make_discretization(const Field<N>& field,
                                                       const StreamSurfaceOptions& options,
                                                       Mesh& mesh, SurfaceReport& report,
                                                       StepRecord& record) {
  if (options.method == Method::timeline)
    return std::make_unique<TimelineFronts<N>>(field, options, mesh, report, record);
  return std::make_unique<OrthogonalFronts<N>>(field, options, mesh, report, record);
}

template std::unique_ptr<Discretization<3>> make_discretization(
    const Field<3>&, const StreamSurfaceOptions&, Mesh&, SurfaceReport&, StepRecord&);
template std::unique_ptr<Discretization<4>> make_discretization(
    const Field<4>&, const StreamSurfaceOptions&, Mesh&, SurfaceReport&, StepRecord&);

}  // namespace orthofront
