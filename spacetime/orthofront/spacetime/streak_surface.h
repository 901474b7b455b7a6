#pragma once
/// Streak surfaces: at each observation time t, the positions of all particles released from a
/// seed curve between release_begin and min(t, release_end). Particles are released in rows (one
/// release time τ each) and all advance together in time, so a streamed series is read one step
/// interval at a time. The mesh is a quad mesh over (s, τ), refined and coarsened in both
/// directions as it stretches and crowds; strips between neighbouring rows are triangulated by
/// walking both rows in s, which keeps it conforming (quads where the rows share s, transition
/// triangles where they do not). Inserted particles are released at their own (s, τ) and moved
/// through the flow map to the current time (exact); interpolation is a counted fallback.
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "orthofront/advect/batch_advector.h"
#include "orthofront/field/unsteady.h"
#include "orthofront/integrate/runge_kutta.h"
#include "orthofront/mesh/mesh.h"
#include "orthofront/quality/quality.h"
#include "orthofront/seed/seed_curve.h"
#include "orthofront/spacetime/brick_cache.h"
#include "orthofront/spacetime/flow_map.h"

namespace orthofront::spacetime {

/// How a particle inserted at (s, τ) gets its position at the current time.
enum class ParticleInsertion {
  exact,        ///< released at τ from the seed point s and moved by the flow map (streamed
                ///< series: reads the steps since τ again)
  interpolate,  ///< cubic in s along its row, or in τ across rows (reads every step once)
};
const char* to_string(ParticleInsertion insertion);

/// How the streak mesh is kept.
enum class StreakMesh {
  /// A triangle mesh whose vertices carry (s, τ) as labels: long edges are split (the new
  /// particle released at the label midpoint), short ones collapsed onto a neighbour, edges
  /// flipped to the Delaunay criterion; so the vertex count follows the surface's area and
  /// boundary rather than the history of its stretching.
  remeshed,
  /// Rows of particles over (s, τ), refined and coarsened by whole rows and columns.
  rows,
};
const char* to_string(StreakMesh mesh);

struct StreakProgress {
  double t = 0, t_end = 0;          ///< simulated time and the last observation time
  std::size_t frames_written = 0, frames = 0;
  std::size_t particles = 0, rows = 0;
  double elapsed_seconds = 0;
  double advect_seconds = 0, refine_seconds = 0, frame_seconds = 0;  ///< so far, as in the report
  bool streamed = false;
  CacheStatistics cache;            ///< streamed only
};

struct StreakOptions {
  double release_begin = 0, release_end = 1;  ///< particles leave the seed during this interval
  std::vector<double> frames;       ///< observation times, increasing, > release_begin
  double edge = 0.05;               ///< ℓ: target edge length
  double split = 1.5;               ///< an edge longer than split·ℓ gets a particle inserted
  double merge = 0.5;               ///< a particle whose edges are both below merge·ℓ goes
  double release_step = 0;          ///< time between rows at release; 0: ℓ / median seed speed
  /// Rows released per stop of the particles: with k > 1 only every k-th release (and the last,
  /// the frames and a series' steps) stops every particle to be refined; the rows released
  /// between are moved from their release times to the next stop in one call. Each stop moves,
  /// takes and looks at every particle, and a long release has hundreds: fewer stops at a
  /// slightly longer interval between refinements.
  int releases_per_break = 1;
  int seed_count = 0;               ///< particles per row at release; 0: seed length / ℓ + 1
  ParticleInsertion insertion = ParticleInsertion::exact;
  /// rows here (the baselines of orthofront-bench streak and orthofront-bench gpu-streak, and batch jobs); the
  /// `streak` command and Python choose remeshed unless told otherwise.
  StreakMesh mesh = StreakMesh::rows;
  /// Remeshed: edges shorter than collapse·ℓ are collapsed (and, as for rows, edges longer
  /// than split·ℓ split). At most split/2, so a collapse never makes an edge that splits.
  double collapse = 0.75;
  /// Remeshed: filaments of dye thinner than w = prune·ℓ are pruned. Stretching thins dye into
  /// filaments a mesh with edges ℓ cannot resolve: their faces are slivers that turn over, and
  /// their boundary, which grows exponentially, would set the vertex count. A filament is eaten
  /// from its loose end while thinner than w, and cut where it is thinner than w/2 or a face of
  /// it turns over (faces touching the newest row are never pruned). 0 keeps every filament.
  /// At most split/2; the default is that, as the strips of a narrower filament have angles
  /// under 30°.
  double prune = 0.75;
  /// Remeshed: particles placed by interpolation at a corner of a face with an angle under 30°
  /// move halfway toward the point that would make the faces around them equilateral (along
  /// the surface, or along a straight boundary; their labels interpolated there) where that
  /// widens the smallest angle. Exactly placed particles never move: they stay on their paths.
  bool smooth = true;
  /// Remeshed: a new particle goes to the split edge's midpoint, with no integration, where the
  /// surface is estimated to depart from the edge's chord by less than flat_split · ℓ there
  /// (from the surface's largest curvature around the edge, and along the dye's boundary from
  /// the boundary's turn). Where the surface is flat the midpoint lies on it exactly, wherever
  /// its label's path goes: in a 2D flow the dye is a region of the plane, so inside it every
  /// split is such. On a curved boundary of the dye, the particle goes where the cubic through
  /// four boundary particles puts it (in their label along a streak line or a time line, which
  /// is the label midpoint's place; by length along a cut), where that cubic departs from the
  /// quadratics through three of them by less than flat_split · ℓ. The particle's label is interpolated (on_path 0), and smoothing may move it.
  /// A filament left one face wide ends in a face whose inner edge is a diagonal, and is pruned
  /// later than with exact particles (its end reads wider than it is). 0: every new particle is
  /// placed as `insertion` says.
  double flat_split = 0.01;
  /// Remeshed: growth controls. Dye in an unsteady flow stretches without end, so a surface with
  /// edges ℓ everywhere grows without bound. Parts older than coarsen_age are meshed at a target
  /// edge of ℓ · age / coarsen_age (an edge takes the younger end's age); their splits,
  /// collapses, flips, smoothing and pruning all use that length. 0: ℓ at every age.
  double coarsen_age = 0;
  /// Remeshed: when the particles exceed this, the builder lowers the age at which coarsening
  /// starts (never raising it again) so the surface, meshed at the new lengths, needs about 70 %
  /// of it, and collapses until it fits: the oldest parts coarsen rather than the run stopping.
  /// 0: no budget (max_vertices still stops the run).
  std::size_t vertex_budget = 25'000'000;
  /// Remeshed: a region of interest. Particles that leave it stop, as at the domain's edge, and
  /// take their faces with them (counted as left_region). In 2D only x and y count.
  std::optional<Box<3>> region;
  Tolerance tolerance{1e-10, 1e-10};
  /// Gridded series only: move particles by bulk advection (advect::BatchAdvector, DOPRI5 at
  /// `tolerance`, slab by slab through whole steps) on this device. Unset: the integrated flow
  /// map of the streamed field.
  std::optional<advect::Device> device;
  std::size_t device_bytes = 0;     ///< steps the CUDA backend keeps on the device (0: half its free memory)
  /// With `device`: the particles stay with the backend (device memory for CUDA) from interval to
  /// interval; only particles placed anew go up, and positions and statuses come down. false:
  /// every particle's state goes up and down each interval (the baseline of orthofront-bench gpu-streak
  /// --particles-per-call). The same frames either way.
  bool resident_particles = true;
  /// With resident particles: the particles move on to the next break on the backend (from a
  /// thread of its own) while the rows of this break are refined and its frame is built; the
  /// particles inserted meanwhile catch up in one call, beside coarsening and the frame. false:
  /// in turn, each waiting for the other (the baseline of orthofront-bench gpu-streak --in-turn). The same
  /// frames either way.
  bool overlap_advection = true;
  std::size_t max_vertices = 50'000'000;  ///< particles (all rows) before the run stops early
  int max_refinement_rounds = 12;   ///< split passes after each time step
  /// false: fixed resolution (no particle inserted or removed), the baseline of bench-streak.
  bool adaptive = true;
  /// Finish each frame (quality, the sink) on a thread of its own while the particles move on;
  /// false: in line, before they move on (the baseline of orthofront-bench gpu-streak --frames-in-line).
  bool finish_frames_aside = true;
  std::function<bool(const StreakProgress&)> progress;  ///< false stops (frames are kept)
  std::string seed_name, field_name;  ///< how messages name the seed and field (may be empty)
};

/// One observation: the mesh (positions, faces; attributes release_time, s, age, speed,
/// particle_id, and for the remeshed mesh on_path; z = 0 for 2D flows) and its quality.
struct StreakFrame {
  int index = 0;
  double time = 0;
  Mesh mesh;
  QualityReport quality;
  std::size_t rows = 0;
};

struct StreakFrameRecord {
  int index = 0;
  double time = 0;
  std::size_t vertices = 0, faces = 0, rows = 0, dead_particles = 0;
  QualityReport quality;
  double max_edge = 0;              ///< longest mesh edge
  /// The frame's area and boundary length, and the size a mesh of well-shaped triangles with
  /// edges ℓ needs for them: 1.155 · area / ℓ² + boundary / ℓ vertices.
  double area = 0, boundary_length = 0, vertex_estimate = 0;
  std::size_t pieces = 0;           ///< connected pieces of the frame's mesh
  /// Remeshed: the age past which the frame is coarsened (infinity: none), and its longest edge
  /// over that edge's target length (ℓ, or longer where coarsened).
  double coarsen_age = 0, max_edge_ratio = 0;
  double area_pruned = 0;           ///< remeshed: area removed as thin filaments up to this frame
  double seconds = 0;               ///< building and handing over the frame (both parts)
  double build_seconds = 0;         ///< its vertices and faces alone (the particles wait for these)
  double finish_seconds = 0;        ///< its quality, longest edge and sink
};

struct StreakReport {
  int dimension = 0;
  bool streamed = false;
  bool complete = true;             ///< false: stopped early (cap, cancel, read error)
  std::string message;              ///< why it stopped early
  ParticleInsertion insertion = ParticleInsertion::exact;
  double release_begin = 0, release_end = 0, release_step = 0;
  double time_reached = 0;
  std::size_t seed_count = 0, rows_released = 0;
  std::size_t particle_steps = 0;   ///< particle advances over one time interval
  /// Simulated time advanced, summed over particles (intervals differ between runs, so this is
  /// the measure to compare their cost by).
  double particle_time = 0;
  std::size_t evaluations = 0;      ///< field evaluations
  std::size_t intervals = 0;        ///< time intervals advanced
  // Refinement.
  std::size_t s_insertions = 0;     ///< particles inserted along rows
  std::size_t rows_inserted = 0, row_particles = 0;  ///< rows inserted between rows, their particles
  std::size_t exact_insertions = 0, interpolated_insertions = 0;
  std::size_t s_removals = 0, rows_removed = 0;
  /// Remeshed: edges split (exact_insertions and interpolated_insertions say how their particles
  /// were placed), collapsed and flipped; faces removed where a particle stopped (left the
  /// domain, no data) and with them (a fan that would have met another at a point); strip faces
  /// not made at release because a corner had stopped.
  std::size_t splits = 0, collapses = 0, flips = 0;
  /// Remeshed, exact insertion: particles released again at a label moved toward the one whose
  /// path passes through the split edge's midpoint (counted per try).
  std::size_t steered_insertions = 0;
  /// Remeshed, exact insertion: particles placed by interpolation instead (of
  /// interpolated_insertions): their labels were tangled (a face beside the edge has its label
  /// triangle turned), their exact path ended farther than a quarter of the edge from its
  /// midpoint, or it would have turned a face over (those go to the edge's midpoint).
  std::size_t diverged_insertions = 0;
  /// Remeshed, exact insertion: of diverged_insertions, edges with an end that was itself placed
  /// by interpolation (not on its label's path); they are interpolated without trying the path.
  std::size_t inexact_ends = 0;
  /// Remeshed: of interpolated_insertions, particles placed at the midpoint of an edge where the
  /// surface is flat (flat_split), with no integration.
  std::size_t flat_insertions = 0;
  /// Remeshed: of interpolated_insertions, particles placed on a curved boundary of the dye by
  /// the cubic through four boundary particles, where its error estimate is within flat_split,
  /// with no integration.
  std::size_t curve_insertions = 0;
  std::size_t smoothed = 0;  ///< Remeshed: particles moved by smoothing (counted per move)
  /// Remeshed, growth controls: collapses of edges no shorter than collapse·ℓ (allowed only by
  /// a coarsened length), times the vertex budget lowered the coarsening age, and that age at
  /// the end (infinity: never coarsened).
  std::size_t coarsened = 0, budget_coarsenings = 0;
  double coarsen_age = 0;
  std::size_t faces_removed_at_stops = 0, strip_faces_skipped = 0;
  /// Remeshed: faces removed as filaments thinner than prune·ℓ (with the fans they would have
  /// pinched), and their area.
  std::size_t faces_pruned = 0;
  double area_pruned = 0;
  /// Remeshed: moves taken back and made in two because a face would have turned over, and
  /// faces that turned over all the same (in a move already 1/64 of the release step).
  std::size_t steps_shortened = 0, faces_turned = 0;
  std::string mesh;                 ///< "remeshed" or "rows"
  std::size_t left_domain = 0, no_data = 0;  ///< particles that stopped
  std::size_t left_region = 0;      ///< remeshed: particles that left the region of interest
  std::size_t max_particles = 0;
  std::vector<StreakFrameRecord> frames;
  CacheStatistics cache;            ///< streamed only
  std::size_t slow_evaluations = 0; ///< streamed: evaluations outside the pinned band
  /// advect_seconds: the driver's time on advection. With overlap_advection it waits for a move
  /// and its catch-up call to land and takes their positions (catch_up_seconds: the catch-up's
  /// part); both run beside refinement, coarsening and frames.
  double total_seconds = 0, advect_seconds = 0, refine_seconds = 0;
  /// Overlapped: calls that moved the particles inserted during a move, and those particles
  /// (coarsening may remove some of them before the move lands).
  std::size_t catch_up_calls = 0, catch_up_particles = 0;
  double catch_up_seconds = 0;      ///< of advect_seconds
  double catch_up_call_seconds = 0; ///< the catch-up calls on their thread (waiting for the move included)
  double take_seconds = 0;          ///< of advect_seconds: the set's positions taken into the rows
  /// releases_per_break > 1: rows released between breaks, the calls that moved them to the next
  /// break, and the driver's seconds on those calls (of advect_seconds).
  std::size_t rows_released_between = 0, release_calls = 0;
  double release_call_seconds = 0;
  double coarsen_seconds = 0;       ///< of refine_seconds
  double insert_seconds = 0;        ///< of refine_seconds: moving inserted particles to now (remeshed)
  /// The driver's time on frames: their vertices and faces, and waiting for the frame before to
  /// be finished. Finishing a frame (quality, the sink) runs beside the particles' advance:
  /// frame_finish_seconds, summed over frames.
  double frame_seconds = 0, frame_finish_seconds = 0;
  double wait_seconds = 0, io_seconds = 0, decode_seconds = 0;  ///< streamed only
  std::string device;               ///< bulk advection backend ("" when not used)
  advect::AdvectionStatistics bulk; ///< what it did
  advect::AdvectionStatistics bulk_batch;  ///< of which batch calls (catch-ups), not the set's moves
};

/// Called with each frame once it is built (e.g. to write it), from a thread of its own while the
/// particles move on: one frame at a time, in order, and every frame before the run returns. An
/// exception stops the run (at its next time step) and propagates; frames handed over before are
/// the caller's.
using StreakFrameSink = std::function<void(const StreakFrame&)>;

/// Streak surface of an analytic (or in-memory) unsteady field. Throws InvalidArgument naming
/// the value for bad times, frames, edge or factors, and for a seed with no particle inside the
/// domain at release_begin.
StreakReport build_streak_surface(const UnsteadyField& flow, const SeedCurve& seed,
                                  const StreakOptions& options, const StreakFrameSink& sink);

/// Streak surface of a time series read through `cache`, one step interval at a time. A read
/// error mid-run stops it (complete = false, message naming step and file); frames handed over
/// before stay valid. Throws InvalidArgument when two steps do not fit the budget.
StreakReport build_streak_surface(BrickCache& cache, const SeedCurve& seed,
                                  const StreakOptions& options, const StreakFrameSink& sink);

}  // namespace orthofront::spacetime
