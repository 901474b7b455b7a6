#pragma once
/// Bulk advection of many particles through a gridded time series, slab by slab: the one seam
/// through which streak surfaces, flow maps and benchmarks move particles on a device. A backend
/// (CPU with oneTBB, CUDA when built) implements BatchAdvector; make_advector() picks it.
#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "orthofront/advect/particle_step.h"
#include "orthofront/field/grid.h"

namespace orthofront::advect {

/// Particles as a structure of arrays (coalesced loads on a device). A particle moves from its own
/// time t[i] to the common end time of a call, or to its own end time stop[i] when `stop` is given.
struct ParticleBatch {
  std::array<std::vector<double>, 3> x;
  std::vector<double> t;
  /// Empty, or one end time per particle, each between t[i] and the call's t_end (inclusive;
  /// the call's t_end is then the farthest of them). A particle whose end lies elsewhere gets
  /// time_bounds and does not move.
  std::vector<double> stop;
  std::vector<double> h;  ///< DOPRI5 step size carried between slabs and calls (0: none yet)
  std::vector<std::uint32_t> evaluations;
  std::vector<ParticleStatus> status;

  std::size_t size() const { return t.size(); }
  void resize(std::size_t n);
  ParticleState state(std::size_t i) const;
  void store(std::size_t i, const ParticleState& p);
};

/// The samples of a series of time steps on one grid. acquire/release are called from one
/// thread, in time order, at most three steps held at once.
class StepSource {
 public:
  StepSource();
  StepSource(const StepSource&);  // a copy is another source (its own identity)
  StepSource& operator=(const StepSource&) { return *this; }
  virtual ~StepSource() = default;
  /// Unique in the process: a backend may keep copies of a source's steps between calls under it
  /// (steps never change).
  std::uint64_t identity() const { return identity_; }
  virtual const GridGeometry& geometry() const = 0;
  virtual int components() const = 0;
  /// A zero vector marks land or solid (the series' convention, as StreamedField reads it).
  virtual bool zero_is_no_data() const = 0;
  virtual const std::vector<double>& times() const = 0;
  /// The point_count() × components() floats of step k, x fastest; valid until release(k).
  /// Throws what the reader throws.
  virtual const float* acquire(std::size_t step) = 0;
  virtual void release(std::size_t step) = 0;
  /// Copies step k's floats (what acquire gives) to `to`, e.g. a device upload's pinned staging;
  /// a source that assembles its steps from pieces writes them there directly, saving a copy.
  virtual void copy_step(std::size_t step, float* to);

 private:
  std::uint64_t identity_;
};

/// Copies n floats in parallel parts (one thread does not fill the memory bandwidth).
void copy_floats(const float* from, float* to, std::size_t n);

/// Steps held in memory (tests, benchmarks, analytic fields sampled on a grid).
class ResidentSteps final : public StepSource {
 public:
  ResidentSteps(GridGeometry geometry, int components, std::vector<double> times,
                std::vector<std::vector<float>> steps, bool zero_is_no_data = false);
  const GridGeometry& geometry() const override { return geometry_; }
  int components() const override { return components_; }
  bool zero_is_no_data() const override { return zero_is_no_data_; }
  const std::vector<double>& times() const override { return times_; }
  const float* acquire(std::size_t step) override { return steps_.at(step).data(); }
  void release(std::size_t) override {}

 private:
  GridGeometry geometry_;
  int components_;
  std::vector<double> times_;
  std::vector<std::vector<float>> steps_;
  bool zero_is_no_data_;
};

/// What a call did and where its time went.
struct AdvectionStatistics {
  std::size_t particles = 0;
  std::size_t slabs = 0;            ///< slabs run (pairs of consecutive steps)
  std::size_t particle_steps = 0;   ///< accepted integration steps, all particles
  std::size_t evaluations = 0;      ///< field samples
  std::size_t steps_loaded = 0;     ///< acquire() calls
  std::size_t steps_read_ahead = 0; ///< of those, read between calls (CUDA resident sets)
  std::size_t bytes_uploaded = 0;   ///< host-to-device bytes (0 on the CPU)
  std::size_t bytes_downloaded = 0; ///< device-to-host particle bytes behind the kernels
  double total_seconds = 0;
  double compute_seconds = 0;       ///< kernels (device events) or the parallel loops
  double upload_seconds = 0;        ///< host-to-device copies (device events)
  double host_seconds = 0;          ///< acquire() and staging copies on the host
  double overlap_seconds = 0;       ///< copies running while a kernel ran (device events)
  double download_seconds = 0;      ///< the particles' way back (device events)
  double pinned_seconds = 0;        ///< making page-locked host memory (CUDA: growing arrays)

  /// Adds another call's figures (totals over calls).
  AdvectionStatistics& operator+=(const AdvectionStatistics& o) {
    particles += o.particles;
    slabs += o.slabs;
    particle_steps += o.particle_steps;
    evaluations += o.evaluations;
    steps_loaded += o.steps_loaded;
    steps_read_ahead += o.steps_read_ahead;
    bytes_uploaded += o.bytes_uploaded;
    bytes_downloaded += o.bytes_downloaded;
    total_seconds += o.total_seconds;
    compute_seconds += o.compute_seconds;
    upload_seconds += o.upload_seconds;
    host_seconds += o.host_seconds;
    overlap_seconds += o.overlap_seconds;
    download_seconds += o.download_seconds;
    pinned_seconds += o.pinned_seconds;
    return *this;
  }
};

/// The grid as kernels see it, with the axis tables it points to.
class GridTables {
 public:
  GridTables(const GridGeometry& geometry, int components, bool zero_is_no_data);
  /// The view with pointers into this object's tables (host memory).
  const GridView& view() const { return view_; }
  const std::array<std::vector<double>, 3>& coordinates() const { return coordinates_; }
  const std::array<std::vector<double>, 3>& inverse_widths() const { return inverse_widths_; }

 private:
  GridView view_;
  std::array<std::vector<double>, 3> coordinates_, inverse_widths_;
};

/// The slabs a call runs, in order, and the times particles stop at in each.
struct SlabPlan {
  bool forward = true;
  std::vector<std::size_t> slabs;  ///< k: the slab [times[k], times[k + 1]]
};

/// Throws InvalidArgument naming the value when `options` cannot integrate (an RK4 step or a
/// tolerance that is not finite and > 0, no evaluation budget).
void check_method(const MethodOptions& options);

/// Marks particles whose time or t_end (or own end, `stop`) lies outside the series, or whose own
/// end is not between its time and t_end (time_bounds), and plans the slabs from the earliest
/// particle time to t_end. Throws InvalidArgument for fewer than two steps.
SlabPlan plan_slabs(const std::vector<double>& times, ParticleBatch& particles, double t_end);

class ResidentParticles;

class BatchAdvector {
 public:
  virtual ~BatchAdvector() = default;
  /// "cpu" or "cuda", with the device's name for CUDA.
  virtual std::string name() const = 0;
  /// Advances every moving particle from t[i] to t_end (forward or backward), slab by slab through
  /// `source`. Particles already at t_end stay as they are. Each particle's result does not
  /// depend on the others, the batch size or the number of threads.
  virtual AdvectionStatistics advect(StepSource& source, ParticleBatch& particles, double t_end,
                                     const MethodOptions& options) = 0;
  /// How many advect() calls may run at once from different threads (each with its own
  /// particles; sources are then read under the backend's own lock). 1: one at a time.
  virtual std::size_t max_concurrent_calls() const { return 1; }
  /// A set of particles kept between calls (resident_particles.h): in device memory for CUDA,
  /// host memory moved by advect() otherwise. The set must not outlive the backend.
  virtual std::unique_ptr<ResidentParticles> make_resident();
};

enum class Device : unsigned char { cpu, cuda, auto_select };

/// Front size from which `--device auto` advances a surface's front on a CUDA device: below it,
/// a call's latency costs more than the device saves (measured with `orthofront-bench front`:
/// docs/benchmarks/README.md, "A path surface's front on the GPU").
inline constexpr std::size_t kCudaFrontBreakEven = 4096;
/// The same for a stream surface of a steady grid: a vertex-step there is several times cheaper
/// on the CPU than a path surface's (no time interpolation), so a CUDA call pays only for far
/// larger fronts (figures: docs/benchmarks/measurements.md).
inline constexpr std::size_t kCudaSteadyFrontBreakEven = 65536;
const char* to_string(Device device);
/// "cpu", "cuda" or "auto"; throws InvalidArgument naming the value otherwise.
Device parse_device(const std::string& text);

/// True when this build has the CUDA backend and a CUDA device is present; otherwise `why` says
/// which is missing.
bool cuda_available(std::string* why = nullptr);

/// Host-to-device bytes per second of one copy of `bytes` from pinned memory (the best of three;
/// PCIe's rate, the floor of every upload). 0 without CUDA.
double cuda_upload_rate(std::size_t bytes);

/// The seam: the CPU backend, or the CUDA backend (cuda; auto when cuda_available()). Throws
/// InvalidArgument when cuda is asked for and cannot be had, saying why. `device_bytes`: what the
/// CUDA backend may keep of a series' steps on the device (0: half its free memory).
std::unique_ptr<BatchAdvector> make_advector(Device device, std::size_t device_bytes = 0);
std::unique_ptr<BatchAdvector> make_cpu_advector();

}  // namespace orthofront::advect
