#include "orthofront/spacetime/time_step_cache.h"

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <system_error>

#include "orthofront/error.h"
#include "orthofront/io/error.h"

namespace orthofront::spacetime {
namespace {
using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}
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
      !(number > 0) || !std::isfinite(number * factor))
    throw InvalidArgument("memory size '" + text +
                          "' is not a positive size such as 512MiB, 2GiB, 100MB or 65536");
  return static_cast<std::size_t>(number * factor);
}

TimeStepCache::Handle::Handle(Handle&& other) noexcept
    : cache_(other.cache_), step_(other.step_), data_(other.data_) {
  other.cache_ = nullptr;
}
TimeStepCache::Handle& TimeStepCache::Handle::operator=(Handle&& other) noexcept {
  if (this != &other) {
    if (cache_) cache_->release(step_);
    cache_ = other.cache_;
    step_ = other.step_;
    data_ = other.data_;
    other.cache_ = nullptr;
  }
  return *this;
}
TimeStepCache::Handle::~Handle() {
  if (cache_) cache_->release(step_);
}

TimeStepCache::TimeStepCache(const io::TimeSeries& series, CacheOptions options)
    : series_(series), options_(options) {
  const std::size_t n = series.step_count();
  times_.resize(n);
  for (std::size_t k = 0; k < n; ++k) times_[k] = series.time(k);
  for (std::size_t k = 1; k < n; ++k)
    if (!(times_[k] > times_[k - 1]))
      throw InvalidArgument("time series " + series.describe() + ": step " + std::to_string(k) +
                            " has time " + std::to_string(times_[k]) +
                            ", not after the previous step's " + std::to_string(times_[k - 1]));
  step_bytes_ = series.step_bytes();
  entries_.resize(n);
  stats_.reads_per_step.assign(n, 0);
  require_fits(2, "interpolating between two time steps");
  StepPipelineOptions po;
  po.max_live_tokens = std::max<std::size_t>(1, options_.max_live_tokens);
  po.transient = [this](std::ptrdiff_t bytes) {
    std::lock_guard lock(mutex_);
    transient_ += bytes;
    note_peak();
  };
  pipeline_ = std::make_unique<StepPipeline>(
      series_, [this](LoadedStep&& s) { publish(std::move(s)); }, std::move(po));
}

TimeStepCache::~TimeStepCache() {
  cancel();
  pipeline_.reset();  // joins the reader thread before the entries go away
}

std::size_t TimeStepCache::bytes_needed(std::size_t steps) const {
  return (steps + 2) * step_bytes_;  // the band, plus one step in flight: raw and decoded
}

void TimeStepCache::require_fits(std::size_t steps, const std::string& what) const {
  if (bytes_needed(steps) <= options_.budget_bytes) return;
  throw InvalidArgument("cache budget " + format_bytes(options_.budget_bytes) +
                        " is too small for " + what + ": " + std::to_string(steps) +
                        " resident steps of " + format_bytes(step_bytes_) +
                        " plus one in flight need " + format_bytes(bytes_needed(steps)) +
                        " (" + std::to_string(bytes_needed(steps)) +
                        " bytes); raise --cache-budget");
}

std::size_t TimeStepCache::accounted() const {
  return resident_ + in_flight_ * step_bytes_ +
         static_cast<std::size_t>(std::max<std::ptrdiff_t>(transient_, 0));
}

void TimeStepCache::note_peak() { stats_.peak_bytes = std::max(stats_.peak_bytes, accounted()); }

bool TimeStepCache::evict_one() {
  // Behind the band first (oldest first), then ahead of it (farthest first).
  std::size_t victim = entries_.size();
  for (std::size_t k = 0; k < std::min(band_first_, entries_.size()); ++k)
    if (entries_[k].state == State::ready && entries_[k].pins == 0) {
      victim = k;
      break;
    }
  if (victim == entries_.size())
    for (std::size_t k = entries_.size(); k-- > band_last_ + 1;)
      if (entries_[k].state == State::ready && entries_[k].pins == 0) {
        victim = k;
        break;
      }
  if (victim == entries_.size()) return false;
  Entry& e = entries_[victim];
  resident_ -= e.values.size() * sizeof(float);
  e.values = std::vector<float>();
  e.state = State::absent;
  ++stats_.evictions;
  return true;
}

bool TimeStepCache::start_load(std::unique_lock<std::mutex>&, std::size_t step, bool prefetch) {
  Entry& e = entries_[step];
  if (e.state != State::absent) return true;
  // A load holds its decoded floats and, until decoded, its raw bytes (at most one step).
  const std::size_t need = 2 * step_bytes_;
  while (accounted() + need > options_.budget_bytes) {
    if (prefetch) return false;  // prefetch never evicts
    if (!evict_one()) return false;
  }
  e.state = State::loading;
  ++in_flight_;
  ++stats_.loads;
  if (prefetch) ++stats_.prefetches;
  note_peak();
  pipeline_->submit(step);
  return true;
}

void TimeStepCache::publish(LoadedStep&& loaded) {
  {
    std::lock_guard lock(mutex_);
    Entry& e = entries_[loaded.step];
    --in_flight_;
    ++stats_.reads_per_step[loaded.step];
    stats_.bytes_read += loaded.raw_bytes;
    stats_.read_seconds += loaded.read_seconds;
    stats_.decode_seconds += loaded.decode_seconds;
    if (!loaded.error.empty()) {
      e.state = State::failed;
      e.error = std::move(loaded.error);
    } else if (cancelled_) {
      e.state = State::absent;
    } else {
      e.values = std::move(loaded.values);
      e.state = State::ready;
      resident_ += e.values.size() * sizeof(float);
      stats_.bytes_decoded += e.values.size() * sizeof(float);
    }
    note_peak();
  }
  changed_.notify_all();
}

TimeStepCache::Handle TimeStepCache::wait_ready(std::unique_lock<std::mutex>& lock,
                                                std::size_t step) {
  Entry& e = entries_[step];
  const auto t0 = Clock::now();
  bool waited = false;
  while (true) {
    if (cancelled_)
      throw Error("time step " + std::to_string(step) + " of " + series_.describe() +
                  ": loading was cancelled");
    if (e.state == State::ready) break;
    if (e.state == State::failed) throw io::IoError(e.error);
    if (e.state == State::absent) {
      if (!start_load(lock, step, false)) {
        if (in_flight_ == 0)
          throw Error("cache budget " + format_bytes(options_.budget_bytes) +
                      " is full of pinned steps: time step " + std::to_string(step) +
                      " does not fit (each step needs " + format_bytes(step_bytes_) +
                      "); raise --cache-budget");
      }
    }
    waited = true;
    changed_.wait(lock);
  }
  if (waited) stats_.wait_seconds += seconds_since(t0);
  ++e.pins;
  return Handle(this, step, e.values.data());
}

TimeStepCache::Handle TimeStepCache::acquire(std::size_t step) {
  if (step >= entries_.size())
    throw InvalidArgument("time step " + std::to_string(step) + " does not exist in " +
                          series_.describe() + " (" + std::to_string(entries_.size()) + " steps)");
  std::unique_lock lock(mutex_);
  Entry& e = entries_[step];
  if (e.state == State::ready) ++stats_.hits;
  else if (e.state == State::loading) ++stats_.late_prefetches;
  else if (e.state == State::absent) ++stats_.misses;
  return wait_ready(lock, step);
}

std::vector<TimeStepCache::Handle> TimeStepCache::acquire_range(std::size_t first,
                                                                std::size_t last) {
  if (last >= entries_.size() || first > last)
    throw InvalidArgument("time steps " + std::to_string(first) + ".." + std::to_string(last) +
                          " do not exist in " + series_.describe());
  std::vector<Handle> handles;
  std::unique_lock lock(mutex_);
  for (std::size_t k = first; k <= last; ++k) {
    Entry& e = entries_[k];
    if (e.state == State::ready) ++stats_.hits;
    else if (e.state == State::loading) ++stats_.late_prefetches;
    else if (e.state == State::absent) {
      ++stats_.misses;
      if (!start_load(lock, k, false)) break;  // the rest starts while waiting below
    }
  }
  for (std::size_t k = first; k <= last; ++k) handles.push_back(wait_ready(lock, k));
  return handles;
}

void TimeStepCache::release(std::size_t step) {
  std::lock_guard lock(mutex_);
  --entries_[step].pins;
}

void TimeStepCache::set_band(std::size_t first, std::size_t last) {
  std::unique_lock lock(mutex_);
  band_first_ = first;
  band_last_ = std::min(last, entries_.size() - 1);
  for (std::size_t k = 0; k < std::min(first, entries_.size()); ++k) {
    Entry& e = entries_[k];
    if (e.state == State::ready && e.pins == 0) {
      resident_ -= e.values.size() * sizeof(float);
      e.values = std::vector<float>();
      e.state = State::absent;
      ++stats_.evictions;
    }
  }
  if (!options_.prefetch || cancelled_) return;
  std::size_t started = 0;
  for (std::size_t k = band_last_ + 1; k < entries_.size(); ++k) {
    if (options_.max_prefetch_steps > 0 && k - band_last_ > options_.max_prefetch_steps) break;
    if (entries_[k].state != State::absent) continue;
    // Keep room for one demand load besides the prefetched steps.
    if (accounted() + 4 * step_bytes_ > options_.budget_bytes) break;
    if (!start_load(lock, k, true)) break;
    ++started;
  }
  (void)started;
}

void TimeStepCache::cancel() {
  {
    std::lock_guard lock(mutex_);
    cancelled_ = true;
  }
  if (pipeline_) pipeline_->cancel();
  changed_.notify_all();
}

CacheStatistics TimeStepCache::statistics() const {
  std::lock_guard lock(mutex_);
  CacheStatistics s = stats_;
  s.resident_bytes = resident_;
  s.resident_steps = 0;
  for (const Entry& e : entries_) s.resident_steps += e.state == State::ready ? 1 : 0;
  return s;
}

}  // namespace orthofront::spacetime
