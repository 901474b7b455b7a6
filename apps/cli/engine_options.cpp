#include "cli/engine_options.h"

#include "cli/process_memory.h"

#include <map>
#include <string>

namespace orthofront::cli {

namespace {
template <typename Enum>
CLI::CheckedTransformer choices(const std::map<std::string, Enum>& map) {
  return CLI::CheckedTransformer(map, CLI::ignore_case);
}
}  // namespace

void add_engine_flags(CLI::App& c, StreamSurfaceOptions& o) {
  c.add_option("--edge", o.edge, "Target edge length ℓ (world units)")->capture_default_str();
  c.add_option("--steps", o.max_steps, "Number of front steps")->capture_default_str();
  o.max_vertices = default_vertex_budget();
  c.add_option("--max-vertices", o.max_vertices,
               "Stop once the mesh has this many vertices (default: what half the available "
               "memory holds, at most 50 M)")
      ->capture_default_str();
  c.add_option("--time-budget", o.time_budget_seconds, "Stop after this many seconds");
  c.add_option("--method", o.method, "orthogonal (flow-orthogonal fronts) or timeline (baseline)")
      ->transform(choices<Method>({{"orthogonal", Method::orthogonal},
                                   {"timeline", Method::timeline}}))
      ->capture_default_str();
  c.add_option("--mu-mode", o.mu_mode,
               "damping (unit-invariant, default) or paper (unit kernel, mu+)")
      ->transform(choices<MuMode>({{"damping", MuMode::damping}, {"paper", MuMode::paper}}));
  c.add_option("--damping", o.damping,
               "Share kappa of the orthogonality error removed per front step (damping mode)")
      ->capture_default_str();
  c.add_option("--mu", o.mu, "mu+ of paper mode")->capture_default_str();
  c.add_option("--negative-alpha", o.negative_alpha, "clamp (default) or keep (may fold)")
      ->transform(choices<NegativeAlpha>({{"clamp", NegativeAlpha::clamp},
                                          {"keep", NegativeAlpha::keep}}));
  c.add_option("--insertion", o.insertion, "Where split vertices go: streamline, cubic, linear")
      ->transform(choices<Insertion>({{"streamline", Insertion::streamline},
                                      {"cubic", Insertion::cubic},
                                      {"linear", Insertion::linear}}));
  c.add_option("--row-skip", o.row_skip,
               "Squareness: slow vertices keep their mesh vertex (off, vertex, run)")
      ->transform(choices<RowSkip>(
          {{"off", RowSkip::off}, {"vertex", RowSkip::vertex}, {"run", RowSkip::run}}));
  c.add_option("--skip-fraction", o.skip_fraction,
               "Row skipping: minimum move, as a share of the edge length")
      ->capture_default_str();
  c.add_flag("!--no-rip", o.rip, "Never rip the front at saddles");
  c.add_option("--integrator", o.integrator, "dopri5 (adaptive, default) or rk4")
      ->transform(choices<IntegratorKind>({{"dopri5", IntegratorKind::dopri5},
                                           {"rk4", IntegratorKind::rk4}}));
  c.add_option("--tolerance", o.tolerance, "Integrator tolerance (relative; absolute = tol * edge)")
      ->capture_default_str();
  c.add_option("--timeline-step", o.timeline_step,
               "Time step of the timeline baseline (0: edge / median seed speed)");
}

}  // namespace orthofront::cli
