#pragma once
/// Streams time steps from a TimeSeries: read (serial, in order: TimeSeries::read_raw) → decode
/// (parallel: TimeSeries::decode, i.e. decompression and conversion) → convert (optional, parallel:
/// the place for a device upload) → publish (serial, in order), as a oneTBB parallel_pipeline
/// with a bounded number of live tokens. Runs on its own thread while the engine advances.
#include <condition_variable>
#include <cstddef>
#include <deque>
#include <exception>
#include <functional>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include "orthofront/io/time_series.h"

namespace orthofront::spacetime {

/// What one step produced: its floats, or the error that stopped it.
struct LoadedStep {
  std::size_t step = 0;
  std::vector<float> values;       ///< step_floats() entries (empty on error)
  std::size_t raw_bytes = 0;       ///< bytes as read from the file
  double read_seconds = 0;         ///< read_raw (I/O)
  double decode_seconds = 0;       ///< decode + convert
  std::string error;               ///< non-empty: what went wrong (names the step and file)
};

struct StepPipelineOptions {
  std::size_t max_live_tokens = 4;  ///< steps in flight at once (bounds the memory in flight)
  /// Optional extra stage after decode, run in parallel (e.g. a GPU upload); may be empty.
  std::function<void(std::size_t step, std::span<float> values)> convert;
  /// Called when a raw buffer of `bytes` is allocated (+) or freed (-), for memory accounting.
  std::function<void(std::ptrdiff_t bytes)> transient;
};

/// Steps are submitted (any thread) and handed to `publish`, in submission order, on the
/// pipeline's thread. `publish` must not throw. The destructor cancels and joins: no thread
/// outlives the object, no `publish` call happens after it returns.
class StepPipeline {
 public:
  using Publish = std::function<void(LoadedStep&&)>;
  StepPipeline(const io::TimeSeries& series, Publish publish, StepPipelineOptions options = {});
  ~StepPipeline();
  StepPipeline(const StepPipeline&) = delete;
  StepPipeline& operator=(const StepPipeline&) = delete;

  void submit(std::size_t step);
  /// Stops reading new steps (steps already read finish and are published); drops the queue.
  void cancel();
  /// Steps submitted but not yet published.
  std::size_t pending() const;
  /// Wall seconds the I/O stage spent in read_raw, summed.
  double read_seconds() const;

 private:
  void run();
  void run_batch();

  const io::TimeSeries& series_;
  Publish publish_;
  StepPipelineOptions options_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<std::size_t> queue_;
  std::size_t in_flight_ = 0;
  bool stop_ = false;
  double read_seconds_ = 0;
  std::thread thread_;
};

/// Reads one step the same way the pipeline does (read_raw + decode), in the calling thread.
LoadedStep load_step(const io::TimeSeries& series, std::size_t step);

}  // namespace orthofront::spacetime
