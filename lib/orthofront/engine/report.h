#pragma once
/// What a stream-surface run did: counts, times per stage, why it stopped, per-step figures.
#include <cstddef>
#include <limits>
#include <string>
#include <vector>

#include "orthofront/engine/options.h"
#include "orthofront/quality/quality.h"

namespace orthofront {

enum class StopReason {
  none,
  steps,             ///< max_steps reached
  vertex_budget,     ///< max_vertices reached
  time_budget,       ///< time_budget_seconds exceeded
  fronts_exhausted,  ///< every front became shorter than two vertices / ℓ, or stalled
  left_domain,       ///< every remaining vertex left the domain (or reached no-data cells)
  cancelled,         ///< the progress callback asked to stop
  end_time,          ///< path surfaces: the path lines reached t1
};

const char* to_string(StopReason reason);

/// Seconds spent per stage (wall clock, summed over steps).
struct StageTimes {
  double alpha = 0;    ///< field evaluation at vertices and midpoints, system set-up, solve, μ
  double rip = 0;      ///< peak detection and front splitting
  double advance = 0;  ///< stream-line integration of every vertex
  double adapt = 0;    ///< split / merge
  double stitch = 0;   ///< mesh vertices and faces
  double gaps = 0;     ///< closing gaps behind rips, once the surface is built
  double quality = 0;  ///< final quality measurement
  double total = 0;
};

struct StepRecord {
  int step = 0;
  std::size_t fronts = 0;
  std::size_t front_vertices = 0;
  double h_min = 0, h_max = 0;           ///< front step (α-time) over the fronts
  double orthogonality_mean = 0;         ///< mean |cos(front tangent, v)| over segments
  double orthogonality_max = 0;
};

struct SurfaceReport {
  StreamSurfaceOptions options;
  StopReason stop_reason = StopReason::none;
  int steps = 0;
  std::size_t vertices = 0, faces = 0, quads = 0, triangles = 0;
  std::size_t vertex_steps = 0;        ///< vertex advances performed
  std::size_t rips = 0;
  std::size_t negative_alpha = 0;      ///< vertex-steps with α < 0 (before clamping)
  std::size_t clamped_alpha = 0;       ///< vertex-steps whose α was clamped to 0
  /// Why α was clamped (the four add up to clamped_alpha), first that applies: the flow at the
  /// vertex is slow (below rip_speed_fraction of the front's median speed: walls, no-slip
  /// layers), the vertex ends an open front (beside no data or the domain's edge), the step's
  /// damping target was infeasible, or none of these (the vertex was ahead of its neighbours).
  std::size_t clamped_slow_flow = 0, clamped_front_end = 0, clamped_infeasible_step = 0,
              clamped_ahead = 0;
  std::size_t lag_raised_alpha = 0;    ///< vertex-steps whose α the lag bound raised
  std::size_t splits = 0, merges = 0;
  std::size_t streamline_insertions = 0, insertion_fallbacks = 0;
  /// Insertions on the stream line through the previous front's interpolated point (the
  /// previous-row mode, and the streamline mode where the seed's stream line failed).
  std::size_t previous_row_insertions = 0;
  /// Insertions that started from the previous row because the stream lines from the seed
  /// beside them had missed the front several times in a row (FrontVertex::seed_misses).
  std::size_t seed_shots_skipped = 0;
  /// Insertions that started from the previous row because a stream line from the seed would
  /// cost more than StreamSurfaceOptions::shot_evaluations: its leg ran out, or it was at least
  /// as long as seed_shot_time_limit.
  std::size_t seed_shots_over_budget = 0;
  /// The shortest first leg (flow time from the seed) that ran out of evaluations so far:
  /// insertions whose leg is as long or longer start from the previous row. Infinite: none.
  double seed_shot_time_limit = std::numeric_limits<double>::infinity();
  /// First legs of seed shots integrated ahead on an idle thread (seed_shot_legs.h), and those
  /// an insertion then used. This process's run only: a saved state does not keep them.
  std::size_t legs_started_ahead = 0, legs_used_ahead = 0;
  /// Fronts whose samples were queued for an idle thread while their strip was stitched
  /// (samples_ahead.h), and those a task had finished when the next step asked.
  /// Depends on thread timing; this process's run only: a saved state does not keep them.
  std::size_t samples_started_ahead = 0, samples_used_ahead = 0;
  /// Why a stream-line insertion fell back to the cubic point (the two add up to
  /// insertion_fallbacks): its stream line left the domain or met no data, or it ended a
  /// quarter of the segment or more away from the front.
  std::size_t fallback_left_domain = 0, fallback_far_from_front = 0;
  /// The fold guard (StreamSurfaceOptions::fold_guard): front vertices taken out where a face
  /// stitched to them folded over a neighbour (local rips), and fold vertices it left in place
  /// after its last try.
  std::size_t fold_rips = 0, folds_left = 0;
  /// Front vertices taken out because they had stopped advancing (StreamSurfaceOptions::
  /// stall_steps).
  std::size_t stall_cuts = 0;
  /// Gaps closed (StreamSurfaceOptions::close_gaps): boundary stretches zipped together, the
  /// faces that took, and stretches left open because a face there would fold or be flat.
  std::size_t gap_stretches = 0, gap_faces = 0, gaps_refused = 0;
  std::size_t skipped_vertex_steps = 0;  ///< vertex-steps that kept their previous mesh vertex
  /// Where the triangles came from (the three add up to `triangles`): between rows of different
  /// segment counts (a split's insertions or a merge: one at least per event), a quad with a
  /// corner on a vertex that kept its mesh vertex while its neighbour moved (row skipping, or
  /// α clamped to 0: one per such neighbour per step), and the faces that closed gaps.
  std::size_t triangles_at_row_changes = 0, triangles_at_waiting_vertices = 0,
              triangles_closing_gaps = 0;
  std::size_t domain_exits = 0, no_data_hits = 0, zero_velocity_cuts = 0;
  std::size_t fronts_created = 0, fronts_dropped_short = 0, fronts_stalled = 0;
  std::size_t infeasible_damping_steps = 0;  ///< steps where no μ reached h = h*
  std::size_t field_evaluations = 0;
  double timeline_step = 0;              ///< the time step used by the timeline baseline
  bool closed_seed = false;
  bool closed_front_opened = false;      ///< a closed front had no closed orthogonal solution
  double closed_log_product = 0;         ///< ln|∏(-p_i/q_i)| at the worst check
  std::vector<StepRecord> per_step;
  StageTimes times;
  QualityReport quality;
  bool complete = true;                  ///< false when cancelled or interrupted
  std::string message;                   ///< a human-readable note (e.g. why a front was opened)
};

}  // namespace orthofront
