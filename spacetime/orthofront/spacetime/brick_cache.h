#pragma once
/// The space-time narrow band: a cache of (brick, time step) units of a TimeSeries under a byte
/// budget that is never exceeded. Units in use are pinned (RAII handles); unpinned units behind
/// the band (earlier steps than the front still needs) go first, then the least recently wanted;
/// units the front will reach next are prefetched asynchronously through a BrickPipeline. Every
/// load (demand and prefetch) goes through the pipeline, so the series' read functions are only
/// ever called from its one reader thread.
#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <unordered_map>
#include <vector>

#include "orthofront/io/time_series.h"
#include "orthofront/spacetime/brick_pipeline.h"

namespace orthofront::spacetime {

struct CacheOptions {
  std::size_t budget_bytes = std::size_t{512} << 20;  ///< resident + in-flight bytes, at most
  bool prefetch = true;           ///< read what the front will reach while the engine computes
  /// Pipeline tokens (units read and decoded at once); 0: one for every other thread TBB may
  /// use, at least 4, more only as far as a sixteenth of the budget holds them.
  std::size_t max_live_tokens = 0;
  /// Ignore the series' bricks: each time step is one unit (the whole-step cache, kept as a
  /// baseline and for series stored without bricks).
  bool whole_steps = false;
  /// Optional stage after decode, in parallel in the pipeline (a device upload); may be empty.
  std::function<void(BrickKey key, std::span<float> values)> upload;
  /// Share of the budget prefetches may fill (the rest stays for the loads the front demands).
  double prefetch_share = 0.75;
};

struct CacheStatistics {
  std::size_t unit_bytes = 0;      ///< decoded bytes of one unit (brick or step)
  std::size_t units_per_step = 0;  ///< bricks per step (1 for whole steps)
  std::size_t live_tokens = 0;     ///< units read and decoded at once (the pipeline's tokens)
  std::size_t hits = 0;            ///< pins of a resident unit
  std::size_t late_prefetches = 0; ///< pins that waited for a prefetch still in flight
  std::size_t misses = 0;          ///< pins that had to start a load
  std::size_t prefetches = 0;      ///< loads started ahead of need
  std::size_t evictions = 0;
  std::size_t loads = 0;           ///< units read, all reasons
  std::size_t units_touched = 0;   ///< distinct units read at least once
  std::size_t units_used = 0;      ///< distinct units pinned at least once (needed)
  std::size_t max_reads_of_a_unit = 0;  ///< 1 when nothing was read twice
  std::size_t bytes_read = 0;      ///< raw bytes read from the files
  std::size_t bytes_needed = 0;    ///< raw bytes of the distinct units used (each counted once)
  std::size_t bytes_decoded = 0;   ///< float bytes produced
  double read_seconds = 0;         ///< I/O, pipeline thread
  double decode_seconds = 0;       ///< decode (+ upload), summed over threads
  double wait_seconds = 0;         ///< time callers blocked waiting for data
  std::size_t peak_bytes = 0;      ///< max of resident + reserved-in-flight bytes
  std::size_t resident_bytes = 0;  ///< now
  std::size_t resident_units = 0;  ///< now
  std::size_t peak_resident_units = 0;
  std::vector<unsigned> units_read_per_step;  ///< loads per time step (all bricks)

  /// bytes_read / bytes_needed (1 when nothing was read twice).
  double read_amplification() const {
    return bytes_needed ? static_cast<double>(bytes_read) / static_cast<double>(bytes_needed) : 1.0;
  }
};

/// Thread-safe.
class BrickCache {
 public:
  /// Throws InvalidArgument when the budget cannot hold the least a sample needs (the 2 × 8
  /// units around a cell corner of two steps, plus loads in flight); the message names the budget
  /// needed.
  BrickCache(const io::TimeSeries& series, CacheOptions options);
  ~BrickCache();
  BrickCache(const BrickCache&) = delete;
  BrickCache& operator=(const BrickCache&) = delete;

  /// A pinned unit: its floats stay valid and resident until the handle is destroyed.
  class Handle {
   public:
    Handle() = default;
    Handle(Handle&& other) noexcept;
    Handle& operator=(Handle&& other) noexcept;
    Handle(const Handle&) = delete;
    Handle& operator=(const Handle&) = delete;
    ~Handle() {
      if (cache_) cache_->release(key_);  // inline: most handles are empty (moved from)
    }
    const float* data() const { return data_; }
    BrickKey key() const { return key_; }
    explicit operator bool() const { return cache_ != nullptr; }

   private:
    friend class BrickCache;
    Handle(BrickCache* cache, BrickKey key, const float* data)
        : cache_(cache), key_(key), data_(data) {}
    BrickCache* cache_ = nullptr;
    BrickKey key_;
    const float* data_ = nullptr;
  };

  /// Pins one unit, loading it if needed (blocks). Throws io::IoError naming the step, brick and
  /// file when it cannot be read, orthofront::Error when the budget cannot take it.
  Handle acquire(BrickKey key);
  /// Pins all `keys`: starts every missing load at once (so they decode in parallel), then waits.
  /// The handles come in their own order (resident units first): tell them by Handle::key().
  /// Same errors as acquire.
  std::vector<Handle> acquire_all(std::span<const BrickKey> keys);
  /// Requests loads of `keys` (most urgent first) while the budget allows, evicting only units
  /// that are neither pinned nor wanted since the last new_epoch(). Never blocks on data.
  void prefetch(std::span<const BrickKey> keys);
  /// Starts a new band: units wanted (acquired or prefetched) from now on are kept over older
  /// ones; units of steps before `first_step` will not be needed again and are evicted first.
  void new_epoch(std::size_t first_step);

  /// The keys of every unit of steps [first, end) (past the series' last step: none), step by
  /// step, each in brick order (the order the file stores them).
  std::vector<BrickKey> step_keys(std::size_t first, std::size_t end) const;

  /// Bytes `units` pinned units need, plus the loads in flight and the reserved units.
  std::size_t bytes_needed(std::size_t units) const;
  /// Keeps room for `units` more units beside every band require_fits() checks: what a bulk
  /// advection backend pins at once as it gathers whole steps (CachedSteps). A band that leaves
  /// less fails its check (a batch pass then sets surfaces aside) instead of a bulk call failing
  /// part-way. The largest reservation asked for holds.
  void reserve_units(std::size_t units);
  /// Throws InvalidArgument naming the needed budget when `units` units do not fit.
  void require_fits(std::size_t units, const std::string& what) const;

  /// Unit layout: bricks of the series, or one brick of the whole grid with whole_steps.
  const io::BrickLayout& layout() const { return layout_; }
  std::size_t unit_bytes() const { return unit_bytes_; }
  bool whole_steps() const { return options_.whole_steps; }
  CacheStatistics statistics() const;
  const io::TimeSeries& series() const { return series_; }
  const std::vector<double>& times() const { return times_; }
  std::size_t budget() const { return options_.budget_bytes; }
  /// Blocks until no load is in flight (every requested unit is published).
  void wait_idle();
  /// Stops loading (pending requests are dropped; waiting callers get an error).
  void cancel();

 private:
  enum class State : unsigned char { loading, ready, failed };
  struct Entry {
    State state = State::loading;
    bool prefetched = false;
    int pins = 0;
    std::uint64_t wanted = 0;  // epoch it was last wanted in
    std::size_t raw_bytes = 0;
    std::vector<float> values;
    std::string error;
  };
  void note_use(std::uint64_t key, Entry& e);

  std::uint64_t id(BrickKey key) const {
    return static_cast<std::uint64_t>(key.step) * layout_.bricks() + key.brick;
  }
  void check_key(BrickKey key) const;
  void release(BrickKey key);
  void publish(LoadedBrick&& loaded);
  // Needs the lock. Starts a load of `key` (absent), making room by eviction; false when no room
  // can be made now.
  bool start_load(BrickKey key, bool prefetch);
  bool evict_one(bool prefetch);
  std::size_t accounted() const;
  Handle wait_ready(std::unique_lock<std::mutex>& lock, BrickKey key);
  void note_peak();

  const io::TimeSeries& series_;
  CacheOptions options_;
  io::BrickLayout layout_;
  std::vector<double> times_;
  std::size_t unit_bytes_ = 0;
  std::size_t load_reserve_ = 0;  // bytes a load in flight may hold (raw, scratch, decoded)
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::unordered_map<std::uint64_t, Entry> entries_;
  std::vector<std::uint8_t> reads_;  // per unit, saturating
  std::vector<bool> used_;           // per unit: pinned at least once
  std::uint64_t epoch_ = 1;
  std::atomic<std::size_t> reserved_units_{0};
  std::uint64_t releases_ = 0;  // units whose last pin went: progress for waiting loads
  std::size_t first_step_ = 0;
  std::size_t resident_ = 0;   // bytes of ready entries
  std::size_t in_flight_ = 0;  // loads started, not yet published
  bool cancelled_ = false;
  CacheStatistics stats_;
  std::unique_ptr<BrickPipeline> pipeline_;  // last: destroyed (joined) first
};

/// "512MiB", "1.5GiB", "100MB", "65536" → bytes. Throws InvalidArgument naming the text.
std::size_t parse_bytes(const std::string& text);
/// 268435456 → "256 MiB".
std::string format_bytes(std::size_t bytes);

}  // namespace orthofront::spacetime
