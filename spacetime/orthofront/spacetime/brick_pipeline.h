#pragma once
/// Streams bricks of time steps from a TimeSeries: read (serial, in submission order:
/// TimeSeries::read_raw_brick) → decode (parallel: TimeSeries::decode_brick, decompression and
/// conversion) → upload (optional, parallel: the seam for a device copy) → publish (serial, in
/// order), as a oneTBB parallel_pipeline with a bounded number of live tokens. Runs on its own
/// thread while the engine advances.
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include "orthofront/io/time_series.h"

namespace orthofront::spacetime {

/// One unit of the cache: brick `brick` of time step `step`.
struct BrickKey {
  std::uint32_t step = 0;
  std::uint32_t brick = 0;
  friend bool operator==(const BrickKey&, const BrickKey&) = default;
};

/// What one brick produced: its floats, or the error that stopped it.
struct LoadedBrick {
  BrickKey key;
  std::vector<float> values;  ///< brick_floats() entries (step_floats() for whole steps); empty on error
  std::size_t raw_bytes = 0;  ///< bytes as read from the file
  double read_seconds = 0;    ///< read_raw_brick (I/O)
  double decode_seconds = 0;  ///< decode + upload
  std::string error;          ///< non-empty: what went wrong (names the step, brick and file)
};

struct BrickPipelineOptions {
  std::size_t max_live_tokens = 4;  ///< bricks in flight at once (bounds the memory in flight)
  /// Read whole steps (TimeSeries::read_raw/decode) whatever the series' bricks: the baseline.
  bool whole_steps = false;
  /// Optional stage after decode, run in parallel (a device upload); may be empty.
  std::function<void(BrickKey key, std::span<float> values)> upload;
};

/// Bricks are submitted (any thread) and handed to `publish`, in submission order, on the
/// pipeline's thread. `publish` must not throw. The destructor cancels and joins: no thread
/// outlives the object, no `publish` call happens after it returns.
class BrickPipeline {
 public:
  using Publish = std::function<void(LoadedBrick&&)>;
  BrickPipeline(const io::TimeSeries& series, Publish publish, BrickPipelineOptions options = {});
  ~BrickPipeline();
  BrickPipeline(const BrickPipeline&) = delete;
  BrickPipeline& operator=(const BrickPipeline&) = delete;

  void submit(BrickKey key);
  /// Drops the queue (bricks already read finish and are published).
  void cancel();
  /// Bricks submitted but not yet published.
  std::size_t pending() const;

 private:
  void run();
  void run_batch();

  const io::TimeSeries& series_;
  Publish publish_;
  BrickPipelineOptions options_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<BrickKey> queue_;
  std::size_t in_flight_ = 0;
  bool stop_ = false;
  std::thread thread_;
};

/// Reads one brick the way the pipeline does (read + decode), in the calling thread.
LoadedBrick load_brick(const io::TimeSeries& series, BrickKey key, bool whole_steps = false);

}  // namespace orthofront::spacetime
