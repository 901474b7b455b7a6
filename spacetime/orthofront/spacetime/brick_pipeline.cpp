#include "orthofront/spacetime/brick_pipeline.h"

#include <tbb/parallel_pipeline.h>

#include <chrono>
#include <memory>

#include "orthofront/stage_timer.h"

namespace orthofront::spacetime {
namespace {

using Clock = std::chrono::steady_clock;
std::string brick_error(const io::TimeSeries& series, BrickKey key, bool whole_steps,
                        const char* what) {
  std::string text = "time step " + std::to_string(key.step);
  if (!whole_steps && series.bricks().bricks() > 1) text += ", brick " + std::to_string(key.brick);
  return text + " of " + series.describe() + ": " + what;
}

struct Work {
  LoadedBrick out;
  io::RawStep raw;
};

void read_stage(const io::TimeSeries& series, bool whole_steps, Work& work) {
  const auto t0 = Clock::now();
  work.raw = whole_steps ? series.read_raw(work.out.key.step)
                         : series.read_raw_brick(work.out.key.step, work.out.key.brick);
  work.out.read_seconds = seconds_since(t0);
  work.out.raw_bytes = work.raw.bytes.size();
}

void decode_stage(const io::TimeSeries& series, const BrickPipelineOptions& options, Work& work) {
  const auto t0 = Clock::now();
  if (options.whole_steps) {
    work.out.values.resize(series.step_floats());
    series.decode(work.raw, work.out.values);
  } else {
    work.out.values.resize(series.brick_floats());
    series.decode_brick(work.raw, work.out.values);
  }
  if (options.upload) options.upload(work.out.key, work.out.values);
  work.out.decode_seconds = seconds_since(t0);
}

}  // namespace

LoadedBrick load_brick(const io::TimeSeries& series, BrickKey key, bool whole_steps) {
  Work work;
  work.out.key = key;
  BrickPipelineOptions options;
  options.whole_steps = whole_steps;
  try {
    read_stage(series, whole_steps, work);
    decode_stage(series, options, work);
  } catch (const std::exception& e) {
    work.out.values = {};
    work.out.error = brick_error(series, key, whole_steps, e.what());
  }
  return std::move(work.out);
}

BrickPipeline::BrickPipeline(const io::TimeSeries& series, Publish publish,
                             BrickPipelineOptions options)
    : series_(series), publish_(std::move(publish)), options_(std::move(options)) {
  if (options_.max_live_tokens == 0) options_.max_live_tokens = 1;
  thread_ = std::thread([this] { run(); });
}

BrickPipeline::~BrickPipeline() {
  {
    std::lock_guard lock(mutex_);
    queue_.clear();
    stop_ = true;
  }
  wake_.notify_all();
  thread_.join();
}

void BrickPipeline::submit(BrickKey key) {
  {
    std::lock_guard lock(mutex_);
    queue_.push_back(key);
  }
  wake_.notify_all();
}

void BrickPipeline::cancel() {
  std::lock_guard lock(mutex_);
  queue_.clear();
}

std::size_t BrickPipeline::pending() const {
  std::lock_guard lock(mutex_);
  return queue_.size() + in_flight_;
}

void BrickPipeline::run() {
  while (true) {
    {
      std::unique_lock lock(mutex_);
      wake_.wait(lock, [this] { return stop_ || !queue_.empty(); });
      if (stop_) return;
    }
    run_batch();
  }
}

// One parallel_pipeline run: it takes bricks from the queue until the queue is empty (or the
// pipeline is stopped), then returns; run() waits for the next submission.
void BrickPipeline::run_batch() {
  tbb::parallel_pipeline(
      options_.max_live_tokens,
      tbb::make_filter<void, std::shared_ptr<Work>>(
          tbb::filter_mode::serial_in_order,
          [&](tbb::flow_control& fc) -> std::shared_ptr<Work> {
            BrickKey key;
            {
              std::lock_guard lock(mutex_);
              if (stop_ || queue_.empty()) {
                fc.stop();
                return nullptr;
              }
              key = queue_.front();
              queue_.pop_front();
              ++in_flight_;
            }
            auto work = std::make_shared<Work>();
            work->out.key = key;
            try {
              read_stage(series_, options_.whole_steps, *work);
            } catch (const std::exception& e) {
              work->out.error = brick_error(series_, key, options_.whole_steps, e.what());
            }
            return work;
          }) &
          tbb::make_filter<std::shared_ptr<Work>, std::shared_ptr<Work>>(
              tbb::filter_mode::parallel,
              [&](std::shared_ptr<Work> work) {
                if (!work->out.error.empty()) return work;
                try {
                  decode_stage(series_, options_, *work);
                } catch (const std::exception& e) {
                  work->out.values = {};
                  work->out.error =
                      brick_error(series_, work->out.key, options_.whole_steps, e.what());
                }
                work->raw.bytes = {};
                return work;
              }) &
          tbb::make_filter<std::shared_ptr<Work>, void>(
              tbb::filter_mode::serial_in_order, [&](std::shared_ptr<Work> work) {
                publish_(std::move(work->out));
                std::lock_guard lock(mutex_);
                --in_flight_;
              }));
}

}  // namespace orthofront::spacetime
