#pragma once
/// A narrow-band cache of the time steps of a TimeSeries under a memory budget: steps in use are
/// pinned (RAII handles), unpinned steps behind the band are evicted, steps ahead of the band are
/// prefetched asynchronously by a StepPipeline. All loads (demand and prefetch) go through the
/// pipeline, so TimeSeries::read_raw is only ever called from its one reader thread.
#include <condition_variable>
#include <cstddef>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "orthofront/io/time_series.h"
#include "orthofront/spacetime/step_pipeline.h"

namespace orthofront::spacetime {

struct CacheOptions {
  std::size_t budget_bytes = std::size_t{512} << 20;  ///< resident + in-flight bytes, at most
  bool prefetch = true;            ///< read steps ahead of the band while the engine computes
  std::size_t max_prefetch_steps = 0;  ///< 0: as many as the budget allows
  std::size_t max_live_tokens = 4;     ///< pipeline tokens (steps decoded at once)
};

struct CacheStatistics {
  std::size_t hits = 0;            ///< pins of a step that was resident
  std::size_t late_prefetches = 0; ///< pins that waited for a prefetch still in flight
  std::size_t misses = 0;          ///< pins that had to start a load (not prefetched)
  std::size_t prefetches = 0;      ///< loads started ahead of the band
  std::size_t evictions = 0;
  std::size_t loads = 0;           ///< steps read, all reasons
  std::size_t bytes_read = 0;      ///< raw bytes read from the files
  std::size_t bytes_decoded = 0;   ///< float bytes produced
  double read_seconds = 0;         ///< I/O (read_raw), pipeline thread
  double decode_seconds = 0;       ///< decode (+ convert), summed over threads
  double wait_seconds = 0;         ///< time callers blocked waiting for data
  std::size_t peak_bytes = 0;      ///< max of resident + in-flight (decoded and raw) bytes
  std::size_t resident_bytes = 0;  ///< now
  std::size_t resident_steps = 0;  ///< now
  std::vector<unsigned> reads_per_step;  ///< how often each step was read
};

/// Steps are loaded as a whole; a step in use is pinned by a Handle and never evicted.
/// Thread-safe.
class TimeStepCache {
 public:
  /// Throws InvalidArgument when the budget cannot hold two steps plus one in flight (the least
  /// any interpolation in time needs); the message names the budget needed.
  TimeStepCache(const io::TimeSeries& series, CacheOptions options);
  ~TimeStepCache();
  TimeStepCache(const TimeStepCache&) = delete;
  TimeStepCache& operator=(const TimeStepCache&) = delete;

  /// A pinned step: its floats stay valid and resident until the handle is destroyed.
  class Handle {
   public:
    Handle() = default;
    Handle(Handle&& other) noexcept;
    Handle& operator=(Handle&& other) noexcept;
    Handle(const Handle&) = delete;
    Handle& operator=(const Handle&) = delete;
    ~Handle();
    const float* data() const { return data_; }
    std::size_t step() const { return step_; }
    explicit operator bool() const { return cache_ != nullptr; }

   private:
    friend class TimeStepCache;
    Handle(TimeStepCache* cache, std::size_t step, const float* data)
        : cache_(cache), step_(step), data_(data) {}
    TimeStepCache* cache_ = nullptr;
    std::size_t step_ = 0;
    const float* data_ = nullptr;
  };

  /// Pins one step, loading it if needed (blocks). Throws io::IoError naming the step and file
  /// when it cannot be read, orthofront::Error when the budget cannot take it.
  Handle acquire(std::size_t step);
  /// Pins steps first..last: starts every missing load at once (so they decode in parallel),
  /// then waits. Same errors as acquire.
  std::vector<Handle> acquire_range(std::size_t first, std::size_t last);

  /// Declares the band [first, last] of steps the engine needs now: unpinned steps before it are
  /// evicted, and (with prefetch) steps after it are requested while the budget allows.
  void set_band(std::size_t first, std::size_t last);

  /// Bytes a band of `steps` steps needs (the steps plus one step in flight, raw and decoded).
  std::size_t bytes_needed(std::size_t steps) const;
  /// Throws InvalidArgument naming the needed budget when a band of `steps` steps does not fit.
  void require_fits(std::size_t steps, const std::string& what) const;

  CacheStatistics statistics() const;
  const io::TimeSeries& series() const { return series_; }
  const std::vector<double>& times() const { return times_; }
  std::size_t budget() const { return options_.budget_bytes; }
  /// Stops loading (pending requests are dropped; waiting callers get an error).
  void cancel();

 private:
  enum class State : unsigned char { absent, loading, ready, failed };
  struct Entry {
    State state = State::absent;
    std::vector<float> values;
    int pins = 0;
    std::string error;
  };

  void release(std::size_t step);
  void publish(LoadedStep&& loaded);
  // Needs the lock. Starts a load of `step` if absent, making room by eviction; false when no
  // room can be made now (loads in flight will free some later).
  bool start_load(std::unique_lock<std::mutex>& lock, std::size_t step, bool prefetch);
  bool evict_one();
  std::size_t accounted() const;
  Handle wait_ready(std::unique_lock<std::mutex>& lock, std::size_t step);
  void note_peak();

  const io::TimeSeries& series_;
  CacheOptions options_;
  std::vector<double> times_;
  std::size_t step_bytes_ = 0;
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::vector<Entry> entries_;
  std::size_t band_first_ = 0, band_last_ = 0;
  std::size_t resident_ = 0;   // bytes of ready entries
  std::size_t in_flight_ = 0;  // loads started, not yet published
  std::ptrdiff_t transient_ = 0;  // raw bytes alive in the pipeline
  bool cancelled_ = false;
  CacheStatistics stats_;
  std::unique_ptr<StepPipeline> pipeline_;  // last: destroyed (joined) first
};

/// "512MiB", "1.5GiB", "100MB", "65536" → bytes. Throws InvalidArgument naming the text.
std::size_t parse_bytes(const std::string& text);
/// 268435456 → "256 MiB".
std::string format_bytes(std::size_t bytes);

}  // namespace orthofront::spacetime
