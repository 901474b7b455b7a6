#include "orthofront/spacetime/brick_cache.h"

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <system_error>

#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include "orthofront/error.h"
#include "orthofront/io/error.h"
#include "orthofront/stage_timer.h"

namespace orthofront::spacetime {
namespace {
using Clock = std::chrono::steady_clock;
}  // namespace

std::string format_bytes(std::size_t bytes) {
  const char* units[] = {"B", "KiB", "MiB", "GiB", "TiB"};
  double value = static_cast<double>(bytes);
  int unit = 0;
  while (value >= 1024 && unit < 4) value /= 1024, ++unit;
  char text[32];
  const auto r = std::to_chars(text, text + sizeof text, value, std::chars_format::general,
                               value < 10 && unit > 0 ? 3 : 4);
  return std::string(text, r.ptr) + " " + units[unit];
}

std::size_t parse_bytes(const std::string& text) {
  std::size_t pos = 0;
  while (pos < text.size() && (std::isdigit(static_cast<unsigned char>(text[pos])) ||
                               text[pos] == '.'))
    ++pos;
  double number = 0;
  const auto r = std::from_chars(text.data(), text.data() + pos, number);
  std::string unit = text.substr(pos);
  double factor = 0;
  if (unit.empty() || unit == "B") factor = 1;
  else if (unit == "KiB" || unit == "K" || unit == "k") factor = 1024.0;
  else if (unit == "MiB" || unit == "M") factor = 1024.0 * 1024;
  else if (unit == "GiB" || unit == "G") factor = 1024.0 * 1024 * 1024;
  else if (unit == "KB" || unit == "kB") factor = 1e3;
  else if (unit == "MB") factor = 1e6;
  else if (unit == "GB") factor = 1e9;
  if (pos == 0 || r.ec != std::errc() || r.ptr != text.data() + pos || factor == 0 ||
      !(number * factor >= 1))
    throw InvalidArgument("memory size '" + text +
                          "' is not a positive size such as 512MiB, 2GiB, 100MB or 65536");
  // Beyond 2^62 bytes the conversion below would overflow; no memory is that large.
  if (!(number * factor < 0x1p62))
    throw InvalidArgument("memory size '" + text + "' is too large");
  return static_cast<std::size_t>(number * factor);
}

BrickCache::Handle::Handle(Handle&& other) noexcept
    : cache_(other.cache_), key_(other.key_), data_(other.data_) {
  other.cache_ = nullptr;
}
BrickCache::Handle& BrickCache::Handle::operator=(Handle&& other) noexcept {
  if (this != &other) {
    if (cache_) cache_->release(key_);
    cache_ = other.cache_;
    key_ = other.key_;
    data_ = other.data_;
    other.cache_ = nullptr;
  }
  return *this;
}

BrickCache::BrickCache(const io::TimeSeries& series, CacheOptions options)
    : series_(series), options_(options) {
  const std::size_t n = series.step_count();
  times_.resize(n);
  for (std::size_t k = 0; k < n; ++k) times_[k] = series.time(k);
  for (std::size_t k = 1; k < n; ++k)
    if (!(times_[k] > times_[k - 1]))
      throw InvalidArgument("time series " + series.describe() + ": step " + std::to_string(k) +
                            " has time " + std::to_string(times_[k]) +
                            ", not after the previous step's " + std::to_string(times_[k - 1]));
  layout_ = options_.whole_steps ? io::BrickLayout::whole(series.geometry()) : series.bricks();
  unit_bytes_ = layout_.brick_points() * static_cast<std::size_t>(series.components()) *
                sizeof(float);
  // The cache keeps a few bytes of bookkeeping per unit of the whole series; a file chunked into
  // tiny bricks (or a damaged chunk shape) would make that unbounded.
  constexpr std::size_t kMaxUnits = std::size_t{1} << 27;
  if (layout_.bricks() > kMaxUnits || n * layout_.bricks() > kMaxUnits)
    throw InvalidArgument("time series " + series.describe() + ": " + std::to_string(n) +
                          " steps of " + std::to_string(layout_.bricks()) + " bricks of " +
                          std::to_string(layout_.size[0]) + " x " + std::to_string(layout_.size[1]) +
                          " x " + std::to_string(layout_.size[2]) +
                          " points are too many to cache; rewrite it with larger bricks "
                          "(orthofront convert --brick 32)");
  // A load holds its raw bytes (at most about a unit), a decode scratch buffer and the floats.
  load_reserve_ = 3 * unit_bytes_;
  if (options_.max_live_tokens == 0) {
    // A unit in flight for every other thread TBB may use here: the readers keep up with a
    // host that waits for data and leave it the other cores when it does not (two units a
    // thread slowed down a streak surface that never waits for data); four at least (what
    // a small budget always had), more only as far as a sixteenth of the budget holds them.
    const auto threads = static_cast<std::size_t>(std::max(
        1, std::min<int>(tbb::this_task_arena::max_concurrency(),
                         static_cast<int>(tbb::global_control::active_value(
                             tbb::global_control::max_allowed_parallelism)))));
    const std::size_t fit = options_.budget_bytes / 16 / std::max<std::size_t>(1, load_reserve_);
    options_.max_live_tokens = std::max<std::size_t>(4, std::min(threads / 2, fit));
  }
  reads_.assign(n * layout_.bricks(), 0);
  used_.assign(n * layout_.bricks(), false);
  stats_.unit_bytes = unit_bytes_;
  stats_.units_per_step = layout_.bricks();
  stats_.live_tokens = options_.max_live_tokens;
  stats_.units_read_per_step.assign(n, 0);
  const std::size_t least = layout_.bricks() == 1 ? 2 : 16;
  require_fits(least, "sampling one cell between two time steps");
  BrickPipelineOptions po;
  po.max_live_tokens = options_.max_live_tokens;
  po.whole_steps = options_.whole_steps;
  po.upload = options_.upload;
  pipeline_ = std::make_unique<BrickPipeline>(
      series_, [this](LoadedBrick&& b) { publish(std::move(b)); }, std::move(po));
}

BrickCache::~BrickCache() {
  cancel();
  pipeline_.reset();  // joins the reader thread before the entries go away
}

std::size_t BrickCache::bytes_needed(std::size_t units) const {
  return (units + reserved_units_) * unit_bytes_ +
         options_.max_live_tokens * load_reserve_;
}

void BrickCache::reserve_units(std::size_t units) {
  std::size_t now = reserved_units_.load();
  while (now < units && !reserved_units_.compare_exchange_weak(now, units)) {
  }
}

void BrickCache::require_fits(std::size_t units, const std::string& what) const {
  if (bytes_needed(units) <= options_.budget_bytes) return;
  const std::string unit = layout_.bricks() == 1 ? "time steps" : "bricks";
  const std::size_t reserved = reserved_units_;
  const std::string bulk =
      reserved ? " (and " + std::to_string(reserved) + " kept free for bulk advection)" : "";
  throw InvalidArgument("cache budget " + format_bytes(options_.budget_bytes) +
                        " is too small for " + what + ": " + std::to_string(units) + " resident " +
                        unit + " of " + format_bytes(unit_bytes_) + bulk +
                        " plus loads in flight need " +
                        format_bytes(bytes_needed(units)) + " (" +
                        std::to_string(bytes_needed(units)) + " bytes); raise --cache-budget");
}

void BrickCache::check_key(BrickKey key) const {
  if (key.step >= times_.size() || key.brick >= layout_.bricks())
    throw InvalidArgument("brick " + std::to_string(key.brick) + " of time step " +
                          std::to_string(key.step) + " does not exist in " + series_.describe() +
                          " (" + std::to_string(times_.size()) + " steps of " +
                          std::to_string(layout_.bricks()) + " bricks)");
}

std::size_t BrickCache::accounted() const { return resident_ + in_flight_ * load_reserve_; }

void BrickCache::note_peak() {
  stats_.peak_bytes = std::max(stats_.peak_bytes, accounted());
  stats_.peak_resident_units = std::max(stats_.peak_resident_units, resident_ / unit_bytes_);
}

bool BrickCache::evict_one(bool prefetch) {
  // Behind the band first (steps the front has passed), then units not wanted in this epoch
  // (least recently wanted first), then, for demand loads only, prefetched units the front will
  // reach last.
  auto best = entries_.end();
  auto rank = [&](const Entry& e, std::uint64_t key) -> std::pair<int, double> {
    const std::size_t step = key / layout_.bricks();
    if (step < first_step_) return {0, 0.0};
    if (e.wanted < epoch_) return {1, static_cast<double>(e.wanted)};
    return {2, -static_cast<double>(step)};
  };
  std::pair<int, double> best_rank{3, 0.0};
  for (auto it = entries_.begin(); it != entries_.end(); ++it) {
    const Entry& e = it->second;
    if (e.state == State::loading || e.pins > 0) continue;
    const auto r = rank(e, it->first);
    if (r.first == 2 && prefetch) continue;
    if (r < best_rank) {
      best_rank = r;
      best = it;
      if (r.first == 0) break;
    }
  }
  if (best == entries_.end()) return false;
  resident_ -= best->second.values.size() * sizeof(float);
  entries_.erase(best);
  ++stats_.evictions;
  return true;
}

bool BrickCache::start_load(BrickKey key, bool prefetch) {
  while (accounted() + load_reserve_ > options_.budget_bytes)
    if (!evict_one(prefetch)) return false;
  Entry& e = entries_[id(key)];
  e.state = State::loading;
  e.prefetched = prefetch;
  e.wanted = epoch_;
  ++in_flight_;
  ++stats_.loads;
  if (prefetch) ++stats_.prefetches;
  note_peak();
  pipeline_->submit(key);
  return true;
}

void BrickCache::publish(LoadedBrick&& loaded) {
  {
    std::lock_guard lock(mutex_);
    const std::uint64_t key = id(loaded.key);
    --in_flight_;
    std::uint8_t& reads = reads_[key];
    if (reads == 0) ++stats_.units_touched;
    if (reads < 255) ++reads;
    stats_.max_reads_of_a_unit = std::max<std::size_t>(stats_.max_reads_of_a_unit, reads);
    ++stats_.units_read_per_step[loaded.key.step];
    stats_.bytes_read += loaded.raw_bytes;
    stats_.read_seconds += loaded.read_seconds;
    stats_.decode_seconds += loaded.decode_seconds;
    auto it = entries_.find(key);
    if (it != entries_.end()) {
      Entry& e = it->second;
      if (!loaded.error.empty()) {
        e.state = State::failed;
        e.error = std::move(loaded.error);
      } else if (cancelled_) {
        entries_.erase(it);
      } else {
        e.values = std::move(loaded.values);
        e.raw_bytes = loaded.raw_bytes;
        e.state = State::ready;
        resident_ += e.values.size() * sizeof(float);
        stats_.bytes_decoded += e.values.size() * sizeof(float);
      }
    }
    note_peak();
  }
  changed_.notify_all();
}

namespace {
constexpr std::chrono::seconds kFullWait{5};
}  // namespace

BrickCache::Handle BrickCache::wait_ready(std::unique_lock<std::mutex>& lock, BrickKey key) {
  const std::uint64_t k = id(key);
  const auto t0 = Clock::now();
  bool waited = false;
  while (true) {
    if (cancelled_)
      throw Error("time step " + std::to_string(key.step) + " of " + series_.describe() +
                  ": loading was cancelled");
    auto it = entries_.find(k);
    if (it == entries_.end()) {
      if (!start_load(key, false) && in_flight_ == 0) {
        // Other threads may hold pins for one evaluation only: give them time to release them
        // before calling the budget full. Releases that never make room (threads that pin again
        // at once, as the surfaces of a batch pass do) end the wait after kFullWait.
        const std::uint64_t before = releases_;
        if (!changed_.wait_for(lock, std::chrono::seconds(1),
                               [&] { return releases_ != before || in_flight_ > 0 || cancelled_; }) ||
            Clock::now() - t0 > kFullWait)
          throw Error("cache budget " + format_bytes(options_.budget_bytes) +
                      " is full of pinned units: brick " + std::to_string(key.brick) +
                      " of time step " + std::to_string(key.step) + " does not fit (each needs " +
                      format_bytes(unit_bytes_) + "); raise --cache-budget");
        waited = true;
        continue;
      }
    } else {
      Entry& e = it->second;
      if (e.state == State::ready) {
        if (waited) stats_.wait_seconds += seconds_since(t0);
        ++e.pins;
        e.wanted = epoch_;
        note_use(k, e);
        return Handle(this, key, e.values.data());
      }
      if (e.state == State::failed) throw io::IoError(e.error);
    }
    waited = true;
    changed_.wait(lock);
  }
}

void BrickCache::note_use(std::uint64_t key, Entry& e) {
  if (used_[key]) return;
  used_[key] = true;
  ++stats_.units_used;
  stats_.bytes_needed += e.raw_bytes;
}

BrickCache::Handle BrickCache::acquire(BrickKey key) {
  check_key(key);
  std::unique_lock lock(mutex_);
  auto it = entries_.find(id(key));
  if (it == entries_.end()) ++stats_.misses;
  else if (it->second.state == State::ready) ++stats_.hits;
  else if (it->second.state == State::loading) ++stats_.late_prefetches;
  return wait_ready(lock, key);
}

std::vector<BrickCache::Handle> BrickCache::acquire_all(std::span<const BrickKey> keys) {
  for (const BrickKey& key : keys) check_key(key);
  std::vector<Handle> handles;
  handles.reserve(keys.size());
  std::unique_lock lock(mutex_);
  // Pin the resident members first, so starting the loads of the others never evicts them.
  std::vector<BrickKey> pending;
  for (const BrickKey& key : keys) {
    const std::uint64_t k = id(key);
    auto it = entries_.find(k);
    if (it != entries_.end() && it->second.state == State::ready) {
      Entry& e = it->second;
      ++stats_.hits;
      ++e.pins;
      e.wanted = epoch_;
      note_use(k, e);
      handles.push_back(Handle(this, key, e.values.data()));
    } else {
      if (it != entries_.end()) it->second.wanted = epoch_;
      pending.push_back(key);
    }
  }
  for (const BrickKey& key : pending) {
    auto it = entries_.find(id(key));
    if (it == entries_.end()) {
      ++stats_.misses;
      start_load(key, false);  // when there is no room now, wait_ready starts it later
    } else if (it->second.state == State::loading) {
      ++stats_.late_prefetches;
    }
  }
  for (const BrickKey& key : pending) handles.push_back(wait_ready(lock, key));
  return handles;
}

void BrickCache::prefetch(std::span<const BrickKey> keys) {
  if (!options_.prefetch) return;
  std::unique_lock lock(mutex_);
  if (cancelled_) return;
  for (const BrickKey& key : keys) {
    if (key.step >= times_.size() || key.brick >= layout_.bricks()) continue;
    auto it = entries_.find(id(key));
    if (it != entries_.end()) {
      it->second.wanted = epoch_;
      continue;
    }
    // Keep room for the loads the front demands besides the prefetched units.
    const auto share = static_cast<std::size_t>(options_.prefetch_share *
                                                 static_cast<double>(options_.budget_bytes));
    while (accounted() + 2 * load_reserve_ > share)
      if (!evict_one(true)) break;
    if (accounted() + 2 * load_reserve_ > share) break;
    if (!start_load(key, true)) break;
  }
}

std::vector<BrickKey> BrickCache::step_keys(std::size_t first, std::size_t end) const {
  end = std::min(end, times_.size());
  std::vector<BrickKey> keys;
  if (end <= first) return keys;
  keys.reserve((end - first) * layout_.bricks());
  for (std::size_t k = first; k < end; ++k)
    for (std::size_t b = 0; b < layout_.bricks(); ++b)
      keys.push_back({static_cast<std::uint32_t>(k), static_cast<std::uint32_t>(b)});
  return keys;
}

void BrickCache::new_epoch(std::size_t first_step) {
  std::lock_guard lock(mutex_);
  ++epoch_;
  first_step_ = first_step;
  // Units behind the band stay until room is needed; they are then the first to go.
}

void BrickCache::release(BrickKey key) {
  bool freed = false;
  {
    std::lock_guard lock(mutex_);
    auto it = entries_.find(id(key));
    if (it != entries_.end() && --it->second.pins == 0) {
      ++releases_;
      freed = true;
    }
  }
  if (freed) changed_.notify_all();  // a unit became evictable: a waiting load may now fit
}

void BrickCache::wait_idle() {
  std::unique_lock lock(mutex_);
  changed_.wait(lock, [this] { return in_flight_ == 0; });
}

void BrickCache::cancel() {
  {
    std::lock_guard lock(mutex_);
    cancelled_ = true;
  }
  if (pipeline_) pipeline_->cancel();
  changed_.notify_all();
}

CacheStatistics BrickCache::statistics() const {
  std::lock_guard lock(mutex_);
  CacheStatistics s = stats_;
  s.resident_bytes = resident_;
  s.resident_units = 0;
  for (const auto& [key, e] : entries_) s.resident_units += e.state == State::ready ? 1 : 0;
  return s;
}

}  // namespace orthofront::spacetime
