#pragma once
/// The flow map of a gridded series by bulk advection: all particles of a call move together,
/// slab by slab through whole time steps, on the CPU or a CUDA device (advect::BatchAdvector).
/// Steps come from the BrickCache, bricks gathered into whole steps.
#include <cstddef>
#include <map>
#include <memory>
#include <mutex>
#include <vector>

#include "orthofront/advect/batch_advector.h"
#include "orthofront/advect/resident_particles.h"
#include "orthofront/spacetime/brick_cache.h"
#include "orthofront/spacetime/flow_map.h"

namespace orthofront::spacetime {

/// Whole time steps of a cached series (a step of one brick is used in place; bricks are gathered
/// into a step buffer, outside the cache's budget: at most three steps at once). A step is
/// gathered kGatherBricks bricks at a time, so the cache needs room for that many beside what
/// else it holds: the constructor reserves it (BrickCache::reserve_units).
class CachedSteps final : public advect::StepSource {
 public:
  static constexpr std::size_t kGatherBricks = 64;
  explicit CachedSteps(BrickCache& cache);
  const GridGeometry& geometry() const override { return cache_.series().geometry(); }
  int components() const override { return cache_.series().components(); }
  bool zero_is_no_data() const override { return cache_.series().zero_is_no_data(); }
  const std::vector<double>& times() const override { return cache_.times(); }
  const float* acquire(std::size_t step) override;
  void release(std::size_t step) override;
  /// Gathers the bricks straight into `to` (no step buffer of its own).
  void copy_step(std::size_t step, float* to) override;

 private:
  // The step's bricks, a group at a time, each into its place in `to` (a whole step).
  void gather(std::size_t step, float* to);
  struct Held {
    std::vector<BrickCache::Handle> pins;
    std::vector<float> gathered;
    const float* data = nullptr;
  };
  BrickCache& cache_;
  std::map<std::size_t, Held> held_;
};

/// Non-owning: `steps` must outlive the map. advect_all is the bulk call; advect() moves a batch
/// of one. Calls from several threads run at once where the backend allows it (CUDA lanes:
/// a streak surface's catch-up beside the move of its resident set), one at a time otherwise.
class BulkFlowMap final : public FlowMap {
 public:
  BulkFlowMap(advect::StepSource& steps, std::unique_ptr<advect::BatchAdvector> backend,
              advect::MethodOptions method);
  int dimension() const override { return steps_.geometry().dimension; }
  Advected advect(const Vec3& x, double t0, double t1) const override;
  std::size_t advect_all(std::span<Vec3> x, std::span<const double> t0, double t1,
                         std::span<ParticleStatus> status) const override;
  const std::string& backend_name() const { return name_; }
  /// Particles the backend keeps between calls (on the device for CUDA), moved by advance().
  std::unique_ptr<advect::ResidentParticles> make_resident() const;
  /// Moves the set's particles from t0 to t1 as advect_all would; returns the evaluations.
  std::size_t advance(advect::ResidentParticles& particles, double t0, double t1) const;
  /// What the backend did, summed over calls.
  advect::AdvectionStatistics statistics() const;
  /// Of those, the advect_all calls (a streak surface's catch-ups and single particles), without
  /// resident sets' advances.
  advect::AdvectionStatistics batch_statistics() const;

 private:
  advect::StepSource& steps_;
  std::unique_ptr<advect::BatchAdvector> backend_;
  advect::MethodOptions method_;
  std::string name_;
  // Taken for a whole call where the backend runs one call at a time.
  std::unique_lock<std::mutex> call_lock() const;
  mutable std::mutex call_mutex_;
  mutable std::mutex mutex_;  // the pool and the totals
  // Particle arrays of calls in flight, kept between calls (a streak surface makes one call per
  // interval): each call takes one out and puts it back.
  mutable std::vector<std::unique_ptr<advect::ParticleBatch>> batches_;
  mutable advect::AdvectionStatistics total_, batch_total_;
};

}  // namespace orthofront::spacetime
