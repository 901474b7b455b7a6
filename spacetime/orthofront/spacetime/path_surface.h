#pragma once
/// Path surfaces of unsteady flows: the stream surface of the lifted field (v, c) in R^(d+1),
/// built by the flow-orthogonal engine, from analytic fields or from time series streamed
/// through the space-time BrickCache.
#include <cstddef>
#include <functional>
#include <optional>
#include <memory>
#include <string>
#include <variant>
#include <vector>

#include "orthofront/advect/batch_advector.h"
#include "orthofront/engine/surface_builder.h"
#include "orthofront/field/unsteady.h"
#include "orthofront/seed/seed_curve.h"
#include "orthofront/spacetime/brick_cache.h"
#include "orthofront/spacetime/bulk_front_integrator.h"
#include "orthofront/spacetime/streamed_field.h"

namespace orthofront::spacetime {

/// What the progress callback sees after each front step.
struct PathProgress {
  Progress engine;
  double t0 = 0, t1 = 0;
  double time_reached = 0;         ///< latest time evaluated so far
  double band_begin = 0, band_end = 0;  ///< time band the last step used
  std::size_t band_first = 0, band_last = 0;  ///< resident steps of the band (streamed only)
  bool streamed = false;
  CacheStatistics cache;           ///< streamed only
};

struct PathSurfaceOptions {
  StreamSurfaceOptions engine;     ///< engine options (edge ℓ, ...; max_steps bounds the steps)
  double t0 = 0;                   ///< seed time
  double t1 = 1;                   ///< the surface ends where its path lines reach t1
  /// c (length per time unit) of the lifted coordinate τ = c t; 0 derives it: the median speed
  /// |v(x, t0)| over the seed vertices (fallback: domain diagonal / (t1 - t0) where v = 0).
  double time_scale = 0;
  /// Bound on the front's time band, in time units (0: none). Vertices that wait near
  /// stagnation lag ever further behind in time and widen the band the cache must hold; with a
  /// bound, vertices more than max_band behind the lead keep pace (the front tilts in time there).
  double max_band = 0;
  std::function<bool(const PathProgress&)> progress;  ///< false stops (the surface is kept)
  /// How error messages name the seed and the field (e.g. as given on a command line); empty:
  /// "the seed curve" and the field's describe().
  std::string seed_name, field_name;
  /// Series read through a cache: move the front by bulk advection (whole time steps, slab by
  /// slab; bulk_front_integrator.h) on cpu or cuda; auto: cuda for fronts of at least
  /// kCudaFrontBreakEven vertices where a device is present, per vertex otherwise. Unset: per
  /// vertex through the streamed field. Insertions and velocities stay per vertex.
  std::optional<advect::Device> device;
  /// Fronts smaller than this stay per vertex (0: every front for cpu and cuda, the break-even
  /// size for auto).
  std::size_t device_min_vertices = 0;
  std::size_t device_bytes = 0;    ///< steps the CUDA backend keeps on the device (0: half its free memory)
  /// Surfaces of one pass over a cache (a batch): one backend and one set of device-resident
  /// steps for all of them (its device replaces `device`, its budget `device_bytes`).
  std::shared_ptr<SharedBulkAdvance> shared_bulk;
};

/// The time band of one front step: the range of times evaluated during it.
struct BandRecord {
  int step = 0;
  double t_min = 0, t_max = 0;     ///< over the front's evaluations (vertices and stages)
  double vertex_t_min = 0, vertex_t_max = 0;  ///< over the mesh vertices created by the step
  std::size_t first_step = 0, last_step = 0;  ///< time steps of the pinned units (streamed)
  std::size_t pinned_units = 0;    ///< bricks (or whole steps) pinned for the step (streamed)
};

struct PathReport {
  double time_scale = 0;
  std::string time_scale_source;   ///< "given", "median seed speed" or "domain / time range"
  double t0 = 0, t1 = 0;
  double time_reached = 0;         ///< max vertex time
  int dimension = 0;               ///< d of the flow
  bool streamed = false;
  bool complete = true;            ///< false: stopped by an error or a cancel
  std::string message;             ///< why it stopped early (names step and file on errors)
  std::vector<BandRecord> band;
  CacheStatistics cache;
  std::size_t slow_evaluations = 0;
  double total_seconds = 0;
  double wait_seconds = 0;         ///< engine thread blocked on data
  double io_seconds = 0;           ///< read_raw seconds (pipeline thread, overlapped)
  double decode_seconds = 0;       ///< decode seconds summed over threads
  double compute_seconds = 0;      ///< total - wait
  std::string device;              ///< bulk front advance backend ("" when not used)
  std::size_t device_min_vertices = 0;  ///< fronts from this size went through it
  std::size_t device_calls = 0;    ///< backend calls (one or two a front)
  advect::AdvectionStatistics device_statistics;
};

struct PathSurfaceResult {
  Mesh mesh;                       ///< positions in R^d (z = 0 for 2D flows), time = physical t
  std::vector<Vec3> spacetime_positions;  ///< 2D flows: (x, y, t) per vertex; empty for 3D
  SurfaceReport report;
  PathReport path;
};

/// What a path surface carries between front steps: the engine's state in the lifted space
/// (R^3 for 2D flows, R^4 for 3D flows) and the driver's own records. A surface continued from it
/// builds the same mesh, bit for bit, as one that never stopped.
struct PathState {
  std::variant<EngineState<3>, EngineState<4>> engine;
  double time_scale = 0;           ///< c, chosen when the surface began
  std::string time_scale_source;
  std::vector<BandRecord> band;
  double time_reached = 0;
  double observed_begin = 0, observed_end = 0;  ///< time range the last step evaluated
};

/// A path surface one front step at a time, for drivers that interleave several surfaces over
/// one cache or save checkpoints. The loop is `while (b.next()) b.step(); b.finish();`.
class PathSurfaceBuilder {
 public:
  /// From an in-memory field, or a series read through `cache` (which must outlive the builder).
  /// `resume`: continue from a saved state instead of the seed (same flow, seed and options).
  /// Throws what build_path_surface throws.
  PathSurfaceBuilder(const UnsteadyField& flow, const SeedCurve& seed, int seed_count,
                     const PathSurfaceOptions& options, const PathState* resume = nullptr);
  PathSurfaceBuilder(BrickCache& cache, const SeedCurve& seed, int seed_count,
                     const PathSurfaceOptions& options, const PathState* resume = nullptr);
  /// One of several surfaces that read `shared` (over `cache`) in one pass: the driver pins the
  /// band of all of them (front_samples, prediction) before their steps; next() pins nothing.
  PathSurfaceBuilder(StreamedField& shared, BrickCache& cache, const SeedCurve& seed,
                     int seed_count, const PathSurfaceOptions& options,
                     const PathState* resume = nullptr);
  ~PathSurfaceBuilder();
  PathSurfaceBuilder(const PathSurfaceBuilder&) = delete;
  PathSurfaceBuilder& operator=(const PathSurfaceBuilder&) = delete;

  /// Checks the stop conditions; when another step is due, pins its band (streamed) and
  /// records the last step's. False: the surface is done (or stopped by an error or a cancel).
  bool next();
  void step();
  void cancel();
  /// Earliest time on the front (a shared pass steps the surface that lags most first).
  double front_time();
  /// The most a front step advances a vertex in time (ℓ / c).
  double step_time() const;
  /// Appends the front's vertices as the band sees them (streamed builders).
  void front_samples(std::vector<FrontSample>& out);
  /// How far ahead of this surface's front its band must reach.
  BandPrediction prediction() const;
  int steps_done() const;
  /// The state for a checkpoint: take it after next() returned true, before step().
  PathState state() const;
  PathSurfaceResult finish();

  class Impl;

 private:
  std::unique_ptr<StreamedField> streamed_;
  std::unique_ptr<Impl> impl_;
};

/// Path surface of an analytic (or any in-memory) unsteady field from `seed` sampled with
/// `seed_count` vertices at time t0. Seeds use the first d coordinates.
/// Throws InvalidArgument for bad times, scale or a seed outside the domain (fewer than 2 seed
/// vertices inside it at t0, or where it has no data; the message names seed, field and domain).
PathSurfaceResult build_path_surface(const UnsteadyField& flow, const SeedCurve& seed,
                                     int seed_count, const PathSurfaceOptions& options);

/// Path surface of a time series read through `cache`. Errors reading a step mid-run stop the
/// surface (complete = false, message naming step and file); the mesh built so far is returned.
/// A band that cannot fit the budget at the start throws InvalidArgument naming the budget.
PathSurfaceResult build_path_surface(BrickCache& cache, const SeedCurve& seed, int seed_count,
                                     const PathSurfaceOptions& options);

}  // namespace orthofront::spacetime
