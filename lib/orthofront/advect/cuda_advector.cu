#include "orthofront/advect/cuda_advector.h"

#include <cuda_runtime.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstring>
#include <string>
#include <vector>

#include "orthofront/advect/dispatch.h"
#include "orthofront/error.h"

namespace orthofront::advect {
namespace {

void check(cudaError_t e, const char* what) {
  if (e != cudaSuccess)
    throw Error(std::string("CUDA: ") + what + ": " + cudaGetErrorString(e));
}

/// Device memory for `n` objects of T, freed with the object.
template <class T>
class DeviceArray {
 public:
  DeviceArray() = default;
  explicit DeviceArray(std::size_t n) : n_(n) {
    if (n) check(cudaMalloc(&data_, n * sizeof(T)), "cudaMalloc");
  }
  ~DeviceArray() {
    if (data_) cudaFree(data_);
  }
  DeviceArray(const DeviceArray&) = delete;
  DeviceArray& operator=(const DeviceArray&) = delete;
  DeviceArray(DeviceArray&& o) noexcept : data_(o.data_), n_(o.n_) { o.data_ = nullptr; }
  DeviceArray& operator=(DeviceArray&& o) noexcept {
    std::swap(data_, o.data_);
    std::swap(n_, o.n_);
    return *this;
  }
  T* get() const { return data_; }
  void upload(const T* host, std::size_t n) {
    check(cudaMemcpy(data_, host, n * sizeof(T), cudaMemcpyHostToDevice), "upload");
  }
  void download(T* host, std::size_t n) const {
    check(cudaMemcpy(host, data_, n * sizeof(T), cudaMemcpyDeviceToHost), "download");
  }

 private:
  T* data_ = nullptr;
  std::size_t n_ = 0;
};

/// Page-locked host memory (asynchronous uploads need it).
class PinnedBuffer {
 public:
  explicit PinnedBuffer(std::size_t bytes) {
    check(cudaMallocHost(&data_, bytes), "cudaMallocHost");
  }
  ~PinnedBuffer() { cudaFreeHost(data_); }
  PinnedBuffer(const PinnedBuffer&) = delete;
  PinnedBuffer& operator=(const PinnedBuffer&) = delete;
  float* get() const { return static_cast<float*>(data_); }

 private:
  void* data_ = nullptr;
};

class Event {
 public:
  Event() { check(cudaEventCreate(&e_), "cudaEventCreate"); }
  ~Event() { cudaEventDestroy(e_); }
  Event(const Event&) = delete;
  Event& operator=(const Event&) = delete;
  cudaEvent_t get() const { return e_; }

 private:
  cudaEvent_t e_{};
};

class Stream {
 public:
  Stream() { check(cudaStreamCreateWithFlags(&s_, cudaStreamNonBlocking), "cudaStreamCreate"); }
  ~Stream() { cudaStreamDestroy(s_); }
  Stream(const Stream&) = delete;
  Stream& operator=(const Stream&) = delete;
  cudaStream_t get() const { return s_; }

 private:
  cudaStream_t s_{};
};

/// Particle arrays on the device (the kernel's view: plain pointers).
struct DeviceParticles {
  double* x[3];
  double* t;
  double* h;
  std::uint32_t* evaluations;
  ParticleStatus* status;
};

template <int Axes, int Components, bool Rectilinear, Method M>
__global__ void advance_kernel(SlabView slab, DeviceParticles p, std::size_t n, bool forward,
                               double t_end, MethodOptions options,
                               unsigned long long* steps_taken) {
  const std::size_t i = static_cast<std::size_t>(blockIdx.x) * blockDim.x + threadIdx.x;
  unsigned steps = 0;
  if (i < n && p.status[i] == ParticleStatus::moving &&
      in_slab(slab.t0, slab.t1, forward, p.t[i], t_end)) {
    ParticleState s;
    for (int d = 0; d < 3; ++d) s.x[d] = p.x[d][i];
    s.t = p.t[i];
    s.h = p.h[i];
    s.evaluations = p.evaluations[i];
    // One method per kernel: fewer registers than a branch between both.
    const double stop = slab_end(slab.t0, slab.t1, forward, t_end);
    if constexpr (M == Method::rk4)
      advance_rk4<Axes, Components, Rectilinear>(slab, s, stop, options);
    else
      advance_dopri5<Axes, Components, Rectilinear>(slab, s, stop, options);
    for (int d = 0; d < 3; ++d) p.x[d][i] = s.x[d];
    p.t[i] = s.t;
    p.h[i] = s.h;
    p.evaluations[i] = s.evaluations;
    p.status[i] = s.status;
    steps = s.steps;
  }
  // One atomic per warp.
  for (int offset = 16; offset > 0; offset /= 2) steps += __shfl_down_sync(0xffffffffu, steps, offset);
  if ((threadIdx.x & 31) == 0 && steps) atomicAdd(steps_taken, static_cast<unsigned long long>(steps));
}

/// Launches the kernel for a grid kind (dispatch_grid's callee), one method per kernel.
struct Launch {
  SlabView slab;
  DeviceParticles particles;
  std::size_t n;
  bool forward;
  double t_end;
  MethodOptions options;
  unsigned long long* steps_taken;
  unsigned blocks, threads;
  cudaStream_t stream;

  template <int Axes, int Components, bool Rectilinear>
  void operator()() const {
    if (options.method == Method::rk4)
      advance_kernel<Axes, Components, Rectilinear, Method::rk4><<<blocks, threads, 0, stream>>>(
          slab, particles, n, forward, t_end, options, steps_taken);
    else
      advance_kernel<Axes, Components, Rectilinear, Method::dopri5><<<blocks, threads, 0, stream>>>(
          slab, particles, n, forward, t_end, options, steps_taken);
  }
};

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

/// Seconds of [a0, a1] that overlap [b0, b1].
double overlap(double a0, double a1, double b0, double b1) {
  return std::max(0.0, std::min(a1, b1) - std::max(a0, b0));
}

class CudaAdvector final : public BatchAdvector {
 public:
  CudaAdvector() {
    int device = 0;
    check(cudaGetDevice(&device), "cudaGetDevice");
    cudaDeviceProp prop{};
    check(cudaGetDeviceProperties(&prop, device), "cudaGetDeviceProperties");
    name_ = std::string("cuda (") + prop.name + ")";
  }
  std::string name() const override { return name_; }

  AdvectionStatistics advect(StepSource& source, ParticleBatch& particles, double t_end,
                             const MethodOptions& options) override {
    const auto start = std::chrono::steady_clock::now();
    AdvectionStatistics stats;
    stats.particles = particles.size();
    const std::vector<double>& times = source.times();
    const SlabPlan plan = plan_slabs(times, particles, t_end);
    const std::size_t n = particles.size();
    if (plan.slabs.empty() || n == 0) {
      stats.total_seconds = seconds_since(start);
      return stats;
    }
    const GridTables tables(source.geometry(), source.components(), source.zero_is_no_data());

    // Axis tables and the grid view with device pointers.
    GridView grid = tables.view();
    std::array<DeviceArray<double>, 3> coordinates, inverse_widths;
    for (int a = 0; a < grid.axes && grid.rectilinear; ++a) {
      const auto ua = static_cast<std::size_t>(a);
      coordinates[ua] = DeviceArray<double>(tables.coordinates()[ua].size());
      coordinates[ua].upload(tables.coordinates()[ua].data(), tables.coordinates()[ua].size());
      inverse_widths[ua] = DeviceArray<double>(tables.inverse_widths()[ua].size());
      inverse_widths[ua].upload(tables.inverse_widths()[ua].data(),
                                tables.inverse_widths()[ua].size());
      grid.axis[a].coordinates = coordinates[ua].get();
      grid.axis[a].inverse_width = inverse_widths[ua].get();
    }

    // Particles stay on the device for the whole call.
    std::array<DeviceArray<double>, 3> px{DeviceArray<double>(n), DeviceArray<double>(n),
                                          DeviceArray<double>(n)};
    DeviceArray<double> pt(n), ph(n);
    DeviceArray<std::uint32_t> pe(n);
    DeviceArray<ParticleStatus> ps(n);
    for (std::size_t d = 0; d < 3; ++d) px[d].upload(particles.x[d].data(), n);
    pt.upload(particles.t.data(), n);
    ph.upload(particles.h.data(), n);
    pe.upload(particles.evaluations.data(), n);
    ps.upload(particles.status.data(), n);
    DeviceArray<unsigned long long> steps_taken(1);
    check(cudaMemset(steps_taken.get(), 0, sizeof(unsigned long long)), "cudaMemset");
    const DeviceParticles view{{px[0].get(), px[1].get(), px[2].get()}, pt.get(), ph.get(),
                               pe.get(), ps.get()};

    // Steps in the order the slabs use them; slab j uses sequence[j] and sequence[j + 1].
    std::vector<std::size_t> sequence;
    for (const std::size_t k : plan.slabs) {
      const std::size_t first = plan.forward ? k : k + 1, second = plan.forward ? k + 1 : k;
      if (sequence.empty()) sequence.push_back(first);
      sequence.push_back(second);
    }
    const std::size_t floats =
        source.geometry().point_count() * static_cast<std::size_t>(source.components());
    const std::size_t bytes = floats * sizeof(float);
    std::array<DeviceArray<float>, 3> device_steps;
    for (std::size_t i = 0; i < std::min<std::size_t>(3, sequence.size()); ++i)
      device_steps[i] = DeviceArray<float>(floats);
    PinnedBuffer staging0(bytes), staging1(bytes);
    float* staging[2] = {staging0.get(), staging1.get()};
    Stream compute, upload;
    Event base;
    std::vector<Event> upload_begin(sequence.size()), upload_end(sequence.size());
    std::vector<Event> kernel_begin(plan.slabs.size()), kernel_end(plan.slabs.size());
    check(cudaEventRecord(base.get(), compute.get()), "cudaEventRecord");
    check(cudaEventRecord(base.get(), upload.get()), "cudaEventRecord");

    const auto upload_step = [&](std::size_t i) {
      float* pinned = staging[i % 2];
      // The pinned buffer is free once the upload that last used it finished; the device buffer
      // once the kernels that read its old step finished.
      if (i >= 2) check(cudaEventSynchronize(upload_end[i - 2].get()), "cudaEventSynchronize");
      // (Buffer i % 3 held step i - 3, read by the kernels of slabs i - 4 and i - 3.)
      if (i >= 3)
        check(cudaStreamWaitEvent(upload.get(), kernel_end[i - 3].get(), 0), "cudaStreamWaitEvent");
      const auto host = std::chrono::steady_clock::now();
      const float* data = source.acquire(sequence[i]);
      tbb::parallel_for(std::size_t{0}, std::size_t{16}, [&](std::size_t part) {
        const std::size_t lo = floats * part / 16, hi = floats * (part + 1) / 16;
        std::memcpy(pinned + lo, data + lo, (hi - lo) * sizeof(float));
      });
      source.release(sequence[i]);
      stats.host_seconds += seconds_since(host);
      ++stats.steps_loaded;
      check(cudaEventRecord(upload_begin[i].get(), upload.get()), "cudaEventRecord");
      check(cudaMemcpyAsync(device_steps[i % 3].get(), pinned, bytes, cudaMemcpyHostToDevice,
                            upload.get()),
            "cudaMemcpyAsync");
      check(cudaEventRecord(upload_end[i].get(), upload.get()), "cudaEventRecord");
      stats.bytes_uploaded += bytes;
    };

    upload_step(0);
    upload_step(1);
    for (std::size_t j = 0; j < plan.slabs.size(); ++j) {
      const std::size_t k = plan.slabs[j];
      SlabView slab;
      slab.grid = grid;
      slab.t0 = times[k];
      slab.t1 = times[k + 1];
      const float* a = device_steps[j % 3].get();
      const float* b = device_steps[(j + 1) % 3].get();
      slab.step0 = plan.forward ? a : b;
      slab.step1 = plan.forward ? b : a;
      check(cudaStreamWaitEvent(compute.get(), upload_end[j].get(), 0), "cudaStreamWaitEvent");
      check(cudaStreamWaitEvent(compute.get(), upload_end[j + 1].get(), 0), "cudaStreamWaitEvent");
      check(cudaEventRecord(kernel_begin[j].get(), compute.get()), "cudaEventRecord");
      const unsigned threads = 128;
      const auto blocks = static_cast<unsigned>((n + threads - 1) / threads);
      dispatch_grid(grid, Launch{slab, view, n, plan.forward, t_end, options, steps_taken.get(),
                                  blocks, threads, compute.get()});
      check(cudaGetLastError(), "kernel launch");
      check(cudaEventRecord(kernel_end[j].get(), compute.get()), "cudaEventRecord");
      // The next step goes up while this slab computes.
      if (j + 2 < sequence.size()) upload_step(j + 2);
      ++stats.slabs;
    }
    check(cudaStreamSynchronize(compute.get()), "advection kernels");
    check(cudaStreamSynchronize(upload.get()), "uploads");

    for (std::size_t d = 0; d < 3; ++d) px[d].download(particles.x[d].data(), n);
    pt.download(particles.t.data(), n);
    ph.download(particles.h.data(), n);
    const std::vector<std::uint32_t> before = particles.evaluations;
    pe.download(particles.evaluations.data(), n);
    ps.download(particles.status.data(), n);
    unsigned long long steps = 0;
    steps_taken.download(&steps, 1);
    stats.particle_steps = static_cast<std::size_t>(steps);
    for (std::size_t i = 0; i < n; ++i) stats.evaluations += particles.evaluations[i] - before[i];

    const auto at = [&](const Event& e) {
      float ms = 0;
      check(cudaEventElapsedTime(&ms, base.get(), e.get()), "cudaEventElapsedTime");
      return 1e-3 * static_cast<double>(ms);
    };
    std::vector<std::array<double, 2>> kernels, uploads;
    for (std::size_t j = 0; j < kernel_begin.size(); ++j)
      kernels.push_back({at(kernel_begin[j]), at(kernel_end[j])});
    for (std::size_t i = 0; i < upload_begin.size(); ++i)
      uploads.push_back({at(upload_begin[i]), at(upload_end[i])});
    for (const auto& k : kernels) stats.compute_seconds += k[1] - k[0];
    for (const auto& u : uploads) {
      stats.upload_seconds += u[1] - u[0];
      for (const auto& k : kernels) stats.overlap_seconds += overlap(u[0], u[1], k[0], k[1]);
    }
    stats.total_seconds = seconds_since(start);
    return stats;
  }

 private:
  std::string name_;
};

}  // namespace

bool cuda_device_present(std::string* why) {
  int count = 0;
  const cudaError_t e = cudaGetDeviceCount(&count);
  if (e != cudaSuccess || count == 0) {
    if (why)
      *why = e != cudaSuccess ? std::string("no CUDA device: ") + cudaGetErrorString(e)
                              : std::string("no CUDA device found");
    return false;
  }
  return true;
}

std::unique_ptr<BatchAdvector> make_cuda_advector() { return std::make_unique<CudaAdvector>(); }

}  // namespace orthofront::advect
