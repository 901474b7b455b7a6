#include <catch2/catch.hpp>

#include <tbb/parallel_for.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <mutex>
#include <random>
#include <set>
#include <thread>

#include "orthofront/error.h"
#include "orthofront/io/error.h"
#include "orthofront/spacetime/step_pipeline.h"
#include "orthofront/spacetime/time_step_cache.h"

using namespace orthofront;
using namespace orthofront::spacetime;

namespace {

// Step k holds the value k * 1000 + i at float i; reads are logged; one step may be "corrupt".
class TestSeries final : public io::TimeSeries {
 public:
  TestSeries(std::size_t steps, std::int64_t n) : steps_(steps) {
    grid_.dimension = 3;
    grid_.size = {n, n, n};
  }
  std::size_t step_count() const override { return steps_; }
  double time(std::size_t step) const override { return 0.5 * static_cast<double>(step); }
  const GridGeometry& geometry() const override { return grid_; }
  int components() const override { return 3; }
  std::string describe() const override { return "test.h5:/velocity"; }
  io::RawStep read_raw(std::size_t step) const override {
    {
      std::lock_guard lock(mutex_);
      log_.push_back(step);
      if (concurrent_++ != 0) overlapped_ = true;
    }
    if (delay_ms > 0) std::this_thread::sleep_for(std::chrono::milliseconds(delay_ms));
    {
      std::lock_guard lock(mutex_);
      --concurrent_;
    }
    if (step == corrupt)
      throw io::FormatError("test.h5: dataset /velocity/step_" + std::to_string(step) +
                            " is truncated");
    io::RawStep raw;
    raw.step = step;
    raw.encoded = true;
    raw.bytes.resize(8);
    std::memcpy(raw.bytes.data(), &step, sizeof step);
    return raw;
  }
  void decode(const io::RawStep& raw, std::span<float> values) const override {
    std::size_t step = 0;
    std::memcpy(&step, raw.bytes.data(), sizeof step);
    for (std::size_t i = 0; i < values.size(); ++i)
      values[i] = static_cast<float>(step * 1000 + i % 1000);
  }
  std::vector<std::size_t> log() const {
    std::lock_guard lock(mutex_);
    return log_;
  }
  std::size_t corrupt = static_cast<std::size_t>(-1);
  int delay_ms = 0;
  mutable bool overlapped_ = false;

 private:
  std::size_t steps_;
  GridGeometry grid_;
  mutable std::mutex mutex_;
  mutable std::vector<std::size_t> log_;
  mutable int concurrent_ = 0;
};

bool holds_step(const float* data, std::size_t step, std::size_t floats) {
  for (std::size_t i = 0; i < floats; i += 97)
    if (data[i] != static_cast<float>(step * 1000 + i % 1000)) return false;
  return true;
}

std::size_t thread_count() {
  std::size_t n = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator("/proc/self/task")) ++n;
  return n;
}

}  // namespace

TEST_CASE("cache: correct data under random access, never above budget", "[spacetime][cache]") {
  TestSeries series(40, 16);  // 48 KiB per step
  const std::size_t step_bytes = series.step_bytes();
  CacheOptions o;
  o.budget_bytes = 10 * step_bytes;
  TimeStepCache cache(series, o);
  std::mt19937 rng(7);
  std::uniform_int_distribution<std::size_t> pick(0, 39);
  for (int i = 0; i < 300; ++i) {
    const std::size_t a = pick(rng), b = pick(rng);
    cache.set_band(std::min(a, b), std::min(a, b) + 2);
    auto h1 = cache.acquire(a);
    auto h2 = cache.acquire(b);
    REQUIRE(holds_step(h1.data(), a, series.step_floats()));
    REQUIRE(holds_step(h2.data(), b, series.step_floats()));
  }
  // From several threads at once.
  tbb::parallel_for(0, 200, [&](int i) {
    const std::size_t k = static_cast<std::size_t>((i * 7) % 40);
    auto h = cache.acquire(k);
    CHECK(holds_step(h.data(), k, series.step_floats()));
  });
  const CacheStatistics s = cache.statistics();
  CHECK(s.peak_bytes <= o.budget_bytes);
  CHECK(s.peak_bytes >= 2 * step_bytes);
  CHECK(s.hits + s.misses + s.late_prefetches == 800);
  CHECK(s.evictions > 0);
  CHECK(s.resident_bytes <= o.budget_bytes);
  std::size_t reads = 0;
  for (unsigned r : s.reads_per_step) reads += r;
  CHECK(reads == s.loads);
  CHECK_FALSE(series.overlapped_);  // read_raw never ran on two threads at once
}

TEST_CASE("cache: a sweep evicts behind the band and prefetches ahead, in order",
          "[spacetime][cache]") {
  TestSeries series(30, 8);
  const std::size_t step_bytes = series.step_bytes();
  CacheOptions o;
  o.budget_bytes = 12 * step_bytes;
  TimeStepCache cache(series, o);
  for (std::size_t k = 0; k + 2 < 30; ++k) {
    auto pins = cache.acquire_range(k, k + 2);
    cache.set_band(k, k + 2);
    REQUIRE(holds_step(pins[2].data(), k + 2, series.step_floats()));
    const CacheStatistics s = cache.statistics();
    REQUIRE(s.peak_bytes <= o.budget_bytes);
  }
  // Give the last prefetches time to land, then check the order and the counts.
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  const std::vector<std::size_t> log = series.log();
  CHECK(std::is_sorted(log.begin(), log.end()));  // a sweep reads every step once, in order
  CHECK(log.size() == 30);
  const CacheStatistics s = cache.statistics();
  for (unsigned r : s.reads_per_step) CHECK(r == 1);
  CHECK(s.prefetches >= 20);      // most steps arrived ahead of the band
  CHECK(s.hits > s.misses);
  CHECK(s.evictions >= 20);       // steps behind the band went
  CHECK(s.resident_steps <= 12);
}

TEST_CASE("cache: load on demand without prefetch reads only the band", "[spacetime][cache]") {
  TestSeries series(20, 8);
  CacheOptions o;
  o.budget_bytes = 8 * series.step_bytes();
  o.prefetch = false;
  TimeStepCache cache(series, o);
  for (std::size_t k = 0; k + 1 < 10; ++k) {
    auto pins = cache.acquire_range(k, k + 1);
    cache.set_band(k, k + 1);
  }
  const CacheStatistics s = cache.statistics();
  CHECK(s.prefetches == 0);
  CHECK(s.loads == 10);
  CHECK(series.log().size() == 10);
}

TEST_CASE("cache: too small a budget is an error naming the budget needed", "[spacetime][cache]") {
  TestSeries series(10, 16);
  CacheOptions o;
  o.budget_bytes = 3 * series.step_bytes();
  try {
    TimeStepCache cache(series, o);
    FAIL("no error");
  } catch (const InvalidArgument& e) {
    const std::string m = e.what();
    CHECK_THAT(m, Catch::Contains("cache budget 144 KiB is too small"));
    CHECK_THAT(m, Catch::Contains(std::to_string(4 * series.step_bytes()) + " bytes"));
  }
  o.budget_bytes = 5 * series.step_bytes();
  TimeStepCache cache(series, o);
  CHECK_NOTHROW(cache.require_fits(3, "a band"));
  CHECK_THROWS_WITH(cache.require_fits(4, "the band of steps 2..5"),
                    Catch::Contains("too small for the band of steps 2..5") &&
                        Catch::Contains(std::to_string(6 * series.step_bytes()) + " bytes"));
}

TEST_CASE("cache: a step that cannot be read names the step and the file", "[spacetime][cache]") {
  TestSeries series(10, 8);
  series.corrupt = 4;
  CacheOptions o;
  o.budget_bytes = 10 * series.step_bytes();
  TimeStepCache cache(series, o);
  CHECK(holds_step(cache.acquire(3).data(), 3, series.step_floats()));
  CHECK_THROWS_AS(cache.acquire(4), io::IoError);
  CHECK_THROWS_WITH(cache.acquire(4), Catch::Contains("time step 4 of test.h5:/velocity") &&
                                          Catch::Contains("step_4 is truncated"));
  CHECK(holds_step(cache.acquire(5).data(), 5, series.step_floats()));
}

TEST_CASE("pipeline: cancellation joins cleanly and leaves no threads", "[spacetime][pipeline]") {
  TestSeries series(64, 8);
  series.delay_ms = 5;
  tbb::parallel_for(0, 64, [](int) {});  // start the TBB workers first
  const std::size_t before = thread_count();
  std::atomic<std::size_t> published{0};
  {
    StepPipeline pipeline(series, [&](LoadedStep&& s) {
      CHECK(s.error.empty());
      CHECK(s.values.size() == series.step_floats());
      published.fetch_add(1);
    });
    for (std::size_t k = 0; k < 64; ++k) pipeline.submit(k);
    std::this_thread::sleep_for(std::chrono::milliseconds(40));
    pipeline.cancel();
  }  // destructor joins
  const std::size_t done = published.load();
  CHECK(done > 0);
  CHECK(done < 64);  // cancelled before the end
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  CHECK(published.load() == done);  // nothing published after the join
  CHECK(thread_count() == before);
  const std::vector<std::size_t> log = series.log();
  CHECK(log.size() == done);  // every step read was published
  CHECK(std::is_sorted(log.begin(), log.end()));
}

TEST_CASE("memory sizes parse and print", "[spacetime][cache]") {
  CHECK(parse_bytes("512MiB") == 512u << 20);
  CHECK(parse_bytes("1.5GiB") == 3u << 29);
  CHECK(parse_bytes("100MB") == 100000000u);
  CHECK(parse_bytes("4096") == 4096u);
  CHECK_THROWS_WITH(parse_bytes("12 parsecs"), Catch::Contains("'12 parsecs'"));
  CHECK(format_bytes(256u << 20) == "256 MiB");
}
