#pragma once
/// Cell-aware steps: integrators end a step just past a kink of the field (a face between two
/// cells of an interpolated grid, where the interpolant's derivative jumps) instead of stepping
/// across it. A kink within kKinkMargin·h of a step's end costs an error of order
/// (kKinkMargin·h)² times the jump, a kink inside the step one of order h²: on gridded data the
/// steps rejected at faces were a third of all attempts. Shared by integrate/runge_kutta.h and
/// the bulk particle step (advect/particle_step.h, CPU and CUDA).

namespace orthofront {

/// How far past a kink a step that would cross it ends, as a share of the controller's step
/// size: the margin that cost the fewest field evaluations of those tried on real data (the
/// evaluation counts: docs/benchmarks/measurements.md). Larger margins leave a larger error
/// for the controller to reject; the smallest make steps that land just short of a face.
inline constexpr double kKinkMargin = 1e-4;

}  // namespace orthofront
