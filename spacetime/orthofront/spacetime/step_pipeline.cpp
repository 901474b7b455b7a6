#include "orthofront/spacetime/step_pipeline.h"

#include <tbb/parallel_pipeline.h>

#include <chrono>

namespace orthofront::spacetime {
namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

std::string step_error(const io::TimeSeries& series, std::size_t step, const char* what) {
  return "time step " + std::to_string(step) + " of " + series.describe() + ": " + what;
}

struct Work {
  LoadedStep out;
  io::RawStep raw;
};

}  // namespace

LoadedStep load_step(const io::TimeSeries& series, std::size_t step) {
  LoadedStep out;
  out.step = step;
  try {
    auto t0 = Clock::now();
    io::RawStep raw = series.read_raw(step);
    out.read_seconds = seconds_since(t0);
    out.raw_bytes = raw.bytes.size();
    t0 = Clock::now();
    out.values.resize(series.step_floats());
    series.decode(raw, out.values);
    out.decode_seconds = seconds_since(t0);
  } catch (const std::exception& e) {
    out.values = {};
    out.error = step_error(series, step, e.what());
  }
  return out;
}

StepPipeline::StepPipeline(const io::TimeSeries& series, Publish publish,
                           StepPipelineOptions options)
    : series_(series), publish_(std::move(publish)), options_(std::move(options)) {
  if (options_.max_live_tokens == 0) options_.max_live_tokens = 1;
  thread_ = std::thread([this] { run(); });
}

StepPipeline::~StepPipeline() {
  cancel();
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  thread_.join();
}

void StepPipeline::submit(std::size_t step) {
  {
    std::lock_guard lock(mutex_);
    queue_.push_back(step);
  }
  wake_.notify_all();
}

void StepPipeline::cancel() {
  std::lock_guard lock(mutex_);
  queue_.clear();
}

std::size_t StepPipeline::pending() const {
  std::lock_guard lock(mutex_);
  return queue_.size() + in_flight_;
}

double StepPipeline::read_seconds() const {
  std::lock_guard lock(mutex_);
  return read_seconds_;
}

void StepPipeline::run() {
  while (true) {
    {
      std::unique_lock lock(mutex_);
      wake_.wait(lock, [this] { return stop_ || !queue_.empty(); });
      if (stop_) return;
    }
    run_batch();
  }
}

// One parallel_pipeline run: it takes steps from the queue until the queue is empty (or the
// pipeline is stopped), then returns; run() waits for the next submission.
void StepPipeline::run_batch() {
  const auto transient = [this](std::ptrdiff_t bytes) {
    if (options_.transient) options_.transient(bytes);
  };
  tbb::parallel_pipeline(
      options_.max_live_tokens,
      tbb::make_filter<void, std::shared_ptr<Work>>(
          tbb::filter_mode::serial_in_order,
          [&](tbb::flow_control& fc) -> std::shared_ptr<Work> {
            std::size_t step = 0;
            {
              std::lock_guard lock(mutex_);
              if (stop_ || queue_.empty()) {
                fc.stop();
                return nullptr;
              }
              step = queue_.front();
              queue_.pop_front();
              ++in_flight_;
            }
            auto work = std::make_shared<Work>();
            work->out.step = step;
            try {
              const auto t0 = Clock::now();
              work->raw = series_.read_raw(step);
              work->out.read_seconds = seconds_since(t0);
              work->out.raw_bytes = work->raw.bytes.size();
              transient(static_cast<std::ptrdiff_t>(work->out.raw_bytes));
              std::lock_guard lock(mutex_);
              read_seconds_ += work->out.read_seconds;
            } catch (const std::exception& e) {
              work->out.error = step_error(series_, step, e.what());
            }
            return work;
          }) &
          tbb::make_filter<std::shared_ptr<Work>, std::shared_ptr<Work>>(
              tbb::filter_mode::parallel,
              [&](std::shared_ptr<Work> work) {
                if (!work->out.error.empty()) return work;
                try {
                  const auto t0 = Clock::now();
                  work->out.values.resize(series_.step_floats());
                  series_.decode(work->raw, work->out.values);
                  if (options_.convert) options_.convert(work->out.step, work->out.values);
                  work->out.decode_seconds = seconds_since(t0);
                } catch (const std::exception& e) {
                  work->out.values = {};
                  work->out.error = step_error(series_, work->out.step, e.what());
                }
                work->raw.bytes = {};
                transient(-static_cast<std::ptrdiff_t>(work->out.raw_bytes));
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
