#include "orthofront/advect/batch_advector.h"

#include <tbb/blocked_range.h>
#include <tbb/combinable.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_reduce.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <tuple>
#include <utility>

#include "orthofront/advect/advect_call.h"
#include "orthofront/advect/dispatch.h"
#include "orthofront/error.h"

#ifdef ORTHOFRONT_HAVE_CUDA
#include "orthofront/advect/cuda_advector.h"
#endif

namespace orthofront::advect {

const char* to_string(ParticleStatus status) {
  switch (status) {
    case ParticleStatus::moving: return "moving";
    case ParticleStatus::left_domain: return "left the domain";
    case ParticleStatus::no_data: return "no data";
    case ParticleStatus::time_bounds: return "outside the time range";
  }
  return "unknown";
}

void ParticleBatch::resize(std::size_t n) {
  const auto x0 = [&] { x[0].resize(n, 0.0); };
  const auto x1 = [&] { x[1].resize(n, 0.0); };
  const auto x2 = [&] { x[2].resize(n, 0.0); };
  const auto times = [&] { t.resize(n, 0.0); };
  const auto steps = [&] { h.resize(n, 0.0); };
  const auto counts = [&] { evaluations.resize(n, 0); };
  const auto statuses = [&] { status.resize(n, ParticleStatus::moving); };
  const auto stops = [&] {
    if (!stop.empty()) stop.resize(n, 0.0);
  };
  // A vector fills the elements it grows by on one thread: a large growth fills the arrays side
  // by side (a pooled batch of a streak surface's catch-ups grows by millions of particles).
  constexpr std::size_t kParallelGrowth = std::size_t{1} << 16;
  if (n > size() + kParallelGrowth) {
    tbb::parallel_invoke(x0, x1, x2, times, steps, counts, statuses, stops);
  } else {
    x0(), x1(), x2(), times(), steps(), counts(), statuses(), stops();
  }
}

ParticleState ParticleBatch::state(std::size_t i) const {
  ParticleState p;
  for (int d = 0; d < 3; ++d) p.x[d] = x[static_cast<std::size_t>(d)][i];
  p.t = t[i];
  p.h = h[i];
  p.evaluations = evaluations[i];
  p.status = status[i];
  return p;
}

void ParticleBatch::store(std::size_t i, const ParticleState& p) {
  for (int d = 0; d < 3; ++d) x[static_cast<std::size_t>(d)][i] = p.x[d];
  t[i] = p.t;
  h[i] = p.h;
  evaluations[i] = p.evaluations;
  status[i] = p.status;
}

namespace {
std::atomic<std::uint64_t> next_source_identity{1};
}  // namespace

StepSource::StepSource() : identity_(next_source_identity.fetch_add(1)) {}
StepSource::StepSource(const StepSource&) : identity_(next_source_identity.fetch_add(1)) {}

void copy_floats(const float* from, float* to, std::size_t n) {
  tbb::parallel_for(std::size_t{0}, std::size_t{16}, [&](std::size_t part) {
    const std::size_t lo = n * part / 16, hi = n * (part + 1) / 16;
    std::copy(from + lo, from + hi, to + lo);
  });
}

void StepSource::copy_step(std::size_t step, float* to) {
  copy_floats(acquire(step), to, geometry().point_count() * static_cast<std::size_t>(components()));
  release(step);
}

ResidentSteps::ResidentSteps(GridGeometry geometry, int components, std::vector<double> times,
                             std::vector<std::vector<float>> steps, bool zero_is_no_data)
    : geometry_(std::move(geometry)), components_(components), times_(std::move(times)),
      steps_(std::move(steps)), zero_is_no_data_(zero_is_no_data) {
  if (steps_.size() != times_.size())
    throw InvalidArgument("resident steps: " + std::to_string(steps_.size()) + " steps for " +
                          std::to_string(times_.size()) + " times");
  const std::size_t floats = geometry_.point_count() * static_cast<std::size_t>(components_);
  for (std::size_t k = 0; k < steps_.size(); ++k)
    if (steps_[k].size() != floats)
      throw InvalidArgument("resident steps: step " + std::to_string(k) + " has " +
                            std::to_string(steps_[k].size()) + " floats, the grid needs " +
                            std::to_string(floats));
}

GridTables::GridTables(const GridGeometry& g, int components, bool zero_is_no_data) {
  if ((g.dimension != 2 && g.dimension != 3) || (components != 2 && components != 3))
    throw InvalidArgument("bulk advection: a " + std::to_string(g.dimension) + "D grid with " +
                          std::to_string(components) +
                          " components is not supported (2D or 3D, 2 or 3 components)");
  view_.axes = g.dimension;
  view_.components = components;
  view_.rectilinear = g.rectilinear();
  view_.zero_is_no_data = zero_is_no_data;
  std::int64_t stride = components;
  for (int a = 0; a < 3; ++a) {
    const auto ua = static_cast<std::size_t>(a);
    AxisView& axis = view_.axis[a];
    view_.stride[a] = stride;
    stride *= g.size[ua];
    if (a >= g.dimension) continue;
    if (g.size[ua] < 2)
      throw InvalidArgument("bulk advection: axis " + std::to_string(a) + " has " +
                            std::to_string(g.size[ua]) + " sample(s); at least 2 are needed");
    axis.cells = g.size[ua] - 1;
    axis.lo = g.coordinate(a, 0);
    axis.hi = g.coordinate(a, axis.cells);
    if (g.rectilinear()) {
      coordinates_[ua] = g.axes[ua];
      inverse_widths_[ua].resize(static_cast<std::size_t>(axis.cells));
      for (std::size_t i = 0; i + 1 < coordinates_[ua].size(); ++i)
        inverse_widths_[ua][i] = 1.0 / (coordinates_[ua][i + 1] - coordinates_[ua][i]);
      axis.coordinates = coordinates_[ua].data();
      axis.inverse_width = inverse_widths_[ua].data();
    } else {
      axis.origin = g.origin[a];
      axis.inverse_spacing = 1.0 / g.spacing[a];
      axis.spacing = g.spacing[a];
    }
  }
}

void check_method(const MethodOptions& o) {
  const auto positive = [](double v) { return std::isfinite(v) && v > 0; };
  if (o.method == Method::rk4 && !positive(o.rk4_step))
    throw InvalidArgument("bulk advection: RK4 step " + std::to_string(o.rk4_step) +
                          " must be finite and > 0");
  if (o.method == Method::dopri5 && !(positive(o.absolute) && positive(o.relative)))
    throw InvalidArgument("bulk advection: DOPRI5 tolerances " + std::to_string(o.absolute) +
                          " / " + std::to_string(o.relative) + " must be finite and > 0");
  if (o.max_evaluations == 0) throw InvalidArgument("bulk advection: no evaluation budget");
}

SlabPlan plan_slabs(const std::vector<double>& times, ParticleBatch& particles, double t_end) {
  if (times.size() < 2)
    throw InvalidArgument("bulk advection needs at least 2 time steps, the series has " +
                          std::to_string(times.size()));
  SlabPlan plan;
  const double lo = times.front(), hi = times.back();
  const bool end_inside = t_end >= lo && t_end <= hi;
  const bool own_ends = !particles.stop.empty();
  if (own_ends && particles.stop.size() != particles.size())
    throw InvalidArgument("bulk advection: " + std::to_string(particles.stop.size()) +
                          " end times for " + std::to_string(particles.size()) + " particles");
  // The earliest and latest start of the moving particles (millions: in parallel; min and max
  // do not depend on the order).
  using Span = std::pair<double, double>;
  const auto [earliest, latest] = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, particles.size(), 16384), Span{t_end, t_end},
      [&](const tbb::blocked_range<std::size_t>& range, Span span) {
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
          if (particles.status[i] != ParticleStatus::moving) continue;
          const double t = particles.t[i];
          // An own end lies between t and t_end, both ends included (NaN fails both tests).
          const bool own_end_ok = !own_ends || (particles.stop[i] >= std::min(t, t_end) &&
                                                particles.stop[i] <= std::max(t, t_end));
          if (!end_inside || !(t >= lo && t <= hi) || !own_end_ok) {
            particles.status[i] = ParticleStatus::time_bounds;
            continue;
          }
          span.first = std::min(span.first, t);
          span.second = std::max(span.second, t);
        }
        return span;
      },
      [](const Span& a, const Span& b) {
        return Span{std::min(a.first, b.first), std::max(a.second, b.second)};
      });
  if (!end_inside) return plan;
  // A batch goes one way: forward when any particle lies before t_end. Particles on the other
  // side of t_end are not moved.
  plan.forward = earliest < t_end || latest <= t_end;
  const double from = plan.forward ? earliest : latest;
  const auto slab_of = [&](double t) {
    const auto it = std::upper_bound(times.begin(), times.end(), t);
    std::size_t k = static_cast<std::size_t>(std::max<std::ptrdiff_t>(it - times.begin() - 1, 0));
    return std::min(k, times.size() - 2);
  };
  std::size_t a = slab_of(std::min(from, t_end)), b = slab_of(std::max(from, t_end));
  // A span ending exactly on a step time does not need the slab after it.
  if (b > a && times[b] == std::max(from, t_end)) --b;
  for (std::size_t k = a; k <= b; ++k) plan.slabs.push_back(k);
  if (!plan.forward) std::reverse(plan.slabs.begin(), plan.slabs.end());
  return plan;
}

namespace {

class CpuAdvector final : public BatchAdvector {
 public:
  std::string name() const override { return "cpu"; }

  AdvectionStatistics advect(StepSource& source, ParticleBatch& particles, double t_end,
                             const MethodOptions& options) override {
    const auto start = std::chrono::steady_clock::now();
    AdvectionStatistics stats;
    const std::vector<double>& times = source.times();
    const SlabPlan plan = begin_call(times, particles, t_end, options, stats);
    const GridTables tables(source.geometry(), source.components(), source.zero_is_no_data());
    const bool own_ends = !particles.stop.empty();
    // The two steps of the current slab; moving on releases the one not needed any more.
    std::size_t held[2] = {SIZE_MAX, SIZE_MAX};
    const float* data[2] = {nullptr, nullptr};
    const auto hold = [&](std::size_t k) {
      for (int s = 0; s < 2; ++s)
        if (held[s] != SIZE_MAX && held[s] != k && held[s] != k + 1) {
          source.release(held[s]);
          held[s] = SIZE_MAX;
        }
      const float* out[2] = {nullptr, nullptr};
      for (std::size_t step = k; step <= k + 1; ++step) {
        int slot = held[0] == step ? 0 : held[1] == step ? 1 : -1;
        if (slot < 0) {
          slot = held[0] == SIZE_MAX ? 0 : 1;
          const auto host = std::chrono::steady_clock::now();
          data[slot] = source.acquire(step);
          stats.host_seconds += seconds_since(host);
          held[slot] = step;
          ++stats.steps_loaded;
        }
        out[step - k] = data[slot];
      }
      return std::pair{out[0], out[1]};
    };
    tbb::combinable<std::size_t> steps, evaluations;
    try {
      for (const std::size_t k : plan.slabs) {
        SlabView slab;
        slab.grid = tables.view();
        slab.t0 = times[k];
        slab.t1 = times[k + 1];
        std::tie(slab.step0, slab.step1) = hold(k);
        const double slab_t_end = slab_end(slab.t0, slab.t1, plan.forward, t_end);
        const auto compute = std::chrono::steady_clock::now();
        // Isolated: the caller may be an engine whose seed-shot legs wait as tasks; its wait
        // here takes none of them.
        tbb::this_task_arena::isolate([&] {
          dispatch_grid(slab.grid, [&]<int Axes, int Components, bool Rectilinear>() {
            tbb::parallel_for(
                tbb::blocked_range<std::size_t>(0, particles.size(), 256),
                [&](const tbb::blocked_range<std::size_t>& r) {
                  std::size_t local_steps = 0, local_evaluations = 0;
                  for (std::size_t i = r.begin(); i != r.end(); ++i) {
                    const double end = own_ends ? particles.stop[i] : t_end;
                    if (particles.status[i] != ParticleStatus::moving ||
                        !in_slab(slab.t0, slab.t1, plan.forward, particles.t[i], end))
                      continue;
                    ParticleState p = particles.state(i);
                    const std::uint32_t e0 = p.evaluations;
                    advance_particle<Axes, Components, Rectilinear>(
                        slab, p, own_ends ? slab_end(slab.t0, slab.t1, plan.forward, end) : slab_t_end,
                        options);
                    local_steps += p.steps;
                    local_evaluations += p.evaluations - e0;
                    particles.store(i, p);
                  }
                  steps.local() += local_steps;
                  evaluations.local() += local_evaluations;
                });
          });
        });
        stats.compute_seconds += seconds_since(compute);
        ++stats.slabs;
      }
    } catch (...) {
      for (const std::size_t s : held)
        if (s != SIZE_MAX) source.release(s);
      throw;
    }
    for (const std::size_t s : held)
      if (s != SIZE_MAX) source.release(s);
    stats.particle_steps = steps.combine(std::plus<>());
    stats.evaluations = evaluations.combine(std::plus<>());
    stats.total_seconds = seconds_since(start);
    return stats;
  }
};

}  // namespace

const char* to_string(Device device) {
  switch (device) {
    case Device::cpu: return "cpu";
    case Device::cuda: return "cuda";
    case Device::auto_select: return "auto";
  }
  return "unknown";
}

Device parse_device(const std::string& text) {
  if (text == "cpu") return Device::cpu;
  if (text == "cuda") return Device::cuda;
  if (text == "auto") return Device::auto_select;
  throw InvalidArgument("unknown device '" + text + "' (cpu, cuda or auto)");
}

bool cuda_available(std::string* why) {
#ifdef ORTHOFRONT_HAVE_CUDA
  return cuda_device_present(why);
#else
  if (why) *why = "this build has no CUDA backend (configure with -DORTHOFRONT_CUDA=ON where CUDA is installed)";
  return false;
#endif
}

double cuda_upload_rate(std::size_t bytes) {
#ifdef ORTHOFRONT_HAVE_CUDA
  if (cuda_available()) return cuda_pinned_upload_rate(bytes);
#endif
  static_cast<void>(bytes);
  return 0;
}

std::unique_ptr<BatchAdvector> make_cpu_advector() { return std::make_unique<CpuAdvector>(); }

std::unique_ptr<BatchAdvector> make_advector(Device device, std::size_t device_bytes) {
  if (device == Device::cpu) return make_cpu_advector();
  std::string why;
  const bool cuda = cuda_available(&why);
  if (device == Device::cuda && !cuda) throw InvalidArgument("--device cuda: " + why);
#ifdef ORTHOFRONT_HAVE_CUDA
  if (cuda) return make_cuda_advector(device_bytes);
#else
  static_cast<void>(device_bytes);  // nothing to keep on a device in a CPU build
#endif
  return make_cpu_advector();
}

}  // namespace orthofront::advect
