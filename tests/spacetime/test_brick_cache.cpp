#include <catch2/catch.hpp>

#include <tbb/parallel_for.h>
#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include <atomic>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <mutex>
#include <random>
#include <thread>

#include "orthofront/error.h"
#include "orthofront/io/error.h"
#include "orthofront/spacetime/brick_cache.h"
#include "orthofront/spacetime/brick_pipeline.h"

using namespace orthofront;
using namespace orthofront::spacetime;

namespace {

// A 16^3 grid in bricks of 4^3 (64 bricks per step). Float i of brick b of step k holds
// k * 100000 + b * 1000 + i % 1000. Reads are logged; one brick may be "corrupt".
class BrickSeries final : public io::TimeSeries {
 public:
  explicit BrickSeries(std::size_t steps) : steps_(steps) {
    grid_.dimension = 3;
    grid_.size = {16, 16, 16};
  }
  std::size_t step_count() const override { return steps_; }
  double time(std::size_t step) const override { return 0.5 * static_cast<double>(step); }
  const GridGeometry& geometry() const override { return grid_; }
  int components() const override { return 3; }
  std::string describe() const override { return "bricks.h5:/velocity"; }
  io::BrickLayout bricks() const override { return io::BrickLayout::cubes(grid_, 4); }
  io::RawStep read_raw(std::size_t step) const override { return read_raw_brick(step, 0); }
  io::RawStep read_raw_brick(std::size_t step, std::size_t brick) const override {
    {
      std::lock_guard lock(mutex_);
      log_.push_back({static_cast<std::uint32_t>(step), static_cast<std::uint32_t>(brick)});
      if (concurrent_++ != 0) overlapped_ = true;
    }
    if (delay_ms > 0) std::this_thread::sleep_for(std::chrono::milliseconds(delay_ms));
    while (hold.load()) std::this_thread::yield();  // a test lets reads start when it is ready
    {
      std::lock_guard lock(mutex_);
      --concurrent_;
    }
    if (step == corrupt_step && brick == corrupt_brick)
      throw io::FormatError("bricks.h5: step " + std::to_string(step) + " of '/velocity', brick " +
                            std::to_string(brick) + ": damaged Blosc data");
    io::RawStep raw;
    raw.step = step;
    raw.brick = brick;
    raw.encoded = true;
    raw.bytes.resize(100);  // stands for a compressed brick
    return raw;
  }
  void decode_brick(const io::RawStep& raw, std::span<float> values) const override {
    for (std::size_t i = 0; i < values.size(); ++i) values[i] = expected(raw.step, raw.brick, i);
  }
  void decode(const io::RawStep& raw, std::span<float> values) const override {
    decode_brick(raw, values);
  }
  static float expected(std::size_t step, std::size_t brick, std::size_t i) {
    return static_cast<float>(step * 100000 + brick * 1000 + i % 1000);
  }
  std::vector<BrickKey> log() const {
    std::lock_guard lock(mutex_);
    return log_;
  }
  std::size_t corrupt_step = static_cast<std::size_t>(-1), corrupt_brick = 0;
  int delay_ms = 0;
  std::atomic<bool> hold{false};
  mutable bool overlapped_ = false;

 private:
  std::size_t steps_;
  GridGeometry grid_;
  mutable std::mutex mutex_;
  mutable std::vector<BrickKey> log_;
  mutable int concurrent_ = 0;
};

bool holds(const BrickCache::Handle& h, std::size_t floats) {
  for (std::size_t i = 0; i < floats; i += 13)
    if (h.data()[i] != BrickSeries::expected(h.key().step, h.key().brick, i)) return false;
  return true;
}

BrickKey key(std::size_t step, std::size_t brick) {
  return {static_cast<std::uint32_t>(step), static_cast<std::uint32_t>(brick)};
}

std::size_t thread_count() {
  std::size_t n = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator("/proc/self/task")) ++n;
  return n;
}

}  // namespace

TEST_CASE("brick cache: correct data under random access from several threads, never above "
          "budget",
          "[spacetime][cache]") {
  BrickSeries series(20);
  CacheOptions o;
  o.budget_bytes = 60 * 768 + 4 * 3 * 768;  // 60 bricks of 768 bytes plus the loads in flight
  BrickCache cache(series, o);
  REQUIRE(cache.unit_bytes() == 768);
  REQUIRE(cache.layout().bricks() == 64);
  const std::size_t floats = series.brick_floats();
  tbb::parallel_for(0, 4, [&](int thread) {
    std::mt19937 rng(static_cast<unsigned>(thread));
    std::uniform_int_distribution<std::size_t> step(0, 19), brick(0, 63);
    for (int i = 0; i < 300; ++i) {
      const BrickKey a = key(step(rng), brick(rng)), b = key(step(rng), brick(rng));
      if (i % 50 == 0) cache.new_epoch(a.step);
      auto ha = cache.acquire(a);
      auto hb = cache.acquire(b);
      REQUIRE(holds(ha, floats));
      REQUIRE(holds(hb, floats));
      REQUIRE(cache.statistics().peak_bytes <= o.budget_bytes);
    }
  });
  const CacheStatistics s = cache.statistics();
  CHECK(s.peak_bytes <= o.budget_bytes);
  CHECK(s.hits + s.misses + s.late_prefetches == 2400);
  CHECK(s.evictions > 0);
  CHECK(s.resident_bytes <= o.budget_bytes);
  std::size_t loads = 0;
  for (unsigned r : s.units_read_per_step) loads += r;
  CHECK(loads == s.loads);
  CHECK_FALSE(series.overlapped_);  // the series was never read on two threads at once
}

TEST_CASE("brick cache: a monotone sweep reads every brick once, prefetched in order, and evicts "
          "behind the band",
          "[spacetime][cache]") {
  BrickSeries series(30);
  CacheOptions o;
  o.budget_bytes = 4 * 16 * 768 + 4 * 3 * 768 + 2 * 3 * 768;
  o.prefetch_share = 1.0;
  BrickCache cache(series, o);
  // The "front" needs bricks 0..15 of steps k, k+1 and asks for step k+2 ahead.
  for (std::size_t k = 0; k + 2 < 30; ++k) {
    cache.new_epoch(k);
    std::vector<BrickKey> now, ahead;
    for (std::size_t b = 0; b < 16; ++b) now.push_back(key(k, b));
    for (std::size_t b = 0; b < 16; ++b) now.push_back(key(k + 1, b));
    for (std::size_t b = 0; b < 16; ++b) ahead.push_back(key(k + 2, b));
    auto pins = cache.acquire_all(now);
    for (const auto& h : pins) REQUIRE(holds(h, series.brick_floats()));
    cache.prefetch(ahead);
    REQUIRE(cache.statistics().peak_bytes <= o.budget_bytes);
  }
  cache.wait_idle();  // the last prefetches land
  const CacheStatistics s = cache.statistics();
  CHECK(s.max_reads_of_a_unit == 1);
  CHECK(s.units_touched >= 29 * 16);
  CHECK(s.read_amplification() < 1.05);  // only the last prefetches went unused
  CHECK(s.prefetches >= 16 * 16);  // most bricks arrived ahead of need
  CHECK(s.hits > s.misses);
  CHECK(s.evictions >= 25 * 16);
  // Prefetches are read in the order asked: steps never go backwards in the read log.
  const std::vector<BrickKey> log = series.log();
  for (std::size_t i = 1; i < log.size(); ++i) REQUIRE(log[i].step >= log[i - 1].step);
}

TEST_CASE("brick cache: the keys of whole steps, in file order, end at the series' last step",
          "[spacetime][cache]") {
  BrickSeries series(30);
  const BrickCache cache(series, CacheOptions{});
  const std::size_t bricks = cache.layout().bricks();
  REQUIRE(bricks > 1);
  const std::vector<BrickKey> keys = cache.step_keys(28, 35);
  REQUIRE(keys.size() == 2 * bricks);
  for (std::size_t i = 0; i < keys.size(); ++i) {
    CHECK(keys[i].step == 28 + i / bricks);
    CHECK(keys[i].brick == i % bricks);
  }
  CHECK(cache.step_keys(30, 31).empty());
  CHECK(cache.step_keys(5, 5).empty());
  CHECK(cache.step_keys(0, 1).size() == bricks);
}

TEST_CASE("brick cache: eviction takes units behind the band, then the least recently wanted",
          "[spacetime][cache]") {
  BrickSeries series(10);
  CacheOptions o;
  o.prefetch = false;
  o.max_live_tokens = 1;
  o.budget_bytes = 20 * 768 + 3 * 768 - 1;  // 20 bricks and a load in flight need one byte more
  BrickCache cache(series, o);
  for (std::size_t b = 0; b < 10; ++b) cache.acquire(key(1, b));  // step 1, epoch 1
  cache.new_epoch(1);
  for (std::size_t b = 0; b < 10; ++b) cache.acquire(key(2, b));  // epoch 2
  cache.new_epoch(2);  // step 1 is behind the band
  CHECK(cache.statistics().resident_units == 20);
  for (std::size_t b = 0; b < 10; ++b) cache.acquire(key(3, b));
  // Room for step 3 came from step 1 (behind), not from step 2.
  std::size_t reads = series.log().size();
  for (std::size_t b = 0; b < 10; ++b) cache.acquire(key(2, b));
  CHECK(series.log().size() == reads);
  cache.new_epoch(0);  // nothing behind
  for (std::size_t b = 0; b < 10; ++b) cache.acquire(key(3, b));  // step 3 wanted again, step 2 not
  reads = series.log().size();
  for (std::size_t b = 0; b < 10; ++b) cache.acquire(key(4, b));
  CHECK(series.log().size() == reads + 10);
  // Room for step 4 came from step 2 (least recently wanted), not from step 3.
  for (std::size_t b = 0; b < 10; ++b) cache.acquire(key(3, b));
  CHECK(series.log().size() == reads + 10);
  cache.acquire(key(2, 0));
  CHECK(series.log().size() == reads + 11);
  CHECK(cache.statistics().peak_bytes <= o.budget_bytes);
}

TEST_CASE("brick cache: too small a budget is an error naming the budget needed",
          "[spacetime][cache]") {
  BrickSeries series(10);
  CacheOptions o;
  o.budget_bytes = 8 * 768;
  CHECK_THROWS_WITH(BrickCache(series, o),
                    Catch::Contains("is too small for sampling one cell between two time steps") &&
                        Catch::Contains("16 resident bricks of 768 B") &&
                        Catch::Contains(std::to_string(16 * 768 + 4 * 3 * 768) + " bytes"));
  o.budget_bytes = 40 * 768;
  BrickCache cache(series, o);
  CHECK_NOTHROW(cache.require_fits(28, "a band"));
  CHECK_THROWS_WITH(cache.require_fits(29, "the front's band"),
                    Catch::Contains("too small for the front's band") &&
                        Catch::Contains("raise --cache-budget"));
  // Room kept for a bulk backend's gathering counts against every band; the largest
  // reservation holds.
  cache.reserve_units(5);
  cache.reserve_units(2);
  CHECK_NOTHROW(cache.require_fits(23, "a band"));
  CHECK_THROWS_WITH(cache.require_fits(24, "the front's band"),
                    Catch::Contains("(and 5 kept free for bulk advection)"));
}

TEST_CASE("brick cache: units read at once: one for every other thread, at least four, more as "
          "far as a sixteenth of the budget holds",
          "[spacetime][cache]") {
  BrickSeries series(10);
  const std::size_t reserve = 3 * 768;  // a unit in flight: raw bytes, scratch and floats
  const auto tokens = [&](int threads, std::size_t budget, std::size_t asked = 0) {
    std::size_t n = 0;
    tbb::task_arena(threads).execute([&] {
      CacheOptions o;
      o.budget_bytes = budget;
      o.max_live_tokens = asked;
      n = BrickCache(series, o).statistics().live_tokens;
    });
    return n;
  };
  {
    const tbb::global_control machine(tbb::global_control::max_allowed_parallelism, 32);
    CHECK(tokens(32, std::size_t{64} << 20) == 16);
    CHECK(tokens(2, std::size_t{64} << 20) == 4);
    CHECK(tokens(32, 16 * reserve * 6) == 6);        // the budget holds six
    CHECK(tokens(32, 16 * 768 + 4 * reserve) == 4);  // no fewer than four, as a small budget had
    CHECK(tokens(32, std::size_t{64} << 20, 3) == 3);  // as asked
    {  // as few as --threads allows
      const tbb::global_control threads(tbb::global_control::max_allowed_parallelism, 12);
      CHECK(tokens(32, std::size_t{64} << 20) == 6);
    }
  }
}

TEST_CASE("brick cache: a brick that cannot be read names the step, the brick and the file",
          "[spacetime][cache]") {
  BrickSeries series(10);
  series.corrupt_step = 4;
  series.corrupt_brick = 17;
  CacheOptions o;
  o.budget_bytes = 100 * 768;
  BrickCache cache(series, o);
  CHECK(holds(cache.acquire(key(4, 16)), series.brick_floats()));
  CHECK_THROWS_AS(cache.acquire(key(4, 17)), io::IoError);
  CHECK_THROWS_WITH(cache.acquire(key(4, 17)),
                    Catch::Contains("time step 4, brick 17 of bricks.h5:/velocity") &&
                        Catch::Contains("damaged Blosc data"));
  CHECK(holds(cache.acquire(key(4, 18)), series.brick_floats()));
}

TEST_CASE("brick cache: whole steps ignore the bricks (the baseline)", "[spacetime][cache]") {
  BrickSeries series(6);
  CacheOptions o;
  o.whole_steps = true;
  o.budget_bytes = 20 * series.step_bytes();
  BrickCache cache(series, o);
  CHECK(cache.layout().bricks() == 1);
  CHECK(cache.unit_bytes() == series.step_bytes());
  auto h = cache.acquire(key(3, 0));
  CHECK(h.data()[5] == BrickSeries::expected(3, 0, 5));
}

TEST_CASE("brick pipeline: cancellation joins cleanly and leaves no threads",
          "[spacetime][pipeline]") {
  BrickSeries series(64);
  // Start every TBB worker first: each body waits until all are running (or 5 s pass), so the
  // pipeline's parallel stage cannot wake a worker the count below has not seen.
  const int workers = tbb::this_task_arena::max_concurrency();
  std::atomic<int> arrived{0};
  tbb::parallel_for(0, workers, [&](int) {
    arrived.fetch_add(1);
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(5);
    while (arrived.load() < workers && std::chrono::steady_clock::now() < until)
      std::this_thread::yield();
  }, tbb::simple_partitioner{});
  const std::size_t before = thread_count();
  std::atomic<std::size_t> published{0};
  {
    BrickPipeline* self = nullptr;
    BrickPipeline pipeline(series, [&](LoadedBrick&& b) {
      CHECK(b.error.empty());
      CHECK(b.values.size() == series.brick_floats());
      if (published.fetch_add(1) + 1 == 5) self->cancel();  // cancel from the pipeline itself
    });
    self = &pipeline;
    series.hold = true;  // every brick is queued before the first read
    for (std::size_t k = 0; k < 64; ++k) pipeline.submit(key(k, k % 64));
    series.hold = false;
    while (pipeline.pending() > 0) std::this_thread::yield();  // until the cancel took effect
  }  // destructor joins
  const std::size_t done = published.load();
  CHECK(done >= 5);
  CHECK(done <= 5 + 4);  // what was read before the cancel (4 tokens) is still published
  CHECK(thread_count() <= before);
  CHECK(series.log().size() == done);  // every brick read was published
}

TEST_CASE("memory sizes parse and print", "[spacetime][cache]") {
  CHECK(parse_bytes("512MiB") == 512u << 20);
  CHECK(parse_bytes("1.5GiB") == 3u << 29);
  CHECK(parse_bytes("100MB") == 100000000u);
  CHECK(parse_bytes("4096") == 4096u);
  CHECK_THROWS_WITH(parse_bytes("12 parsecs"), Catch::Contains("'12 parsecs'"));
  CHECK(format_bytes(256u << 20) == "256 MiB");
}
