#pragma once
/// The stream-surface engine one front step at a time: a driver (a batch of surfaces sharing a
/// data pass, a job that checkpoints) decides when each step runs, and can save the whole state
/// between steps and continue from it later with the same result, bit for bit.
#include <memory>
#include <vector>

#include "orthofront/engine/front.h"
#include "orthofront/engine/front_integrator.h"
#include "orthofront/engine/stream_surface.h"

namespace orthofront {

/// Everything a surface carries from one front step to the next (plain data; the scratch
/// buffers of a step are not part of it).
template <int N>
struct EngineState {
  std::vector<Front<N>> fronts;
  int step = 0;                   ///< front steps done
  bool died_outside = false;      ///< the last step left no front because vertices left the domain
  std::int32_t next_front_id = 0;
  double elapsed_seconds = 0;     ///< wall clock spent so far (the time budget counts it)
  Mesh mesh;
  SurfaceReport report;           ///< counts and per-step records so far
};

template <int N>
class Engine;

template <int N>
class SurfaceBuilder {
 public:
  /// Validates the options and lays the seed as the first front (mesh vertices of step 0).
  /// Throws InvalidArgument as build_stream_surface does.
  SurfaceBuilder(const Field<N>& field, const Seed<N>& seed, const StreamSurfaceOptions& options);
  /// Continues from a saved state instead of the seed (validates the options; `field` and
  /// `seed` must be those the state was made with).
  SurfaceBuilder(const Field<N>& field, const Seed<N>& seed, const StreamSurfaceOptions& options,
                 EngineState<N> state);
  ~SurfaceBuilder();
  SurfaceBuilder(SurfaceBuilder&&) noexcept;
  SurfaceBuilder& operator=(SurfaceBuilder&&) noexcept;

  /// True while another step is due; false once a stop condition holds (fronts gone, step,
  /// vertex or time budget reached, cancelled). Checked before each step.
  bool next();
  /// Runs one front step (call only after next() returned true).
  void step();
  /// Stops the surface (reason: cancelled, report incomplete).
  void cancel();
  /// Asked inside long integrations of a step (thread-safe); true ends the step where its
  /// integrations got to and then the surface, as cancel() does. The time budget is checked
  /// there too.
  void set_stop_request(StopRequest request);
  /// Moves fronts of at least integrator->min_vertices() vertices through `integrator` (not
  /// owned; it must outlive the builder) instead of per vertex; nullptr: per vertex.
  void set_front_integrator(FrontIntegrator<N>* integrator);

  /// The front that the next step advances, N coordinates per vertex (valid until step()).
  FrontSnapshot front();
  Progress progress() const;
  int steps_done() const;

  /// The state after the last step, for a checkpoint.
  EngineState<N> state() const;
  /// Final counts, quality, times: the surface. The builder is spent afterwards.
  SurfaceResult finish();

 private:
  std::unique_ptr<Engine<N>> engine_;
};

extern template class SurfaceBuilder<3>;
extern template class SurfaceBuilder<4>;

}  // namespace orthofront
