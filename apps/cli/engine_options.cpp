#include "cli/engine_options.h"

#include "cli/process_memory.h"

#include <limits>
#include <map>
#include <string>

#include "orthofront/spacetime/brick_cache.h"

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
               "Stop once the mesh has this many vertices (default: what half of --memory holds "
               "at ~300 B a vertex, at most 50 M; the figure shown is for the memory available "
               "now)")
      ->capture_default_str();
  c.add_option("--time-budget", o.time_budget_seconds, "Stop after this many seconds")
      ->check(CLI::PositiveNumber);
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
  c.add_option("--insertion", o.insertion,
               "Where split vertices go: streamline (integrated from the seed), previous-row "
               "(from the previous front), cubic, linear")
      ->transform(choices<Insertion>({{"streamline", Insertion::streamline},
                                      {"cubic", Insertion::cubic},
                                      {"linear", Insertion::linear},
                                      {"previous-row", Insertion::previous_row}}));
  c.add_option("--row-skip", o.row_skip,
               "Squareness: slow vertices keep their mesh vertex (off, vertex, run)")
      ->transform(choices<RowSkip>(
          {{"off", RowSkip::off}, {"vertex", RowSkip::vertex}, {"run", RowSkip::run}}));
  c.add_option("--skip-fraction", o.skip_fraction,
               "Row skipping: minimum move, as a share of the edge length")
      ->capture_default_str();
  c.add_option("--join-fraction", o.join_fraction,
               "Row skipping (run): a waiting vertex beside a moving one moves with it once it "
               "has gone this share of the minimum move (lower: fewer triangles, more short "
               "edges)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  c.add_flag("!--no-rip", o.rip, "Never rip the front at saddles");
  c.add_flag("!--no-fold-guard", o.fold_guard,
             "Keep strips whose faces fold over a neighbour instead of ripping the front there");
  c.add_flag("!--no-close-gaps", o.close_gaps,
             "Leave the gap open where a torn surface's halves run side by side again");
  c.add_option("--gap-distance", o.gap_distance,
               "Close gaps whose sides come within this many edge lengths of each other")
      ->check(CLI::PositiveNumber);
  c.add_option("--stall-steps", o.stall_steps,
               "A front vertex that kept its mesh vertex more than this many steps (it stopped "
               "advancing) leaves the front; 0: never")
      ->check(CLI::Range(0, std::numeric_limits<int>::max()));
  // Baselines of orthofront-bench (the same surface, in the old order of work): accepted, left
  // out of the user's help (group "").
  c.add_flag("!--no-shots-ahead", o.shots_ahead,
             "Integrate seed shots only when an insertion needs them, not a step ahead on an "
             "idle thread (the same surface, for timing)")
      ->group("");
  c.add_flag("!--no-samples-ahead", o.samples_ahead,
             "Sample each front when its step begins, not while the previous strip is stitched "
             "on an idle thread (the same surface, for timing)")
      ->group("");
  c.add_option("--shot-evaluations", o.shot_evaluations,
               "The most field evaluations an insertion's stream line from the seed may cost; "
               "from the first that runs out, insertions on longer ones start from the previous "
               "row (one step's integration); 0: no limit")
      ->capture_default_str()
      ->check(CLI::Range(0, std::numeric_limits<int>::max()));
  c.add_option("--integrator", o.integrator, "dopri5 (adaptive, default) or rk4")
      ->transform(choices<IntegratorKind>({{"dopri5", IntegratorKind::dopri5},
                                           {"rk4", IntegratorKind::rk4}}));
  c.add_option("--tolerance", o.tolerance, "Integrator tolerance (relative; absolute = tol * edge)")
      ->capture_default_str();
  c.add_option("--timeline-step", o.timeline_step,
               "Time step of the timeline baseline (0: edge / median seed speed)");
}

void add_memory_flag(CLI::App& c, MemoryLimits& limits) {
  c.add_option("--memory", limits.memory,
               "Memory the run may use, e.g. 4GiB, 512MiB (default: what the machine has "
               "available when the run starts, now " +
                   format_memory(available_memory_bytes()) +
                   "). The vertex cap is half of it at ~300 B a vertex (unless --max-vertices is "
                   "given); path's --cache-budget a quarter");
}

void apply_memory_flag(const CLI::App& c, MemoryLimits& limits, StreamSurfaceOptions& o) {
  limits.memory_given = c.count("--memory") > 0;
  limits.max_vertices_given = c.count("--max-vertices") > 0;
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

}  // namespace orthofront::cli
