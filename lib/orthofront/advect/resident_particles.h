#pragma once
/// Particles a backend keeps between calls (in device memory for CUDA): a caller that moves the
/// same particles interval after interval (a streak surface) sends only the particles it places
/// anew and reads positions and statuses back, instead of every particle's whole state up and down
/// each call. Slots are indices the caller hands out and takes back.
#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>

#include "orthofront/advect/batch_advector.h"

namespace orthofront::advect {

class ResidentParticles {
 public:
  /// Positions and statuses by slot, after the last advance (plain host arrays; valid until the
  /// next call on the object). Slots placed or parked since then read what they held before.
  struct View {
    const double* x[3] = {nullptr, nullptr, nullptr};
    const ParticleStatus* status = nullptr;
    std::size_t size = 0;  ///< slots held
  };

  virtual ~ResidentParticles() = default;
  /// Puts a moving particle at x[i] into slots[i] (the set grows to hold it); a slot placed twice
  /// holds the last placement.
  virtual void place(std::span<const std::uint32_t> slots, std::span<const std::array<double, 3>> x) = 0;
  /// Takes the particles in `slots` out: they do not move until placed again.
  virtual void park(std::span<const std::uint32_t> slots) = 0;
  /// Moves every moving particle from t_begin to t_end through `source`, each as a
  /// BatchAdvector::advect of particles at t_begin with no step size yet moves it (the same
  /// bits). A particle that stops keeps its status until placed again. Throws InvalidArgument
  /// when t_begin or t_end lies outside the source's times; after any other exception (a read
  /// error, the device) the set's contents are unspecified: place its particles again.
  virtual AdvectionStatistics advance(StepSource& source, double t_begin, double t_end,
                                      const MethodOptions& options) = 0;
  virtual View view() const = 0;
};

/// place() of this many slots or more is done in parallel (the new particles of a streak
/// surface's refinement: up to millions a call).
inline constexpr std::size_t kParallelPlacements = std::size_t{1} << 16;

/// place()'s argument check, the same for every set: a position for each slot.
void check_placement(std::span<const std::uint32_t> slots, std::span<const std::array<double, 3>> x);

/// Whether place() may write `slots` (each below `end`) in parallel: kParallelPlacements of them
/// or more, none twice (checked in parallel; a slot given twice keeps its last placement, which
/// only a walk in turn finds).
bool placeable_in_parallel(std::span<const std::uint32_t> slots, std::size_t end);

/// The largest of `slots` (not empty), found in parallel.
std::uint32_t largest_slot(std::span<const std::uint32_t> slots);

/// The set in host memory, moved by `backend`'s advect() (the CPU backend's, and any backend's
/// without a set of its own). Non-owning: `backend` must outlive it.
std::unique_ptr<ResidentParticles> make_host_resident_particles(BatchAdvector& backend);

}  // namespace orthofront::advect
