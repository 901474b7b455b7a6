#pragma once
/// The front advance of a path surface by bulk advection: the front's vertices in the lifted
/// space (x, c t) are particles (x, t) that move by their own spans of time, all in one call of
/// an advect::BatchAdvector (CPU or CUDA) through whole time steps. Plugs into the engine at its
/// FrontIntegrator seam.
#include <cstddef>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "orthofront/advect/batch_advector.h"
#include "orthofront/advect/merging_advector.h"
#include "orthofront/engine/front_integrator.h"
#include "orthofront/field/unsteady.h"
#include "orthofront/spacetime/brick_cache.h"

namespace orthofront::spacetime {

/// Front size from which `--device auto` moves a path surface's front on a CUDA device.
inline constexpr std::size_t kCudaFrontBreakEven = advect::kCudaFrontBreakEven;

struct BulkFrontOptions {
  double time_scale = 1;            ///< c of the lifted coordinate τ = c (t - time_origin)
  double time_origin = 0;           ///< t at τ = 0
  TimeRange times;                  ///< the surface's [t0, t1]: a vertex stops at its end
  advect::MethodOptions method;
  std::size_t min_vertices = 0;     ///< smaller fronts go per vertex through the engine's field
};

/// Makes the backend when the first front large enough comes (so a surface whose fronts stay
/// small never starts a device); nullptr: none can be had, the fronts stay per vertex.
using BackendFactory = std::function<std::shared_ptr<advect::BatchAdvector>()>;

/// One backend and one view of a series' whole steps for the surfaces of a batch pass, which
/// step in parallel: the device keeps each step once for all of them, and the fronts that come
/// while a call runs go together in the next one (advect::MergingAdvector). The backend starts at
/// the first call.
class SharedBulkAdvance {
 public:
  /// Non-owning: `cache` must outlive it. `device` auto: CUDA where present, else none (fronts
  /// stay per vertex).
  /// `merge` false: the calls take turns unmerged (the baseline `batch --no-merge-fronts` measures).
  /// `concurrent_calls`: backend calls at once (0: what the backend allows).
  SharedBulkAdvance(BrickCache& cache, advect::Device device, std::size_t device_bytes,
                    bool merge = true, std::size_t concurrent_calls = 0);
  ~SharedBulkAdvance();
  advect::StepSource& steps();
  /// The backend (made on the first call; nullptr where auto found no CUDA device).
  std::shared_ptr<advect::BatchAdvector> backend();
  advect::Device device() const { return device_; }
  /// How the fronts' calls were merged (none while no backend was made).
  std::optional<advect::MergeStatistics> merge_statistics();
  /// Backend calls at once (0 while no backend was made).
  std::size_t concurrent_calls();

 private:
  advect::Device device_;
  std::size_t device_bytes_;
  bool merge_;
  std::size_t concurrent_calls_;
  std::unique_ptr<advect::StepSource> steps_;
  std::mutex mutex_;
  bool made_ = false;
  std::shared_ptr<advect::MergingAdvector> backend_;
};

/// Non-owning: `steps` must outlive it.
template <int N>
class BulkFrontIntegrator final : public FrontIntegrator<N> {
  static_assert(N == 3 || N == 4, "lifted spaces have N = 3 (2D flows) or N = 4 (3D flows)");

 public:
  static constexpr int d = N - 1;

  BulkFrontIntegrator(advect::StepSource& steps, std::shared_ptr<advect::BatchAdvector> backend,
                      BulkFrontOptions options);
  BulkFrontIntegrator(advect::StepSource& steps, BackendFactory make_backend,
                      BulkFrontOptions options);
  std::size_t min_vertices() const override { return options_.min_vertices; }
  bool integrate(std::span<const Vec<N>> x, std::span<const double> tau,
                 std::span<IntegrationResult<N>> out) override;
  /// The backend's name, or "" while none was made (or none could be).
  std::string backend_name() const { return backend_ ? backend_->name() : std::string(); }

  /// What the backend did, summed over calls, and the fronts and vertices it moved.
  const advect::AdvectionStatistics& statistics() const { return total_; }
  std::size_t calls() const { return calls_; }
  /// The range of times the particles spanned since the last take (lo > hi: nothing moved),
  /// then starts a new range.
  std::pair<double, double> take_time_range();

 private:
  void run(std::span<const Vec<N>> x, std::span<const double> tau,
           std::span<IntegrationResult<N>> out, bool forward);

  advect::StepSource& steps_;
  std::shared_ptr<advect::BatchAdvector> backend_;
  BackendFactory make_backend_;
  BulkFrontOptions options_;
  advect::ParticleBatch batch_;
  std::vector<std::size_t> index_;  ///< front vertex of each particle
  advect::AdvectionStatistics total_;
  std::size_t calls_ = 0;
  double lo_, hi_;
};

extern template class BulkFrontIntegrator<3>;
extern template class BulkFrontIntegrator<4>;

}  // namespace orthofront::spacetime
