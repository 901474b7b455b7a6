#include "jobs/streak_job.h"

#include <algorithm>
#include <string>
#include <tuple>

#include "jobs/grid_args.h"
#include "jobs/process_memory.h"
#include "jobs/streak_report.h"
#include "orthofront/advect/batch_advector.h"
#include "orthofront/error.h"
#include "orthofront/spacetime/brick_cache.h"

namespace orthofront::jobs {

void add_streak_options(OptionSet& set, StreakArgs& args) {
  using G = OptionGroup;
  set.text("release", args.release, "Release interval T0:T1").required().group(G::input);
  set.text("frames", args.frames,
           "Observation times: a list t1,t2,... or START:END:COUNT (after T0); with --route "
           "spacetime, the last one ends the surface")
      .group(G::input);
  set.text("route", args.route,
           "direct: release rows of particles and write one frame per observation time (.pvd); "
           "streak-line: 2D analytic flows, at each observation time the stream surface of the "
           "streak-line field (Weinkauf & Theisel) over (x, y, age) built by the flow-orthogonal "
           "engine (.pvd, positions (x, y, age)); spacetime: 2D analytic flows, the streak lines "
           "of --point at all times as one surface in (x, y, t) (.vtp, .ply, .obj)")
      .one_of({"direct", "streak-line", "spacetime"});
  set.text("point", args.point, "--route spacetime: the release point x,y").group(G::input);
  set.real("edge", args.edge, "Target edge length").positive().unit("world units");
  set.text("mesh", args.mesh,
           "remeshed: a triangle mesh whose vertices keep their release labels (s, tau), adapted "
           "by split, collapse and flip so its size follows the surface's area; rows: rows of "
           "particles over (s, tau), refined by whole rows and columns")
      .one_of({"remeshed", "rows"});
  set.real("collapse", args.collapse,
           "--mesh remeshed: collapse edges shorter than this many edge lengths")
      .positive()
      .unit("edge lengths");
  set.real("prune", args.prune,
           "--mesh remeshed: remove filaments of dye narrower than this many edge lengths (a mesh "
           "with edges of one edge length cannot resolve them, and its faces there are slivers; "
           "at most split/2, the default with a smaller --split; 0 keeps them all)")
      .at_least(0)
      .unit("edge lengths");
  set.real("split", args.split, "Split edges longer than this many edge lengths")
      .positive()
      .unit("edge lengths");
  set.real("merge", args.merge,
           "--mesh rows: remove particles whose edges are both shorter than this many edge "
           "lengths")
      .positive()
      .unit("edge lengths");
  set.real("release-step", args.release_step,
           "Time between released rows (0: edge over the largest speed on the seed; --mesh rows: "
           "over the median speed)")
      .at_least(0);
  set.integer("releases-per-break", args.releases_per_break,
              "--mesh rows: rows released per refinement; the rows released between move from "
              "their release times to the next break in one call")
      .at_least(1)
      .group(G::performance);
  set.integer("seed-count", args.seed_count,
              "Particles per row at release (0: seed length / edge + 1)")
      .at_least(0);
  set.text("insert", args.insertion,
           "How inserted particles are placed: exact (released at their own (s, tau) and "
           "integrated; a streamed series then reads earlier steps again) or interpolate (cubic; "
           "every step is read once)")
      .one_of({"exact", "interpolate"});
  set.real("flat-split", args.flat_split,
           "--mesh remeshed: an edge where the surface departs from its chord by less than this "
           "many edge lengths is split at its midpoint, with no integration (in 2D, every edge "
           "inside the dye; the new label is interpolated), and a curved edge of the dye's boundary "
           "by the cubic through four of its particles where that is as close; 0: every new particle is placed as --insert says")
      .at_least(0)
      .unit("edge lengths");
  set.real("coarsen-age", args.coarsen_age,
           "--mesh remeshed: dye older than this is meshed coarser, at edge * age / this (0: the "
           "same edge length at every age)")
      .at_least(0)
      .group(G::budget);
  set.count("vertex-budget", args.vertex_budget,
            "--mesh remeshed: when the particles exceed this, the oldest dye is coarsened (the age "
            "of --coarsen-age lowered) until they fit, rather than the run stopping (default: "
            "half of --max-vertices; 0: no budget)")
      .group(G::budget)
      .derived_default();
  set.text("region", args.region,
           "--mesh remeshed: region of interest xmin,ymin,zmin:xmax,ymax,zmax (2D: "
           "xmin,ymin:xmax,ymax); dye that leaves it is removed, as at the domain's edge")
      .group(G::budget);
  set.count("max-vertices", args.max_vertices,
            "Stop when the particles exceed this (default: from --memory)")
      .at_least(2)
      .group(G::budget)
      .derived_default();
  add_memory_option(set, args.limits);
  set.text("cache-budget", args.budget,
           "Memory for resident and in-flight data of a streamed series (default: a quarter of "
           "--memory)")
      .group(G::budget)
      .derived_default();
  set.text("device", args.device,
           "Gridded series: move particles by bulk advection (whole steps, slab by slab) on cpu, "
           "cuda or auto (cuda when built with it and a device is present); default: the "
           "streamed field's integrated flow map")
      .one_of({"cpu", "cuda", "auto"})
      .group(G::performance)
      .derived_default();
  set.text("device-memory", args.device_memory,
           "With --device cuda/auto: time steps kept on the device (e.g. 8GiB; default: half its "
           "free memory)")
      .group(G::performance)
      .derived_default();
}

spacetime::StreakOptions streak_options(const OptionSet& set, StreakArgs& args) {
  StreamSurfaceOptions caps;
  if (set.given("max-vertices")) caps.max_vertices = args.max_vertices;
  apply_memory_limits(set, args.limits, caps);
  spacetime::StreakOptions o;
  std::tie(o.release_begin, o.release_end) = parse_streak_release(args.release);
  o.frames = parse_streak_frames(args.frames);
  o.edge = args.edge;
  o.split = args.split;
  o.merge = args.merge;
  o.mesh = args.mesh == "rows" ? spacetime::StreakMesh::rows : spacetime::StreakMesh::remeshed;
  o.collapse = args.collapse;
  // The default width is the widest split allows: a smaller split narrows it with it.
  o.prune = set.given("prune") ? args.prune : std::min(args.prune, 0.5 * args.split);
  o.release_step = args.release_step;
  o.releases_per_break = args.releases_per_break;
  o.seed_count = args.seed_count;
  o.insertion = args.insertion == "exact" ? spacetime::ParticleInsertion::exact
                                          : spacetime::ParticleInsertion::interpolate;
  o.max_vertices = caps.max_vertices;
  o.coarsen_age = args.coarsen_age;
  o.flat_split = args.flat_split;
  o.vertex_budget = set.given("vertex-budget") ? args.vertex_budget : o.max_vertices / 2;
  if (!args.region.empty()) o.region = parse_box(args.region, "--region", true);
  if (o.mesh == spacetime::StreakMesh::rows)
    for (const char* remeshed_only : {"coarsen-age", "vertex-budget", "region", "flat-split"})
      if (set.given(remeshed_only))
        throw InvalidArgument(std::string("--") + remeshed_only + " applies to --mesh remeshed only");
  o.seed_name = args.seed;
  o.field_name = args.field;
  if (!args.device.empty()) o.device = advect::parse_device(args.device);
  if (!args.device_memory.empty()) o.device_bytes = spacetime::parse_bytes(args.device_memory);
  return o;
}

std::size_t streak_cache_budget(const StreakArgs& args) {
  return args.budget.empty() ? cache_budget_for(args.limits.memory_bytes)
                             : spacetime::parse_bytes(args.budget);
}

}  // namespace orthofront::jobs
