#pragma once
/// Options of the stream-surface engine; defaults are the project's recommended mode.
#include <cstddef>
#include <limits>

namespace orthofront {

enum class Method {
  orthogonal,  ///< flow-orthogonal front lines (α-scaled advance)
  timeline,    ///< baseline: timeline front advanced by a fixed time step in v
};

enum class MuMode {
  damping,  ///< unit-invariant: fraction κ of the orthogonality error removed per step
  paper,    ///< the paper's rule: unit kernel, α = α^L + μ k^+
};

enum class NegativeAlpha {
  clamp,  ///< α_i < 0 becomes 0: the vertex waits (no folds)
  keep,   ///< the paper: vertices may move backwards (may fold)
};

enum class Insertion {
  linear,      ///< midpoint of the new segment (the paper)
  cubic,       ///< Catmull-Rom point on the new front
  streamline,  ///< on the true stream line: the seed point at the interpolated parameter,
               ///< integrated over the interpolated time; where that fails, as previous_row;
               ///< cubic where both fail
  previous_row,  ///< on the stream line through the Catmull-Rom point of the previous front
                 ///< between the ends' origins, integrated over the interpolated step time:
                 ///< one step's integration instead of one from the seed, exact to within the
                 ///< previous front's interpolation (from the seed where the ends' origins are
                 ///< not neighbours there; cubic on failure)
};

enum class RowSkip {
  off,     ///< every vertex gets a new mesh vertex every step
  vertex,  ///< a vertex that moved less than skip_fraction·ℓ keeps its previous mesh vertex
  run,     ///< as `vertex`, but short runs are merged with their neighbours (fewer triangles)
};

enum class IntegratorKind { dopri5, rk4 };

/// The option names the command line, job files and reports use.
const char* to_string(Method method);
const char* to_string(MuMode mode);
const char* to_string(NegativeAlpha mode);
const char* to_string(Insertion mode);
const char* to_string(RowSkip mode);
const char* to_string(IntegratorKind kind);

struct StreamSurfaceOptions {
  Method method = Method::orthogonal;
  double edge = 0.1;       ///< target edge length ℓ, world units
  int max_steps = 100;     ///< front steps
  std::size_t max_vertices = 50'000'000;
  double time_budget_seconds = std::numeric_limits<double>::infinity();

  MuMode mu_mode = MuMode::damping;
  double damping = 0.5;    ///< κ in (0, 1): share of the orthogonality error removed per step
  double mu = 1.0;         ///< μ+ of paper mode (unit kernel)
  double paper_max_step = 1.0;  ///< paper mode's upper bound on h
  NegativeAlpha negative_alpha = NegativeAlpha::clamp;

  Insertion insertion = Insertion::streamline;
  double split_factor = 1.5;   ///< split a segment longer than split_factor·ℓ
  double merge_factor = 1.25;  ///< merge two segments shorter than merge_factor·ℓ together
  RowSkip row_skip = RowSkip::run;
  double skip_fraction = 0.5;  ///< see RowSkip
  /// RowSkip::run: a waiting vertex beside a moving one moves with it once it has gone this share
  /// of skip_fraction·ℓ (and so on along the waiting run). Lower: fewer triangles where waiting
  /// and moving vertices meet, more short edges along the flow (docs/benchmarks/engine-options.md,
  /// row skipping).
  double join_fraction = 0.5;

  /// Lag bound (path surfaces): a vertex more than max_lag behind the front's lead along
  /// coordinate lag_axis advances with the front's largest α, so the front's spread along that
  /// axis (the time band of a lifted field) stays near max_lag. lag_axis < 0: off.
  int lag_axis = -1;
  double max_lag = 0;
  /// Share of max_lag over which α ramps up smoothly to the front's largest (0: a hard switch at
  /// max_lag, the first version of the bound).
  double lag_ramp = 1.0;

  bool rip = true;
  /// A front vertex whose mesh vertex is more than this many steps old leaves the front: it moved
  /// less than skip_fraction·ℓ in all of them with row skipping (without: not at all, α clamped
  /// to 0) while the front's fastest vertex moved about ℓ a step, so it has stopped advancing (a
  /// wall, a recirculation bubble); its stream line ends there, as at a rip, and the rest of the
  /// front goes on. 0: never (orthogonal method only; path surfaces turn it off).
  int stall_steps = 50;
  /// Stream surfaces: where the surface tore (a rip, an obstacle, a no-data cut) and its halves
  /// run side by side again downstream, zip their boundaries together where they come within
  /// gap_distance·ℓ of each other over at least 2ℓ (mesh/close_gaps.h), once the surface is built.
  /// 2ℓ by default: halves that meet again behind an obstacle a little over ℓ apart close, with
  /// closing faces at most 2ℓ across.
  bool close_gaps = true;
  double gap_distance = 2.0;
  /// Undo a strip whose faces fold over a neighbour (normals more than 90° apart) and take the
  /// vertices on the fold out of the front, which ends their stream lines there (orthogonal
  /// method only; the timeline baseline is left as the paper has it).
  bool fold_guard = true;
  double rip_sharpness = 0.5;        ///< 1 - (α_{i-1} + α_{i+1}) / (2 α_i) above this ...
  double rip_speed_fraction = 0.05;  ///< ... and |v_i| below this share of the median speed
  double zero_speed_fraction = 1e-9; ///< |v| below this share of the median speed: no flow

  /// Insertions from the seed (Insertion::streamline) integrate in two legs, the first to the
  /// previous front's time; a step starts the legs of the next step's likely insertions on
  /// TBB's idle worker (engine/seed_shot_legs.h). The mesh is the same either way, bit for bit.
  bool shots_ahead = true;
  /// The link stage starts sampling each front it stitches (v at its vertices, the α system's
  /// terms at its segments) on TBB's idle worker; the next step takes the samples where its front
  /// has the same positions (engine/samples_ahead.h). The mesh is the same either way, bit for
  /// bit.
  bool samples_ahead = true;
  /// The most field evaluations an insertion's stream line from the seed may cost (its first
  /// leg). A shot costs the surface's age in integration: one that runs out sets a time (its
  /// leg's) from which this surface's insertions start from the previous row instead, one
  /// step's integration each (SurfaceReport::seed_shot_time_limit). 0: no limit.
  int shot_evaluations = 2048;

  IntegratorKind integrator = IntegratorKind::dopri5;
  double tolerance = 1e-9;   ///< relative tolerance; absolute tolerance is tolerance·ℓ
  int rk4_substeps = 4;

  double timeline_step = 0;  ///< time step of the timeline baseline; 0: ℓ / median seed speed
  double closed_log_product_limit = 0.5;  ///< |ln ∏(-p_i/q_i)| above this: no closed front

  /// Fronts with fewer vertices run their per-vertex stages serially: below it, splitting a
  /// stage into tasks costs more than it saves (chosen with `orthofront-bench stream
  /// --parallel-threshold`; figures: docs/benchmarks/measurements.md).
  std::size_t parallel_threshold = 128;
  bool measure_quality = true;
};

}  // namespace orthofront
