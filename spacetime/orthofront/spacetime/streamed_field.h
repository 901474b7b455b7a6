#pragma once
/// An unsteady field read from a time series on disk through a TimeStepCache: linear in time
/// between steps, multilinear in space. Evaluations read a published SlabView (lock-free); the
/// owner moves the band between front steps with update_band().
#include <atomic>
#include <cstddef>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "orthofront/field/unsteady.h"
#include "orthofront/spacetime/slab_view.h"
#include "orthofront/spacetime/time_step_cache.h"

namespace orthofront::spacetime {

class StreamedField final : public UnsteadyField {
 public:
  /// Non-owning: `cache` must outlive the field. Throws InvalidArgument for a series with fewer
  /// than two steps or a grid that is not 2D/3D with 2 or 3 components.
  explicit StreamedField(TimeStepCache& cache);

  int dimension() const override { return dimension_; }
  FieldStatus velocity(const Vec3& x, double t, Vec3& v) const override;
  FieldStatus velocity_jacobian(const Vec3& x, double t, Vec3& v, Mat3& J,
                                Vec3& dvdt) const override;
  Box<3> domain() const override { return box_; }
  TimeRange time_range() const override;
  std::string describe() const override;

  /// Pins the steps whose intervals cover [t_lo, t_hi], tells the cache the band (it evicts
  /// behind and prefetches ahead) and publishes a view of them. Not concurrent with evaluations:
  /// call it between front steps. Throws what the cache throws (names step and file).
  void update_band(double t_lo, double t_hi);
  /// Steps of the band published last.
  std::size_t band_first() const { return band_first_; }
  std::size_t band_last() const { return band_last_; }

  /// Evaluations that found a step outside the published view and pinned it themselves
  /// (correct but slow: a sign that the band was estimated too narrow).
  std::size_t slow_evaluations() const { return slow_.load(std::memory_order_relaxed); }
  /// The first error met by an evaluation (which then returned no_data); empty if none.
  std::string error() const;

 private:
  FieldStatus evaluate(const Vec3& x, double t, Vec3& v, Mat3* J, Vec3* dvdt) const;
  FieldStatus slow_path(const Vec3& x, double t, Vec3& v, Mat3* J, Vec3* dvdt) const;

  TimeStepCache& cache_;
  int dimension_ = 3;
  Box<3> box_;
  std::vector<TimeStepCache::Handle> pins_;
  std::shared_ptr<const SlabView> view_;      // owned here
  std::atomic<const SlabView*> current_{nullptr};
  std::size_t band_first_ = 0, band_last_ = 0;
  mutable std::atomic<std::size_t> slow_{0};
  mutable std::mutex error_mutex_;
  mutable std::string error_;
};

}  // namespace orthofront::spacetime
