#include "orthofront/advect/cuda_advector.h"

#include <cuda_runtime.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <new>
#include <optional>
#include <thread>
#include <memory>
#include <cstdint>
#include <cstring>
#include <type_traits>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include "orthofront/advect/advect_call.h"
#include "orthofront/advect/dispatch.h"
#include "orthofront/advect/resident_particles.h"
#include "orthofront/error.h"
#include "orthofront/huge_pages.h"

#ifdef __linux__
#include <unistd.h>
#endif

namespace orthofront::advect {
namespace {

void check(cudaError_t e, const char* what) {
  if (e != cudaSuccess)
    throw Error(std::string("CUDA: ") + what + ": " + cudaGetErrorString(e));
}

/// Whether the device allocates in stream order (cudaMallocAsync): cudaFree waits for the whole
/// device, so a batch call that grows its arrays while a resident set's move runs would wait for
/// that move to end.
bool stream_ordered_memory() {
  static const bool supported = [] {
    int device = 0, pools = 0;
    return cudaGetDevice(&device) == cudaSuccess &&
           cudaDeviceGetAttribute(&pools, cudaDevAttrMemoryPoolsSupported, device) == cudaSuccess &&
           pools != 0;
  }();
  return supported;
}

/// Device memory for `n` objects of T, freed with the object; with a stream (where the device
/// allocates in stream order), allocated and freed in that stream's order, without waiting for
/// other streams' work.
template <class T>
class DeviceArray {
 public:
  DeviceArray() = default;
  explicit DeviceArray(std::size_t n, cudaStream_t stream = nullptr)
      : n_(n), stream_(stream && stream_ordered_memory() ? stream : nullptr) {
    if (!n) return;
    if (stream_)
      check(cudaMallocAsync(reinterpret_cast<void**>(&data_), n * sizeof(T), stream_), "cudaMallocAsync");
    else
      check(cudaMalloc(&data_, n * sizeof(T)), "cudaMalloc");
  }
  ~DeviceArray() {
    if (!data_) return;
    if (stream_)
      cudaFreeAsync(data_, stream_);
    else
      cudaFree(data_);
  }
  DeviceArray(const DeviceArray&) = delete;
  DeviceArray& operator=(const DeviceArray&) = delete;
  DeviceArray(DeviceArray&& o) noexcept : data_(o.data_), n_(o.n_), stream_(o.stream_) {
    o.data_ = nullptr;
  }
  DeviceArray& operator=(DeviceArray&& o) noexcept {
    std::swap(data_, o.data_);
    std::swap(n_, o.n_);
    std::swap(stream_, o.stream_);
    return *this;
  }
  T* get() const { return data_; }
  /// In the order of `stream`: work queued there after it reads the values. (A plain
  /// cudaMemcpy from pageable memory may return before its DMA ends, on the legacy stream,
  /// which a non-blocking stream's kernels do not wait for.) `host` may be reused on return.
  void upload(const T* host, std::size_t n, cudaStream_t stream) {
    check(cudaMemcpyAsync(data_, host, n * sizeof(T), cudaMemcpyHostToDevice, stream), "upload");
  }

 private:
  T* data_ = nullptr;
  std::size_t n_ = 0;
  cudaStream_t stream_ = nullptr;  ///< stream-ordered where set
};

/// Page-locked host memory (asynchronous uploads need it).
/// Large buffers are mapped on transparent huge pages, faulted in by parallel first touches and
/// then registered with the driver: cudaMallocHost pins 4 KiB page by page, which takes several
/// times longer for a buffer of a gigabyte (figures: docs/benchmarks/measurements.md). Where
/// that fails, cudaMallocHost.
class PinnedBuffer {
 public:
  explicit PinnedBuffer(std::size_t bytes) : bytes_(bytes) {
    if (bytes >= kHugePageBytes && map_and_register()) return;
    check(cudaMallocHost(&data_, bytes), "cudaMallocHost");
  }
  ~PinnedBuffer() {
    if (mapped_bytes_ == 0) {
      cudaFreeHost(data_);
      return;
    }
    cudaHostUnregister(data_);
#ifdef __linux__
    ::munmap(data_, mapped_bytes_);
#endif
  }
  PinnedBuffer(const PinnedBuffer&) = delete;
  PinnedBuffer& operator=(const PinnedBuffer&) = delete;
  float* get() const { return static_cast<float*>(data_); }
  template <class T>
  T* as() const { return static_cast<T*>(data_); }
  std::size_t bytes() const { return bytes_; }

 private:
  bool map_and_register() {
#ifdef __linux__
    const std::size_t whole = (bytes_ + kHugePageBytes - 1) & ~(kHugePageBytes - 1);
    // Touching pages the machine does not have would wake the OOM killer, where cudaMallocHost
    // fails with an error the pool can act on: only with room to spare in free memory.
    const long free_pages = ::sysconf(_SC_AVPHYS_PAGES), page = ::sysconf(_SC_PAGESIZE);
    if (free_pages <= 0 || page <= 0 ||
        whole > static_cast<std::size_t>(free_pages) / 2 * static_cast<std::size_t>(page))
      return false;
    // One huge page more, so that the block can start on a huge page's boundary.
    const std::size_t mapped = whole + kHugePageBytes;
    void* p = ::mmap(nullptr, mapped, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (p == MAP_FAILED) return false;
    auto* base = static_cast<char*>(p);
    const auto misalign = reinterpret_cast<std::uintptr_t>(base) & (kHugePageBytes - 1);
    char* block = misalign == 0 ? base : base + (kHugePageBytes - misalign);
    // The ends outside the aligned block go back (unmapping a part of a mapping is allowed).
    if (block > base) ::munmap(base, static_cast<std::size_t>(block - base));
    const std::size_t tail = mapped - static_cast<std::size_t>(block - base) - whole;
    if (tail > 0) ::munmap(block + whole, tail);
    ::madvise(block, whole, MADV_HUGEPAGE);
    // The kernel zeroes each page at its first touch: touched from the pool's threads at once
    // (without huge pages a touch faults 4 KiB and registering faults in the rest).
    const std::size_t pages = whole / kHugePageBytes;
    tbb::parallel_for(std::size_t{0}, pages, [&](std::size_t i) {
      static_cast<volatile char*>(block)[i * kHugePageBytes] = 0;
    });
    if (cudaHostRegister(block, whole, cudaHostRegisterPortable) != cudaSuccess) {
      cudaGetLastError();  // clear it: cudaMallocHost is tried next
      ::munmap(block, whole);
      return false;
    }
    data_ = block;
    mapped_bytes_ = whole;
    return true;
#else
    return false;
#endif
  }

  void* data_ = nullptr;
  std::size_t bytes_ = 0;
  std::size_t mapped_bytes_ = 0;  ///< the mapping registered, where not from cudaMallocHost
};

/// Page-locked buffers for arrays that grow (a lane's particles, a resident set's mirror and its
/// changes), kept for reuse instead of freed: cudaFreeHost waits for all of the device's work, so
/// a streak surface's catch-up call that grew its staging waited for the resident set's move on
/// the other stream, and the driver for the catch-up. A buffer given back serves a later take()
/// of up to four times less. Kept buffers stay page-locked until the pool goes (about twice the
/// users' peak, as they grow by doubling), unless making a new one fails: then they are freed
/// and the making tried once more.
/// (Making the next size ahead on a thread of its own was measured and not kept: with it the
/// catch-ups of orthofront-bench gpu-streak took longer, not shorter.)
class PinnedPool {
 public:
  /// A buffer of at least `bytes`: the smallest kept one that fits, or else a new one (its making
  /// counted in `seconds`).
  std::unique_ptr<PinnedBuffer> take(std::size_t bytes, double& seconds) {
    {
      std::lock_guard lock(mutex_);
      auto best = kept_.end();
      for (auto it = kept_.begin(); it != kept_.end(); ++it)
        if (fits((*it)->bytes(), bytes) && (best == kept_.end() || (*it)->bytes() < (*best)->bytes()))
          best = it;
      if (best != kept_.end()) {
        std::unique_ptr<PinnedBuffer> out = std::move(*best);
        kept_.erase(best);
        return out;
      }
    }
    const auto start = std::chrono::steady_clock::now();
    std::unique_ptr<PinnedBuffer> out;
    try {
      out = std::make_unique<PinnedBuffer>(bytes);
    } catch (const Error&) {
      // The memory the kept buffers lock may be what is missing (their freeing waits for the
      // device: only here).
      std::vector<std::unique_ptr<PinnedBuffer>> freed;
      {
        std::lock_guard lock(mutex_);
        freed.swap(kept_);
      }
      if (freed.empty()) throw;
      freed.clear();
      out = std::make_unique<PinnedBuffer>(bytes);
    }
    seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return out;
  }

  /// Keeps `buffer` for a later take() (or frees it where it cannot be kept). No copy may still
  /// read or write it.
  void give_back(std::unique_ptr<PinnedBuffer> buffer) noexcept {
    if (!buffer) return;
    std::lock_guard lock(mutex_);
    try {
      kept_.push_back(std::move(buffer));
    } catch (const std::bad_alloc&) {
      // Freed on return instead.
    }
  }

 private:
  /// A buffer of `size` bytes serves a request of `bytes` (not one many times smaller: the
  /// larger user would then make its own).
  static bool fits(std::size_t size, std::size_t bytes) { return size >= bytes && size / 4 <= bytes; }

  std::mutex mutex_;
  std::vector<std::unique_ptr<PinnedBuffer>> kept_;
};

/// Copies n objects between host arrays in parallel (into or out of pinned staging: one thread
/// does not fill the copy engine's bandwidth).
template <class T>
void parallel_copy(T* to, const T* from, std::size_t n) {
  const std::size_t parts = std::min<std::size_t>(16, std::max<std::size_t>(1, n / 65536));
  if (parts == 1) {
    if (n > 0) std::memcpy(to, from, n * sizeof(T));
    return;
  }
  tbb::parallel_for(std::size_t{0}, parts, [&](std::size_t part) {
    const std::size_t lo = n * part / parts, hi = n * (part + 1) / parts;
    if (hi > lo) std::memcpy(to + lo, from + lo, (hi - lo) * sizeof(T));
  });
}

/// Whether the first n elements of `values` are all the same bits (checked in parallel).
template <class T>
bool all_same(const std::vector<T>& values, std::size_t n) {
  if (n == 0) return true;
  const T* v = values.data();
  if (n <= 65536) {
    for (std::size_t i = 1; i < n; ++i)
      if (std::memcmp(v + i, v, sizeof(T)) != 0) return false;
    return true;
  }
  return tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(1, n, 65536), true,
      [&](const tbb::blocked_range<std::size_t>& range, bool same) {
        for (std::size_t i = range.begin(); same && i < range.end(); ++i)
          same = std::memcmp(v + i, v, sizeof(T)) == 0;
        return same;
      },
      [](bool a, bool b) { return a && b; });
}

template <class T>
__global__ void fill_kernel(T* to, T value, std::size_t n) {
  const std::size_t i = blockIdx.x * static_cast<std::size_t>(blockDim.x) + threadIdx.x;
  if (i < n) to[i] = value;
}

class Event {
 public:
  explicit Event(unsigned flags = cudaEventDefault) {
    check(cudaEventCreateWithFlags(&e_, flags), "cudaEventCreate");
  }
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
  explicit Stream(int priority) {
    check(cudaStreamCreateWithPriority(&s_, cudaStreamNonBlocking, priority), "cudaStreamCreateWithPriority");
  }
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
  const double* stop;  ///< own end times, or nullptr: the call's t_end
};

template <int Axes, int Components, bool Rectilinear, Method M>
__global__ void advance_kernel(SlabView slab, DeviceParticles p, std::size_t n, bool forward,
                               double t_end, MethodOptions options,
                               unsigned long long* counters) {
  const std::size_t i = static_cast<std::size_t>(blockIdx.x) * blockDim.x + threadIdx.x;
  unsigned steps = 0, evaluations = 0;
  const double end = p.stop && i < n ? p.stop[i] : t_end;
  if (i < n && p.status[i] == ParticleStatus::moving &&
      in_slab(slab.t0, slab.t1, forward, p.t[i], end)) {
    ParticleState s;
    for (int d = 0; d < 3; ++d) s.x[d] = p.x[d][i];
    s.t = p.t[i];
    s.h = p.h[i];
    s.evaluations = p.evaluations[i];
    // One method per kernel: fewer registers than a branch between both.
    const double stop = slab_end(slab.t0, slab.t1, forward, end);
    if constexpr (M == Method::rk4)
      advance_rk4<Axes, Components, Rectilinear>(slab, s, stop, options);
    else
      advance_dopri5<Axes, Components, Rectilinear>(slab, s, stop, options);
    for (int d = 0; d < 3; ++d) p.x[d][i] = s.x[d];
    p.t[i] = s.t;
    p.h[i] = s.h;
    evaluations = s.evaluations - p.evaluations[i];
    p.evaluations[i] = s.evaluations;
    p.status[i] = s.status;
    steps = s.steps;
  }
  // counters[0] += accepted steps, counters[1] += evaluations: one atomic each per warp.
  for (int offset = 16; offset > 0; offset /= 2) {
    steps += __shfl_down_sync(0xffffffffu, steps, offset);
    evaluations += __shfl_down_sync(0xffffffffu, evaluations, offset);
  }
  if ((threadIdx.x & 31) == 0 && steps) atomicAdd(counters, static_cast<unsigned long long>(steps));
  if ((threadIdx.x & 31) == 0 && evaluations)
    atomicAdd(counters + 1, static_cast<unsigned long long>(evaluations));
}

/// A change to a resident set: a particle placed in a slot, or the slot parked.
struct SlotChange {
  double x[3];
  std::uint32_t slot;
  std::uint32_t place;  ///< 1: placed at x; 0: parked
};

/// Changes to slots below n (a slot at or past n was never placed, or placed and parked again
/// before any advance: parked already, and maybe past the arrays' end).
__global__ void apply_changes_kernel(const SlotChange* changes, std::size_t m, std::size_t n,
                                     DeviceParticles p) {
  const std::size_t i = static_cast<std::size_t>(blockIdx.x) * blockDim.x + threadIdx.x;
  if (i >= m) return;
  const SlotChange c = changes[i];
  if (c.slot >= n) return;
  if (c.place) {
    for (int d = 0; d < 3; ++d) p.x[d][c.slot] = c.x[d];
    p.status[c.slot] = ParticleStatus::moving;
  } else {
    p.status[c.slot] = ParticleStatus::time_bounds;
  }
}

/// Every moving particle starts afresh at t (as a call's particles do: no step size yet);
/// *moving counts them (one atomic per warp).
__global__ void restart_kernel(DeviceParticles p, std::size_t n, double t, unsigned long long* moving) {
  const std::size_t i = static_cast<std::size_t>(blockIdx.x) * blockDim.x + threadIdx.x;
  unsigned count = 0;
  if (i < n && p.status[i] == ParticleStatus::moving) {
    p.t[i] = t;
    p.h[i] = 0;
    p.evaluations[i] = 0;
    count = 1;
  }
  for (int offset = 16; offset > 0; offset /= 2) count += __shfl_down_sync(0xffffffffu, count, offset);
  if ((threadIdx.x & 31) == 0 && count) atomicAdd(moving, static_cast<unsigned long long>(count));
}

/// Launches the kernel for a grid kind (dispatch_grid's callee), one method per kernel.
struct Launch {
  SlabView slab;
  DeviceParticles particles;
  std::size_t n;
  bool forward;
  double t_end;
  MethodOptions options;
  unsigned long long* counters;
  unsigned blocks, threads;
  cudaStream_t stream;

  template <int Axes, int Components, bool Rectilinear>
  void operator()() const {
    if (options.method == Method::rk4)
      advance_kernel<Axes, Components, Rectilinear, Method::rk4><<<blocks, threads, 0, stream>>>(
          slab, particles, n, forward, t_end, options, counters);
    else
      advance_kernel<Axes, Components, Rectilinear, Method::dopri5><<<blocks, threads, 0, stream>>>(
          slab, particles, n, forward, t_end, options, counters);
  }
};

/// Seconds of [a0, a1] that overlap [b0, b1].
double overlap(double a0, double a1, double b0, double b1) {
  return std::max(0.0, std::min(a1, b1) - std::max(a0, b0));
}

/// What one call needs of its own, so that calls from several threads run at once (a batch
/// pass's small fronts each leave most of the device idle): a stream, the particle arrays and
/// their pinned staging, the counters, the axis tables, and per step slot an event marking the
/// last kernel of this lane's current call that read it (an upload into that slot waits for it).
/// The device's highest stream priority.
int greatest_priority() {
  int least = 0, greatest = 0;
  check(cudaDeviceGetStreamPriorityRange(&least, &greatest), "cudaDeviceGetStreamPriorityRange");
  return greatest;
}

/// The particles a lane's arrays hold at least.
constexpr std::size_t kLaneParticles = std::size_t{1} << 16;

struct Lane {
  // A batch call (small, such as a streak surface's catch-up) runs on the urgent stream: the
  // device starts its blocks before the waiting blocks of a resident set's move on the normal one.
  Stream normal, urgent{greatest_priority()};
  cudaStream_t compute = nullptr;  ///< the stream of the call in flight
  std::array<DeviceArray<double>, 3> px;
  DeviceArray<double> pt, ph, pstop;
  DeviceArray<std::uint32_t> pe;
  DeviceArray<ParticleStatus> ps;
  std::size_t capacity = 0;
  std::unique_ptr<PinnedBuffer> host;  // pinned staging of the particle arrays
  DeviceArray<unsigned long long> counters{2};  // accepted steps, evaluations
  std::array<DeviceArray<double>, 3> coordinates, inverse_widths;
  std::vector<std::unique_ptr<Event>> used_event;  // per slot (kept between calls)
  std::vector<char> used;                          // per slot: read by this call's kernels
  std::vector<int> mine;                           // slots pinned: the slab's steps, the next
  Event base;                                      // a call's start
  /// The end of a call's work, waited for asleep: a thread spinning in a stream
  /// synchronization takes a core from the surfaces' own work and the cache's reads.
  Event done{cudaEventBlockingSync | cudaEventDisableTiming};
  PinnedBuffer counts{2 * sizeof(unsigned long long)};  // accepted steps, evaluations
  std::vector<std::unique_ptr<Event>> marks;       // a call's timing events
};

class CudaResident;

class CudaAdvector final : public BatchAdvector {
 public:
  explicit CudaAdvector(std::size_t device_bytes) : device_budget_(device_bytes) {
    int device = 0;
    check(cudaGetDevice(&device), "cudaGetDevice");
    cudaDeviceProp prop{};
    check(cudaGetDeviceProperties(&prop, device), "cudaGetDeviceProperties");
    name_ = std::string("cuda (") + prop.name + ")";
  }
  ~CudaAdvector() override {
    if (stager_.joinable()) {
      {
        std::lock_guard lock(ahead_mutex_);
        stop_stager_ = true;
        ahead_cv_.notify_all();
      }
      stager_.join();
    }
    // Nothing may still read the buffers freed next.
    for (const auto& lane : lanes_) {
      cudaStreamSynchronize(lane->normal.get());
      cudaStreamSynchronize(lane->urgent.get());
    }
    cudaStreamSynchronize(upload_.get());
  }
  std::string name() const override { return name_; }
  /// As many as the slots allow once they are laid out (lanes_in_use); 16 before the first call.
  std::size_t max_concurrent_calls() const override {
    std::lock_guard lock(mutex_);
    return slots_.empty() ? kMaxLanes : lanes_in_use();
  }

  AdvectionStatistics advect(StepSource& source, ParticleBatch& particles, double t_end,
                             const MethodOptions& options) override {
    const auto start = std::chrono::steady_clock::now();
    AdvectionStatistics stats;
    const std::vector<double>& times = source.times();
    const SlabPlan plan = begin_call(times, particles, t_end, options, stats);
    const std::size_t n = particles.size();
    if (plan.slabs.empty() || n == 0) {
      stats.total_seconds = seconds_since(start);
      return stats;
    }
    const std::size_t floats =
        source.geometry().point_count() * static_cast<std::size_t>(source.components());
    Lane& lane = begin_lane(floats, true);
    try {
      run(lane, source, particles, plan, t_end, options, stats);
    } catch (...) {
      cudaStreamSynchronize(lane.compute);  // nothing of the call's may still run
      end_lane(lane);
      throw;
    }
    end_lane(lane);
    stats.total_seconds = seconds_since(start);
    return stats;
  }

  std::unique_ptr<ResidentParticles> make_resident() override;

 private:
  friend class CudaResident;

  /// A device buffer for one step, with what it holds, an event for when its upload ends, and
  /// how many calls in flight read it (a slot read by another call is never overwritten).
  struct Slot {
    DeviceArray<float> data;
    std::uint64_t source = 0;
    std::size_t step = 0;
    std::uint64_t last_use = 0;
    Event ready_event;
    bool ready = false;
    bool filling = false;  ///< a lane is reading its step in (source and step already set)
    bool ahead = false;    ///< staged ahead, for no call yet (its reading not yet counted)
    double ahead_seconds = 0;  ///< the host seconds of that reading
    int pins = 0;
  };

  void run(Lane& lane, StepSource& source, ParticleBatch& particles, const SlabPlan& plan,
           double t_end, const MethodOptions& options, AdvectionStatistics& stats) {
    const DeviceParticles view = upload_particles(lane, particles, pinned_, stats);
    run_slabs(lane, source, view, particles.size(), plan, t_end, options, stats,
              [&] { return enqueue_download(lane, particles.size()); });
    copy_downloaded(lane, particles);
  }

  /// The slabs of `plan` over the n particles of `view` (device arrays) on the lane's stream;
  /// `download` enqueues the particles' way back behind the kernels, and the call returns once it
  /// has ended, with the counters and timings in `stats`.
  template <class Download>
  void run_slabs(Lane& lane, StepSource& source, const DeviceParticles& view, std::size_t n,
                 const SlabPlan& plan, double t_end, const MethodOptions& options,
                 AdvectionStatistics& stats, const Download& download) {
    const std::vector<double>& times = source.times();
    const cudaStream_t stream = lane.compute;
    const GridTables tables(source.geometry(), source.components(), source.zero_is_no_data());
    const GridView grid = device_grid(lane, tables);
    check(cudaMemsetAsync(lane.counters.get(), 0, 2 * sizeof(unsigned long long), stream),
          "cudaMemset");

    // Steps in the order the slabs use them; slab j uses sequence[j] and sequence[j + 1].
    std::vector<std::size_t> sequence;
    for (const std::size_t k : plan.slabs) {
      const std::size_t first = plan.forward ? k : k + 1, second = plan.forward ? k + 1 : k;
      if (sequence.empty()) sequence.push_back(first);
      sequence.push_back(second);
    }
    const Event& base = lane.base;
    std::vector<std::array<double, 2>> kernels, uploads;
    // Begin/end events of this call's work, kept by the lane between calls (making events costs
    // more than a small call's kernels).
    std::vector<std::unique_ptr<Event>>& marks = lane.marks;
    std::size_t marked = 0;
    const auto mark = [&](cudaStream_t s) {
      if (marked == marks.size()) marks.push_back(std::make_unique<Event>());
      check(cudaEventRecord(marks[marked]->get(), s), "cudaEventRecord");
      return marked++;
    };
    std::vector<std::array<std::size_t, 2>> kernel_marks, upload_marks;
    check(cudaEventRecord(base.get(), stream), "cudaEventRecord");
    {
      std::lock_guard lock(mutex_);
      check(cudaStreamWaitEvent(upload_.get(), base.get(), 0), "cudaStreamWaitEvent");
    }

    // Makes sequence[i] resident in a slot other than `keep0` and `keep1` (the current slab's),
    // pinned by this call, and returns the slot: a step already there, from an earlier call or
    // another lane's, is not uploaded again. A call pins at most three slots.
    const auto need = [&](std::size_t i, int keep0, int keep1) -> int {
      const std::size_t step = sequence[i];
      std::unique_lock lock(mutex_);
      const int slot_count = static_cast<int>(slots_.size());
      const auto pin = [&](int s) {
        if (std::find(lane.mine.begin(), lane.mine.end(), s) == lane.mine.end()) {
          lane.mine.push_back(s);
          ++slots_[s]->pins;
        }
        slots_[s]->last_use = ++clock_;
      };
      const auto holds = [&](int s) {
        return slots_[s]->source == source.identity() && slots_[s]->step == step;
      };
      for (;;) {
        int found = -1;
        for (int s = 0; s < slot_count && found < 0; ++s)
          if (holds(s)) found = s;
        if (found < 0) break;
        pin(found);
        // Another lane may still be reading the step in: wait for it (its upload is queued
        // when `filling` ends; the kernels wait for the ready event).
        slot_filled_.wait(lock, [&] { return !slots_[found]->filling; });
        if (holds(found)) {
          take_staged_ahead(*slots_[found], stats);
          return found;
        }
        drop_pin(lane, found);  // its read failed: the slot holds nothing now
      }
      // The least recently used slot no call has pinned; while there is none, wait for one
      // (lanes_in_use() keeps one free for a waiting call).
      int victim = -1;
      for (;;) {
        victim = least_recent_unpinned(keep0, keep1);
        if (victim >= 0) break;
        slot_freed_.wait(lock);
      }
      pin(victim);
      std::size_t upload_begin = 0;
      stats.host_seconds += fill_slot(lock, victim, source, step,
                                      [&] { upload_begin = mark(upload_.get()); },
                                      [&] { upload_marks.push_back({upload_begin, mark(upload_.get())}); });
      ++stats.steps_loaded;
      stats.bytes_uploaded += slot_floats_ * sizeof(float);
      return victim;
    };

    int a = need(0, -1, -1);
    int b = need(1, a, -1);
    for (std::size_t j = 0; j < plan.slabs.size(); ++j) {
      const std::size_t k = plan.slabs[j];
      SlabView slab;
      slab.grid = grid;
      slab.t0 = times[k];
      slab.t1 = times[k + 1];
      slab.step0 = slots_[plan.forward ? a : b]->data.get();
      slab.step1 = slots_[plan.forward ? b : a]->data.get();
      // (A pinned slot's ready event is not recorded again while this call runs.)
      for (const int s : {a, b})
        if (slots_[s]->ready)
          check(cudaStreamWaitEvent(stream, slots_[s]->ready_event.get(), 0), "cudaStreamWaitEvent");
      const std::size_t begin = mark(stream);
      const unsigned threads = 128;
      const auto blocks = static_cast<unsigned>((n + threads - 1) / threads);
      dispatch_grid(grid, Launch{slab, view, n, plan.forward, t_end, options,
                                  lane.counters.get(), blocks, threads, stream});
      check(cudaGetLastError(), "kernel launch");
      kernel_marks.push_back({begin, mark(stream)});
      // (Without the lock: a lane records only on slots it has pinned, which no upload takes;
      // the flags reach an uploading lane through the lock of the unpin.)
      for (const int s : {a, b}) {
        const auto us = static_cast<std::size_t>(s);
        if (!lane.used_event[us]) lane.used_event[us] = std::make_unique<Event>();
        check(cudaEventRecord(lane.used_event[us]->get(), stream), "cudaEventRecord");
        lane.used[us] = 1;
      }
      ++stats.slabs;
      if (j + 1 < plan.slabs.size()) {
        // The next step goes up (into the third slot) while this slab computes.
        const int c = need(j + 2, a, b);
        unpin(lane, a);  // read by this slab only: free for others once its kernel ends
        a = b;
        b = c;
      }
    }
    // The particles and the counters come down behind the kernels; one wait for all of it.
    const std::size_t down_begin = mark(stream);
    stats.bytes_downloaded += download();
    const std::size_t down_end = mark(stream);
    finish_call(lane);
    // This call's uploads have ended: its kernels waited for them.
    const auto* counts = lane.counts.as<unsigned long long>();
    stats.particle_steps = static_cast<std::size_t>(counts[0]);
    stats.evaluations = static_cast<std::size_t>(counts[1]);

    const auto at = [&](std::size_t m) {
      float ms = 0;
      check(cudaEventElapsedTime(&ms, base.get(), marks[m]->get()), "cudaEventElapsedTime");
      return 1e-3 * static_cast<double>(ms);
    };
    for (const auto& km : kernel_marks) kernels.push_back({at(km[0]), at(km[1])});
    for (const auto& um : upload_marks) uploads.push_back({at(um[0]), at(um[1])});
    for (const auto& kn : kernels) stats.compute_seconds += kn[1] - kn[0];
    stats.download_seconds += at(down_end) - at(down_begin);
    for (const auto& u : uploads) {
      stats.upload_seconds += u[1] - u[0];
      for (const auto& kn : kernels) stats.overlap_seconds += overlap(u[0], u[1], kn[0], kn[1]);
    }
  }

  /// Reads `step` of `source` into the pinned staging and uploads it into slot `victim` (pinned
  /// by the caller, under `lock`, which is let go meanwhile and held again on return) behind the
  /// kernels still reading the slot's old step. `before` and `after` run around the copy's
  /// enqueueing (the upload stream's order is the staging lock's). Returns the host seconds.
  template <class Before, class After>
  double fill_slot(std::unique_lock<std::mutex>& lock, int victim, StepSource& source, std::size_t step,
                   const Before& before, const After& after) {
    Slot& slot = *slots_[victim];
    // The slot is free once the kernels of calls in flight that read its old step finished
    // (calls that ended synchronized; nobody records these events again: the slot is pinned).
    const auto uv = static_cast<std::size_t>(victim);
    std::vector<cudaEvent_t> readers;
    for (const auto& other : lanes_)
      if (other->used.size() > uv && other->used[uv]) readers.push_back(other->used_event[uv]->get());
    slot.source = source.identity();
    slot.step = step;
    slot.filling = true;
    slot.ahead = false;
    lock.unlock();
    double host_seconds = 0;
    // Reading and staging the step holds the staging lock only: other lanes go on finding
    // their steps and launching kernels meanwhile.
    try {
      std::lock_guard staging(staging_mutex_);
      const int p = next_staging_;
      next_staging_ = 1 - next_staging_;
      // The pinned buffer is free once its last upload finished.
      if (staged_[p]) check(cudaEventSynchronize(staged_event_[p].get()), "cudaEventSynchronize");
      for (const cudaEvent_t e : readers)
        check(cudaStreamWaitEvent(upload_.get(), e, 0), "cudaStreamWaitEvent");
      const auto host = std::chrono::steady_clock::now();
      float* pinned = staging_[p]->get();
      source.copy_step(step, pinned);
      host_seconds = seconds_since(host);
      before();
      check(cudaMemcpyAsync(slot.data.get(), pinned, slot_floats_ * sizeof(float),
                            cudaMemcpyHostToDevice, upload_.get()),
            "cudaMemcpyAsync");
      after();
      check(cudaEventRecord(slot.ready_event.get(), upload_.get()), "cudaEventRecord");
      check(cudaEventRecord(staged_event_[p].get(), upload_.get()), "cudaEventRecord");
      staged_[p] = true;
    } catch (...) {
      lock.lock();
      slot.source = 0;  // holds nothing (identities start at 1)
      slot.filling = false;
      slot_filled_.notify_all();
      throw;
    }
    lock.lock();
    slot.ready = true;
    slot.filling = false;
    slot_filled_.notify_all();
    return host_seconds;
  }

  /// A call that finds its step staged ahead counts its reading and upload as its own (under
  /// mutex_): the totals hold every step read, and a call that reads none counts none.
  void take_staged_ahead(Slot& slot, AdvectionStatistics& stats) const {
    if (!slot.ahead) return;
    slot.ahead = false;
    ++stats.steps_loaded;
    ++stats.steps_read_ahead;
    stats.bytes_uploaded += slot_floats_ * sizeof(float);
    stats.host_seconds += slot.ahead_seconds;
  }

  /// Reads `step` of `source` into a slot on a thread of its own, for a later call: a resident
  /// set's next interval after its last step. A newer request replaces one not yet started;
  /// nothing is staged where no slot is free, the step is there already or the slots are laid
  /// out for another step size. A read that fails leaves the slot empty (the call that needs
  /// the step reads it again and reports the error).
  void stage_ahead(StepSource& source, std::size_t step) {
    std::lock_guard lock(ahead_mutex_);
    if (!stager_.joinable()) {
      try {
        stager_ = std::thread([this] { stager_loop(); });
      } catch (const std::system_error&) {
        return;  // no thread to spare: calls read their steps themselves
      }
    }
    ahead_request_ = AheadRequest{&source, step};
    ahead_cv_.notify_all();
  }

  /// Waits until no step is being staged ahead or waits to be (before a source may go).
  void finish_staging_ahead() {
    std::unique_lock lock(ahead_mutex_);
    ahead_request_.reset();
    ahead_cv_.wait(lock, [&] { return !ahead_busy_; });
  }

  void stager_loop() {
    std::unique_lock ahead(ahead_mutex_);
    for (;;) {
      ahead_cv_.wait(ahead, [&] { return stop_stager_ || ahead_request_.has_value(); });
      if (stop_stager_) return;
      const AheadRequest request = *ahead_request_;
      ahead_request_.reset();
      ahead_busy_ = true;
      ahead.unlock();
      try {
        stage_one_ahead(*request.source, request.step);
      } catch (...) {
        // The call that needs the step reads it itself.
      }
      ahead.lock();
      ahead_busy_ = false;
      ahead_cv_.notify_all();
    }
  }

  void stage_one_ahead(StepSource& source, std::size_t step) {
    std::unique_lock lock(mutex_);
    const std::size_t floats = source.geometry().point_count() * static_cast<std::size_t>(source.components());
    if (floats != slot_floats_) return;
    for (const auto& slot : slots_)
      if (slot->source == source.identity() && slot->step == step) return;  // there or coming
    const int victim = least_recent_unpinned(-1, -1);
    if (victim < 0) return;
    Slot& slot = *slots_[victim];
    ++slot.pins;
    slot.last_use = ++clock_;
    ++staging_ahead_;
    // (Under the lock again, whether the fill ended or threw.)
    const auto release = [&] {
      --slot.pins;
      --staging_ahead_;
      slot_freed_.notify_all();
      lane_free_.notify_all();
    };
    try {
      const double host = fill_slot(lock, victim, source, step, [] {}, [] {});
      slot.ahead = true;
      slot.ahead_seconds = host;
    } catch (...) {
      release();
      throw;
    }
    release();
  }

  /// The least recently used slot that no call pins, other than keep0 and keep1; -1 if there is
  /// none (under mutex_).
  int least_recent_unpinned(int keep0, int keep1) const {
    int victim = -1;
    for (int s = 0; s < static_cast<int>(slots_.size()); ++s) {
      if (s == keep0 || s == keep1 || slots_[s]->pins > 0) continue;
      if (victim < 0 || slots_[s]->last_use < slots_[victim]->last_use) victim = s;
    }
    return victim;
  }

  /// Calls that may be in flight at once: each pins up to three slots and waits for a third
  /// holding two, so one slot more than twice the calls keeps a slot free for a waiting call.
  std::size_t lanes_in_use() const {
    return slots_.size() < 3 ? 1 : std::clamp<std::size_t>((slots_.size() - 1) / 2, 1, kMaxLanes);
  }

  /// The lane lets go of slot s (under mutex_).
  void drop_pin(Lane& lane, int s) {
    const auto it = std::find(lane.mine.begin(), lane.mine.end(), s);
    if (it == lane.mine.end()) return;
    lane.mine.erase(it);
    --slots_[s]->pins;
    slot_freed_.notify_all();
  }

  void unpin(Lane& lane, int s) {
    std::lock_guard lock(mutex_);
    drop_pin(lane, s);
  }

  /// A free lane (made when every lane is busy), after the slots are laid out for steps of
  /// `floats` floats: a new step size waits until no call is in flight, then drops the slots.
  /// `urgent`: the call runs on the lane's high-priority stream (batch calls; a resident set's
  /// move, long, on the normal one).
  Lane& begin_lane(std::size_t floats, bool urgent) {
    if (floats == 0) throw Error("CUDA: a step of the source has no samples");
    std::unique_lock lock(mutex_);
    lane_free_.wait(lock, [&] {
      return floats == slot_floats_ ? in_flight_ < lanes_in_use() : in_flight_ == 0 && staging_ahead_ == 0;
    });
    if (floats != slot_floats_) prepare_buffers(floats);
    Lane* lane = nullptr;
    if (!free_lanes_.empty()) {
      lane = free_lanes_.back();
      free_lanes_.pop_back();
    } else {
      lanes_.push_back(std::make_unique<Lane>());
      lane = lanes_.back().get();
    }
    lane->compute = urgent ? lane->urgent.get() : lane->normal.get();
    lane->used_event.resize(slots_.size());
    lane->used.assign(slots_.size(), 0);
    lane->mine.reserve(3);
    ++in_flight_;
    return *lane;
  }

  /// Unpins the lane's slots and gives it back (its stream has nothing left to run).
  void end_lane(Lane& lane) {
    std::lock_guard lock(mutex_);
    for (const int s : lane.mine) --slots_[s]->pins;
    lane.mine.clear();
    std::fill(lane.used.begin(), lane.used.end(), 0);
    free_lanes_.push_back(&lane);
    --in_flight_;
    slot_freed_.notify_all();
    lane_free_.notify_all();
  }

  // Step buffers for steps of `floats` floats (as many as the device budget holds, at least
  // three; lanes_in_use() follows from their number) and two pinned staging buffers; a new size
  // drops what the slots held. Called with no call in flight.
  void prepare_buffers(std::size_t floats) {
    check(cudaDeviceSynchronize(), "cudaDeviceSynchronize");
    // Until the new slots are all there, the buffers fit no step size.
    slots_.clear();
    slot_floats_ = 0;
    const std::size_t step_bytes = floats * sizeof(float);
    std::size_t budget = device_budget_;
    if (budget == 0) {
      // Half the memory free now: room for the particles and for other users of the device.
      std::size_t free_bytes = 0, total_bytes = 0;
      check(cudaMemGetInfo(&free_bytes, &total_bytes), "cudaMemGetInfo");
      budget = free_bytes / 2;
    }
    const std::size_t count = std::clamp<std::size_t>(
        budget / std::max<std::size_t>(step_bytes, 1), 3, kMaxSlots);
    for (std::size_t i = 0; i < count; ++i) {
      slots_.push_back(std::make_unique<Slot>());
      slots_.back()->data = DeviceArray<float>(floats);
    }
    for (auto& p : staging_) p = std::make_unique<PinnedBuffer>(floats * sizeof(float));
    staged_[0] = staged_[1] = false;
    slot_floats_ = floats;
  }

  // The grid view with device pointers to its axis tables (uploaded for every call: small), on
  // the lane's stream, ahead of its kernels. (Copied on the legacy stream, a call's kernels
  // could read a rectilinear grid's tables before they arrived: under load, a call now and then
  // gave most of its particles other bits than the same call alone.)
  static GridView device_grid(Lane& lane, const GridTables& tables) {
    GridView grid = tables.view();
    const cudaStream_t s = lane.compute;
    for (int a = 0; a < grid.axes && grid.rectilinear; ++a) {
      const auto ua = static_cast<std::size_t>(a);
      lane.coordinates[ua] = DeviceArray<double>(tables.coordinates()[ua].size(), s);
      lane.coordinates[ua].upload(tables.coordinates()[ua].data(), tables.coordinates()[ua].size(), s);
      lane.inverse_widths[ua] = DeviceArray<double>(tables.inverse_widths()[ua].size(), s);
      lane.inverse_widths[ua].upload(tables.inverse_widths()[ua].data(),
                                     tables.inverse_widths()[ua].size(), s);
      grid.axis[a].coordinates = lane.coordinates[ua].get();
      grid.axis[a].inverse_width = lane.inverse_widths[ua].get();
    }
    return grid;
  }

  // The pinned staging of a lane's c particles: x, y, z, t, h, stop (doubles), evaluations,
  // status.
  static std::size_t lane_bytes(std::size_t c) {
    return c * (6 * sizeof(double) + sizeof(std::uint32_t) + sizeof(ParticleStatus));
  }

  // Particle arrays on the device and pinned staging for them on the host (grown, never shrunk;
  // the staging from `pinned`), filled from `particles` on the lane's stream (kernels follow in
  // order).
  static DeviceParticles upload_particles(Lane& lane, const ParticleBatch& particles,
                                          PinnedPool& pinned, AdvectionStatistics& stats) {
    const std::size_t n = particles.size();
    const cudaStream_t s = lane.compute;
    if (n > lane.capacity) {
      check(cudaStreamSynchronize(s), "cudaStreamSynchronize");
      // Doubling from 64 Ki particles, in the stream's order: a streak surface's catch-ups grow
      // from a thousand particles to millions, and each growth is costly (pinned memory, and
      // frees that wait for the resident set's move on the other stream), so there are few.
      const std::size_t c = std::max({n, 2 * lane.capacity, kLaneParticles});
      for (auto& x : lane.px) x = DeviceArray<double>(c, s);
      lane.pt = DeviceArray<double>(c, s);
      lane.ph = DeviceArray<double>(c, s);
      lane.pe = DeviceArray<std::uint32_t>(c, s);
      lane.ps = DeviceArray<ParticleStatus>(c, s);
      lane.pstop = DeviceArray<double>(c, s);
      // (The new staging first: a lane whose growth failed keeps its old one.)
      std::unique_ptr<PinnedBuffer> bigger = pinned.take(lane_bytes(c), stats.pinned_seconds);
      // (The old staging has no copy in flight: every call on the lane ended synchronized.)
      pinned.give_back(std::exchange(lane.host, std::move(bigger)));
      lane.capacity = c;
    }
    const bool own_ends = !particles.stop.empty();
    const Staged h = staged(lane);
    // An array of one value throughout (a fresh start: h = 0, no evaluations, all moving; one
    // start time for all) is filled on the device: PCIe is the slow part of a large batch.
    const auto up = [&](auto* device, auto* host, const auto& values) {
      using T = std::remove_cv_t<std::remove_reference_t<decltype(values[0])>>;
      if (n > 0 && all_same(values, n)) {
        const unsigned threads = 256;
        const auto blocks = static_cast<unsigned>((n + threads - 1) / threads);
        fill_kernel<T><<<blocks, threads, 0, s>>>(device, values[0], n);
        check(cudaGetLastError(), "particle fill");
        return;
      }
      parallel_copy(host, values.data(), n);
      check(cudaMemcpyAsync(device, host, n * sizeof(T), cudaMemcpyHostToDevice, s),
            "particle upload");
    };
    for (std::size_t d = 0; d < 3; ++d) up(lane.px[d].get(), h.x[d], particles.x[d]);
    up(lane.pt.get(), h.t, particles.t);
    up(lane.ph.get(), h.h, particles.h);
    if (own_ends) up(lane.pstop.get(), h.stop, particles.stop);
    up(lane.pe.get(), h.evaluations, particles.evaluations);
    up(lane.ps.get(), h.status, particles.status);
    return {{lane.px[0].get(), lane.px[1].get(), lane.px[2].get()}, lane.pt.get(), lane.ph.get(),
            lane.pe.get(), lane.ps.get(), own_ends ? lane.pstop.get() : nullptr};
  }

  // After the kernels (same stream): the particles back into the pinned staging.
  // Returns the bytes enqueued.
  static std::size_t enqueue_download(Lane& lane, std::size_t n) {
    const Staged h = staged(lane);
    const cudaStream_t s = lane.compute;
    std::size_t bytes = 0;
    const auto down = [&](auto* host, const auto* device) {
      check(cudaMemcpyAsync(host, device, n * sizeof(*host), cudaMemcpyDeviceToHost, s),
            "particle download");
      bytes += n * sizeof(*host);
    };
    for (std::size_t d = 0; d < 3; ++d) down(h.x[d], lane.px[d].get());
    down(h.t, lane.pt.get());
    down(h.h, lane.ph.get());
    down(h.evaluations, lane.pe.get());
    down(h.status, lane.ps.get());
    return bytes;
  }

  // The counters come down behind everything the lane's stream has; waits for all of it.
  static void finish_call(Lane& lane) {
    const cudaStream_t s = lane.compute;
    check(cudaMemcpyAsync(lane.counts.get(), lane.counters.get(), 2 * sizeof(unsigned long long),
                          cudaMemcpyDeviceToHost, s),
          "counter download");
    check(cudaEventRecord(lane.done.get(), s), "cudaEventRecord");
    check(cudaEventSynchronize(lane.done.get()), "advection kernels and particle download");
  }

  // From the pinned staging into the caller's arrays (after finish_call).
  static void copy_downloaded(Lane& lane, ParticleBatch& particles) {
    const std::size_t n = particles.size();
    const Staged h = staged(lane);
    for (std::size_t d = 0; d < 3; ++d) parallel_copy(particles.x[d].data(), h.x[d], n);
    parallel_copy(particles.t.data(), h.t, n);
    parallel_copy(particles.h.data(), h.h, n);
    parallel_copy(particles.evaluations.data(), h.evaluations, n);
    parallel_copy(particles.status.data(), h.status, n);
  }

  // The pinned staging arrays, laid out for the lane's capacity.
  struct Staged {
    double* x[3];
    double *t, *h, *stop;
    std::uint32_t* evaluations;
    ParticleStatus* status;
  };
  static Staged staged(const Lane& lane) {
    double* base = lane.host->as<double>();
    const std::size_t c = lane.capacity;
    Staged h{{base, base + c, base + 2 * c}, base + 3 * c, base + 4 * c, base + 5 * c,
             reinterpret_cast<std::uint32_t*>(base + 6 * c), nullptr};
    h.status = reinterpret_cast<ParticleStatus*>(h.evaluations + c);
    return h;
  }

  std::string name_;
  static constexpr std::size_t kMaxSlots = 1024;
  /// Calls in flight at most (fewer where the device budget holds few steps: lanes_in_use).
  static constexpr std::size_t kMaxLanes = 16;
  std::size_t device_budget_ = 0;  ///< bytes for resident steps (0: half the free memory)

  // Under mutex_: the slots and what they hold, the lanes.
  mutable std::mutex mutex_;
  std::condition_variable slot_freed_, slot_filled_, lane_free_;
  /// Held while a step is read from its source and staged (the source is read by one thread
  /// at a time; the two staging buffers and the upload stream's order are this lock's).
  std::mutex staging_mutex_;
  Stream upload_;
  std::vector<std::unique_ptr<Slot>> slots_;
  std::size_t slot_floats_ = 0;
  std::array<std::unique_ptr<PinnedBuffer>, 2> staging_;
  /// Page-locked memory of the lanes' particles and the resident sets (its own lock).
  PinnedPool pinned_;
  std::array<Event, 2> staged_event_;
  bool staged_[2] = {false, false};
  int next_staging_ = 0;
  std::uint64_t clock_ = 0;
  std::vector<std::unique_ptr<Lane>> lanes_;
  std::vector<Lane*> free_lanes_;
  std::size_t in_flight_ = 0;
  std::size_t staging_ahead_ = 0;
  ///< the stager is filling a slot (under mutex_)

  // The stager (stage_ahead): one request waiting at most, taken under ahead_mutex_.
  struct AheadRequest {
    StepSource* source;
    std::size_t step;
  };
  std::mutex ahead_mutex_;
  std::condition_variable ahead_cv_;
  std::optional<AheadRequest> ahead_request_;
  bool ahead_busy_ = false;
  bool stop_stager_ = false;
  std::thread stager_;
};

/// A resident set in device memory: changes wait on the host (one per slot, the last) until the
/// next advance uploads them with one copy and applies them with one kernel; after the kernels
/// the positions and statuses come down into pinned memory, which view() shows.
class CudaResident final : public ResidentParticles {
 public:
  explicit CudaResident(CudaAdvector& owner) : owner_(owner) {}
  ~CudaResident() override {
    owner_.finish_staging_ahead();  // the source may go once the set has gone
    // Nothing may still use the arrays freed next (an advance that threw synchronized its lane).
    cudaDeviceSynchronize();
    // A later set (the next surface of a batch) takes them without locking memory again.
    owner_.pinned_.give_back(std::move(host_));
    owner_.pinned_.give_back(std::move(staged_));
  }

  void place(std::span<const std::uint32_t> slots, std::span<const std::array<double, 3>> x) override {
    check_placement(slots, x);
    if (slots.size() >= kParallelPlacements) {  // (a smaller call takes no pass for its largest slot)
      const std::size_t end = std::size_t{largest_slot(slots)} + 1;
      if (placeable_in_parallel(slots, end)) {
        place_apart(slots, x, end);
        return;
      }
    }
    for (std::size_t i = 0; i < slots.size(); ++i) change(slots[i]) = {{x[i][0], x[i][1], x[i][2]}, slots[i], 1};
  }

  void park(std::span<const std::uint32_t> slots) override {
    for (const std::uint32_t s : slots)
      if (s < size_ || (s < change_of_.size() && change_of_[s] != 0)) change(s) = {{0, 0, 0}, s, 0};
  }

  AdvectionStatistics advance(StepSource& source, double t_begin, double t_end,
                              const MethodOptions& options) override {
    const auto start = std::chrono::steady_clock::now();
    AdvectionStatistics stats;
    check_method(options);
    const SlabPlan plan = plan_resident(source.times(), t_begin, t_end);
    const std::size_t floats =
        source.geometry().point_count() * static_cast<std::size_t>(source.components());
    Lane& lane = owner_.begin_lane(floats, false);
    try {
      const cudaStream_t s = lane.compute;
      const auto host = std::chrono::steady_clock::now();
      upload_changes(s, stats.pinned_seconds);
      // (Page-locked memory made for growth is counted apart, as for batch calls.)
      stats.host_seconds += seconds_since(host) - stats.pinned_seconds;
      if (size_ > 0) {
        // Restarted and counted: with none moving, no step is read.
        check(cudaMemsetAsync(lane.counters.get(), 0, sizeof(unsigned long long), s), "cudaMemset");
        const unsigned threads = 256;
        const auto blocks = static_cast<unsigned>((size_ + threads - 1) / threads);
        restart_kernel<<<blocks, threads, 0, s>>>(device_view(), size_, t_begin, lane.counters.get());
        check(cudaGetLastError(), "particle restart");
        CudaAdvector::finish_call(lane);
        stats.particles = static_cast<std::size_t>(lane.counts.as<unsigned long long>()[0]);
      }
      const auto download = [&]() -> std::size_t {
        if (size_ == 0) return 0;
        std::size_t bytes = 0;
        const auto down = [&](auto* to, const auto* from) {
          check(cudaMemcpyAsync(to, from, size_ * sizeof(*to), cudaMemcpyDeviceToHost, s),
                "particle download");
          bytes += size_ * sizeof(*to);
        };
        const Mirror m = mirror();
        for (std::size_t d = 0; d < 3; ++d) down(m.x[d], x_[d].get());
        down(m.status, status_.get());
        return bytes;
      };
      if (!plan.slabs.empty() && stats.particles > 0) {
        owner_.run_slabs(lane, source, device_view(), size_, plan, t_end, options, stats, download);
        // The step after the last this call read goes up while the caller works on: the next
        // interval's or a later one's (a streak surface's intervals are shorter than a step).
        const std::size_t last = plan.slabs.back();
        if (plan.forward ? last + 2 < source.times().size() : last >= 1)
          owner_.stage_ahead(source, plan.forward ? last + 2 : last - 1);
      } else {
        download();
        CudaAdvector::finish_call(lane);
      }
    } catch (...) {
      cudaStreamSynchronize(lane.compute);
      owner_.end_lane(lane);
      throw;
    }
    owner_.end_lane(lane);
    stats.total_seconds = seconds_since(start);
    return stats;
  }

  View view() const override {
    View v;
    if (!host_) return v;
    const Mirror m = mirror();
    for (int d = 0; d < 3; ++d) v.x[d] = m.x[d];
    v.status = m.status;
    v.size = size_;
    return v;
  }

 private:
  struct Mirror {
    double* x[3];
    ParticleStatus* status;
  };
  Mirror mirror() const {
    double* base = host_->as<double>();
    return {{base, base + capacity_, base + 2 * capacity_},
            reinterpret_cast<ParticleStatus*>(base + 3 * capacity_)};
  }
  DeviceParticles device_view() const {
    return {{x_[0].get(), x_[1].get(), x_[2].get()}, t_.get(), h_.get(), evaluations_.get(),
            status_.get(), nullptr};
  }

  // place() of distinct slots (all below `end`), in parallel: the changes one change() after
  // the other makes (a slot's change kept where it has one, new ones appended in order), found
  // in blocks counted beforehand.
  void place_apart(std::span<const std::uint32_t> slots, std::span<const std::array<double, 3>> x,
                   std::size_t end) {
    if (end > change_of_.size()) change_of_.resize(std::max(end, change_of_.size() * 3 / 2), 0);
    constexpr std::size_t kBlock = 16384;
    const std::size_t blocks = (slots.size() + kBlock - 1) / kBlock;
    std::vector<std::size_t> fresh(blocks + 1, 0);  // [b + 1]: slots of block b without a change
    tbb::parallel_for(std::size_t{0}, blocks, [&](std::size_t b) {
      for (std::size_t i = b * kBlock; i < std::min(slots.size(), (b + 1) * kBlock); ++i)
        fresh[b + 1] += change_of_[slots[i]] == 0;
    });
    for (std::size_t b = 0; b < blocks; ++b) fresh[b + 1] += fresh[b];
    const std::size_t base = changes_.size();
    changes_.resize(base + fresh[blocks]);
    tbb::parallel_for(std::size_t{0}, blocks, [&](std::size_t b) {
      std::size_t k = base + fresh[b];
      for (std::size_t i = b * kBlock; i < std::min(slots.size(), (b + 1) * kBlock); ++i) {
        std::uint32_t& at = change_of_[slots[i]];
        if (at == 0) at = static_cast<std::uint32_t>(++k);
        changes_[at - 1] = {{x[i][0], x[i][1], x[i][2]}, slots[i], 1};
      }
    });
  }

  SlotChange& change(std::uint32_t slot) {
    if (slot >= change_of_.size()) change_of_.resize(std::max<std::size_t>(slot + 1, change_of_.size() * 3 / 2), 0);
    std::uint32_t& k = change_of_[slot];
    if (k == 0) {
      changes_.push_back({});
      k = static_cast<std::uint32_t>(changes_.size());
    }
    return changes_[k - 1];
  }

  // The pinned mirror of c slots: x, y, z, status.
  static std::size_t mirror_bytes(std::size_t c) { return c * (3 * sizeof(double) + sizeof(ParticleStatus)); }

  // Grows the arrays to hold every changed slot (keeping what they hold; new slots parked),
  // then uploads the changes and applies them, on stream s.
  void upload_changes(cudaStream_t s, double& pinned_seconds) {
    // (Millions of changes after a streak surface's refinement: the walks over them in parallel.)
    const std::size_t needed = tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, changes_.size(), 65536), size_,
        [&](const tbb::blocked_range<std::size_t>& r, std::size_t top) {
          for (std::size_t i = r.begin(); i != r.end(); ++i)
            if (changes_[i].place) top = std::max<std::size_t>(top, std::size_t{changes_[i].slot} + 1);
          return top;
        },
        [](std::size_t a, std::size_t b) { return std::max(a, b); });
    if (needed > capacity_) {
      // Doubling from a million: each growth allocates pinned memory, slow to get.
      const std::size_t c = std::max({needed, 2 * capacity_, std::size_t{1} << 20});
      const auto grow = [&](auto& array) {
        using A = std::remove_reference_t<decltype(array)>;
        A bigger(c);
        if (size_ > 0)
          check(cudaMemcpyAsync(bigger.get(), array.get(), size_ * sizeof(*array.get()),
                                cudaMemcpyDeviceToDevice, s),
                "resident particles: copy");
        check(cudaStreamSynchronize(s), "cudaStreamSynchronize");
        array = std::move(bigger);
      };
      for (auto& a : x_) grow(a);
      grow(t_);
      grow(h_);
      grow(evaluations_);
      grow(status_);
      const unsigned threads = 256;
      const auto blocks = static_cast<unsigned>((c - size_ + threads - 1) / threads);
      fill_kernel<ParticleStatus><<<blocks, threads, 0, s>>>(status_.get() + size_,
                                                            ParticleStatus::time_bounds, c - size_);
      check(cudaGetLastError(), "resident particles: park");
      std::unique_ptr<PinnedBuffer> bigger = owner_.pinned_.take(mirror_bytes(c), pinned_seconds);
      owner_.pinned_.give_back(std::exchange(host_, std::move(bigger)));  // nothing reads it now
      capacity_ = c;
    }
    size_ = needed;
    if (changes_.empty()) return;
    const std::size_t m = changes_.size();
    if (m > staged_capacity_) {
      check(cudaStreamSynchronize(s), "cudaStreamSynchronize");  // the old buffers' last copy
      // (The capacity changes with its buffers: a growth that failed leaves the old ones.)
      const std::size_t capacity = std::max(m, staged_capacity_ + staged_capacity_ / 2);
      std::unique_ptr<PinnedBuffer> bigger = owner_.pinned_.take(capacity * sizeof(SlotChange), pinned_seconds);
      DeviceArray<SlotChange> device_bigger(capacity);
      owner_.pinned_.give_back(std::exchange(staged_, std::move(bigger)));
      device_changes_ = std::move(device_bigger);
      staged_capacity_ = capacity;
    } else {
      check(cudaStreamSynchronize(s), "cudaStreamSynchronize");  // the staging's last copy
    }
    parallel_copy(staged_->as<SlotChange>(), changes_.data(), m);
    check(cudaMemcpyAsync(device_changes_.get(), staged_->as<SlotChange>(), m * sizeof(SlotChange),
                          cudaMemcpyHostToDevice, s),
          "resident particles: changes");
    const unsigned threads = 256;
    apply_changes_kernel<<<static_cast<unsigned>((m + threads - 1) / threads), threads, 0, s>>>(
        device_changes_.get(), m, size_, device_view());
    check(cudaGetLastError(), "resident particles: apply");
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, m, 65536), [&](const tbb::blocked_range<std::size_t>& r) {
      for (std::size_t i = r.begin(); i != r.end(); ++i) change_of_[changes_[i].slot] = 0;
    });
    changes_.clear();
  }

  CudaAdvector& owner_;
  std::vector<SlotChange> changes_;
  std::vector<std::uint32_t> change_of_;  ///< [slot]: index + 1 of its change (0: none)
  std::size_t size_ = 0, capacity_ = 0, staged_capacity_ = 0;
  std::array<DeviceArray<double>, 3> x_;
  DeviceArray<double> t_, h_;
  DeviceArray<std::uint32_t> evaluations_;
  DeviceArray<ParticleStatus> status_;
  std::unique_ptr<PinnedBuffer> host_;    ///< x, y, z, status by slot (capacity_ each)
  std::unique_ptr<PinnedBuffer> staged_;  ///< the changes on their way up
  DeviceArray<SlotChange> device_changes_;
};

std::unique_ptr<ResidentParticles> CudaAdvector::make_resident() {
  return std::make_unique<CudaResident>(*this);
}

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

double cuda_pinned_upload_rate(std::size_t bytes) {
  const std::size_t floats = std::max<std::size_t>(bytes / sizeof(float), 1);
  PinnedBuffer host(floats * sizeof(float));
  std::memset(host.get(), 0, floats * sizeof(float));
  DeviceArray<float> device(floats);
  Stream stream;
  Event begin, end;
  double best = 0;
  for (int i = 0; i < 3; ++i) {
    check(cudaEventRecord(begin.get(), stream.get()), "cudaEventRecord");
    check(cudaMemcpyAsync(device.get(), host.get(), floats * sizeof(float), cudaMemcpyHostToDevice,
                          stream.get()),
          "cudaMemcpyAsync");
    check(cudaEventRecord(end.get(), stream.get()), "cudaEventRecord");
    check(cudaEventSynchronize(end.get()), "cudaEventSynchronize");
    float ms = 0;
    check(cudaEventElapsedTime(&ms, begin.get(), end.get()), "cudaEventElapsedTime");
    if (ms > 0) best = std::max(best, static_cast<double>(floats * sizeof(float)) / (1e-3 * ms));
  }
  return best;
}

std::unique_ptr<BatchAdvector> make_cuda_advector(std::size_t device_bytes) {
  return std::make_unique<CudaAdvector>(device_bytes);
}

}  // namespace orthofront::advect
