#pragma once
/// An unsteady field read from a time series on disk through a BrickCache: linear in time
/// between steps, multilinear in space (the one kernel of field/multilinear.h, so the values are
/// those of the whole-step grid, bit for bit, whatever the bricks). Evaluations read a table of
/// pinned units (lock-free); between front steps the owner tells the field where the front is
/// (update_front) and the field pins what the next steps sample and prefetches what follows.
#include <atomic>
#include <cstddef>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <vector>

#include "orthofront/field/unsteady.h"
#include "orthofront/spacetime/brick_cache.h"

namespace orthofront::spacetime {

/// Time interval of t: k with times[k] <= t <= times[k+1] and the weight w of step k+1.
/// False when t lies outside [times.front(), times.back()].
bool locate_time(const std::vector<double>& times, double t, std::size_t& k, double& w);

/// A front vertex as the band sees it: position, time and velocity (zero when unknown).
struct FrontSample {
  Vec3 x = Vec3::Zero();
  double t = 0;
  Vec3 v = Vec3::Zero();
  /// c of the surface the vertex belongs to, where one band serves several surfaces with their
  /// own lifts (0: the prediction's time_scale).
  double time_scale = 0;
};

/// How far ahead of the front the band reaches.
struct BandPrediction {
  double edge = 0;          ///< ℓ: a front step moves a vertex at most about ℓ in (x, c t)
  double time_scale = 1;    ///< c of the lifted coordinate
  int pinned_steps = 2;     ///< front steps whose samples are pinned before the step runs
  int prefetch_steps = 8;   ///< front steps whose samples are prefetched
  double back_time = 0;     ///< time below a vertex's that it may still sample
};

struct BandUpdate {
  std::size_t pinned = 0, prefetched = 0;  ///< units
  std::size_t first_step = 0, last_step = 0;  ///< time steps of the pinned units
};

class StreamedField final : public UnsteadyField {
 public:
  /// Non-owning: `cache` must outlive the field. Throws InvalidArgument for a series with fewer
  /// than two steps or a grid that is not 2D/3D with 2 or 3 components.
  explicit StreamedField(BrickCache& cache);

  int dimension() const override { return dimension_; }
  FieldStatus velocity(const Vec3& x, double t, Vec3& v) const override;
  FieldStatus velocity_jacobian(const Vec3& x, double t, Vec3& v, Mat3& J,
                                Vec3& dvdt) const override;
  Box<3> domain() const override { return box_; }
  TimeRange time_range() const override;
  std::string describe() const override;
  /// Cell faces and time steps.
  double next_kink(const Vec3& x, double t, const Vec3& w, double w_t, double after,
                   double before) const override;

  /// Pins every unit of the steps whose intervals cover [t_lo, t_hi] (the whole domain). Not
  /// concurrent with evaluations. Throws what the cache throws.
  void update_band(double t_lo, double t_hi);
  /// Pins the units the front samples in the next `pinned_steps` front steps, predicted from each
  /// vertex's position, velocity and time, and prefetches those of the following steps. Units
  /// pinned before are released. Not concurrent with evaluations. Throws InvalidArgument naming
  /// the budget when the pinned units do not fit, or what the cache throws.
  BandUpdate update_front(std::span<const FrontSample> front, const BandPrediction& prediction);
  /// Velocity at a point from pinned data only (no loads); false when not resident.
  bool resident_velocity(const Vec3& x, double t, Vec3& v) const;

  /// Evaluations that found a unit outside the pinned set and pinned it themselves (correct but
  /// slower: the band was predicted too narrow).
  std::size_t slow_evaluations() const { return slow_.load(std::memory_order_relaxed); }
  /// The first error met by an evaluation (which then returned no_data); empty if none.
  std::string error() const;

 private:
  template <int Axes, int Components, bool WithJacobian>
  FieldStatus evaluate(const Vec3& x, double t, Vec3& v, Mat3* J, Vec3* dvdt,
                       bool resident_only) const;
  FieldStatus dispatch(const Vec3& x, double t, Vec3& v, Mat3* J, Vec3* dvdt,
                       bool resident_only) const;
  // Pointer to the floats of unit (step, brick): from the table, or pinned now (slow path);
  // nullptr on error or, with resident_only, when not pinned.
  // Slow-path pins are kept until the next update while they take at most a quarter of the
  // budget; beyond that `local` takes the pin for the one evaluation (empty until then: nothing
  // to build or tear down on the fast path, which is every evaluation of a well-predicted band).
  const float* unit(std::size_t step, std::size_t brick, bool resident_only,
                    std::vector<BrickCache::Handle>& local) const;
  void publish(std::vector<BrickCache::Handle>&& pins);
  // Releases the pins of units not in `keep` (sorted by step, then brick) and the slow path's,
  // so the budget can take the next band.
  void release_except(std::span<const BrickKey> keep);
  // Appends the units a box of point indices [lo, hi] touches at steps [k0, k1].
  void collect(const std::array<std::int64_t, 3>& lo, const std::array<std::int64_t, 3>& hi,
               std::size_t k0, std::size_t k1, std::vector<BrickKey>& out);
  std::int64_t point_below(int axis, double x) const;

  BrickCache& cache_;
  const GridGeometry& grid_;
  io::BrickLayout layout_;
  int dimension_ = 3;
  int components_ = 3;
  int kind_ = 0;
  bool zero_is_no_data_ = false;
  Box<3> box_;
  std::array<std::int64_t, 3> cells_{};
  std::array<double, 3> inverse_spacing_{};
  std::array<std::vector<double>, 3> inverse_width_;
  std::array<std::size_t, 3> stride_{};  // floats between neighbours inside a unit
  // table_[step * units + brick]: data of pinned units (nullptr: not pinned).
  std::unique_ptr<std::atomic<const float*>[]> table_;
  std::vector<BrickCache::Handle> pins_;
  mutable std::mutex extra_mutex_;
  mutable std::vector<BrickCache::Handle> extra_pins_;  // pinned by slow evaluations
  std::vector<std::uint64_t> stamp_;  // de-duplication of collected units
  std::uint64_t stamp_epoch_ = 0;
  mutable std::atomic<std::size_t> slow_{0};
  mutable std::mutex error_mutex_;
  mutable std::string error_;
  /// A unit could not be had: later misses fail at once (each would wait on the cache again).
  mutable std::atomic<bool> failed_{false};
};

}  // namespace orthofront::spacetime
