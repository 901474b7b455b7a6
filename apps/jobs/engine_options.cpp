#include "jobs/engine_options.h"

#include "jobs/process_memory.h"

#include <limits>
#include <string>

#include "orthofront/spacetime/brick_cache.h"

namespace orthofront::jobs {

void add_engine_options(OptionSet& set, StreamSurfaceOptions& o) {
  using G = OptionGroup;
  set.real("edge", o.edge, "Target edge length ℓ (world units)").positive().unit("world units");
  set.integer("steps", o.max_steps, "Number of front steps").at_least(0).group(G::budget);
  o.max_vertices = default_vertex_budget();
  set.count("max-vertices", o.max_vertices,
            "Stop once the mesh has this many vertices (default: what half of --memory holds at "
            "~300 B a vertex, at most 50 M; the figure shown is for the memory available now)")
      .at_least(2)
      .group(G::budget);
  set.real("time-budget", o.time_budget_seconds, "Stop after this many seconds")
      .positive()
      .unit("s")
      .group(G::budget)
      .derived_default();
  set.choice<Method>("method", o.method,
                     {{"orthogonal", Method::orthogonal}, {"timeline", Method::timeline}},
                     "orthogonal (flow-orthogonal fronts) or timeline (baseline)");
  set.choice<MuMode>("mu-mode", o.mu_mode, {{"damping", MuMode::damping}, {"paper", MuMode::paper}},
                     "damping (unit-invariant, default) or paper (unit kernel, mu+)");
  set.real("damping", o.damping,
           "Share kappa of the orthogonality error removed per front step (damping mode)")
      .between(0.0, 1.0);
  set.real("mu", o.mu, "mu+ of paper mode").at_least(0);
  set.choice<NegativeAlpha>("negative-alpha", o.negative_alpha,
                            {{"clamp", NegativeAlpha::clamp}, {"keep", NegativeAlpha::keep}},
                            "clamp (default) or keep (may fold)");
  set.choice<Insertion>("insertion", o.insertion,
                        {{"streamline", Insertion::streamline},
                         {"cubic", Insertion::cubic},
                         {"linear", Insertion::linear},
                         {"previous-row", Insertion::previous_row}},
                        "Where split vertices go: streamline (integrated from the seed), "
                        "previous-row (from the previous front), cubic, linear");
  set.choice<RowSkip>("row-skip", o.row_skip,
                      {{"off", RowSkip::off}, {"vertex", RowSkip::vertex}, {"run", RowSkip::run}},
                      "Squareness: slow vertices keep their mesh vertex (off, vertex, run)");
  set.real("skip-fraction", o.skip_fraction,
           "Row skipping: minimum move, as a share of the edge length")
      .unit("edge lengths");
  set.real("join-fraction", o.join_fraction,
           "Row skipping (run): a waiting vertex beside a moving one moves with it once it has "
           "gone this share of the minimum move (lower: fewer triangles, more short edges)")
      .range(0.0, 1.0);
  set.flag("no-rip", o.rip, "Never rip the front at saddles", false);
  set.flag("no-fold-guard", o.fold_guard,
           "Keep strips whose faces fold over a neighbour instead of ripping the front there",
           false);
  set.flag("no-close-gaps", o.close_gaps,
           "Leave the gap open where a torn surface's halves run side by side again", false);
  set.real("gap-distance", o.gap_distance,
           "Close gaps whose sides come within this many edge lengths of each other")
      .positive()
      .unit("edge lengths");
  set.integer("stall-steps", o.stall_steps,
              "A front vertex that kept its mesh vertex more than this many steps (it stopped "
              "advancing) leaves the front; 0: never")
      .at_least(0);
  set.integer("shot-evaluations", o.shot_evaluations,
              "The most field evaluations an insertion's stream line from the seed may cost; from "
              "the first that runs out, insertions on longer ones start from the previous row "
              "(one step's integration); 0: no limit")
      .at_least(0)
      .group(G::performance);
  set.choice<IntegratorKind>("integrator", o.integrator,
                             {{"dopri5", IntegratorKind::dopri5}, {"rk4", IntegratorKind::rk4}},
                             "dopri5 (adaptive, default) or rk4");
  set.real("tolerance", o.tolerance, "Integrator tolerance (relative; absolute = tol * edge)")
      .positive();
  set.real("timeline-step", o.timeline_step,
           "Time step of the timeline baseline (0: edge / median seed speed)")
      .at_least(0);
}

void add_memory_option(OptionSet& set, MemoryLimits& limits) {
  set.text("memory", limits.memory,
           "Memory the run may use, e.g. 4GiB, 512MiB (default: what the machine has available "
           "when the run starts, now " +
               format_memory(available_memory_bytes()) +
               "). The vertex cap is half of it at ~300 B a vertex (unless --max-vertices is "
               "given); path's --cache-budget a quarter")
      .group(OptionGroup::budget)
      .derived_default();
}

void apply_memory_limits(const OptionSet& set, MemoryLimits& limits, StreamSurfaceOptions& o) {
  limits.memory_given = set.given("memory");
  limits.max_vertices_given = set.given("max-vertices");
  limits.memory_bytes =
      limits.memory_given ? spacetime::parse_bytes(limits.memory) : available_memory_bytes();
  if (!limits.max_vertices_given)
    o.max_vertices =
        limits.memory_given ? vertex_budget_for(limits.memory_bytes) : default_vertex_budget();
  limits.max_vertices = o.max_vertices;
}

std::string MemoryLimits::cap_source() const {
  if (max_vertices_given) return "--max-vertices";
  if (memory_bytes == 0) return "the default cap (the machine's memory is unknown)";
  return std::string("half of ") + (memory_given ? "--memory " : "the available memory ") +
         format_memory(memory_bytes) + " at ~300 B a vertex";
}

std::string MemoryLimits::raise_advice() const {
  // An explicit --max-vertices wins over --memory, so raising --memory alone would change nothing.
  if (max_vertices_given) return "raise --max-vertices (or leave it out and give --memory)";
  if (memory_given) return "raise --memory or --max-vertices";
  return "raise --max-vertices or --memory (on a machine with more memory)";
}

nlohmann::json MemoryLimits::to_json() const {
  return {{"memory_bytes", memory_bytes},
          {"memory_source", memory_given ? "--memory" : "available memory"},
          {"max_vertices", max_vertices},
          {"max_vertices_source", max_vertices_given ? "--max-vertices"
                                  : memory_given     ? "--memory"
                                                     : "available memory"}};
}

std::string vertex_cap_reached(const MemoryLimits& limits, std::size_t vertices) {
  return "the vertex budget of " + std::to_string(limits.max_vertices) + " (" +
         limits.cap_source() + "): " + std::to_string(vertices) + " vertices, resident memory " +
         format_memory(current_rss_bytes()) + " (peak " + format_memory(peak_rss_bytes()) + ")";
}

}  // namespace orthofront::jobs
