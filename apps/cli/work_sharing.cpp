#include "cli/work_sharing.h"

#include <chrono>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <thread>
#include <vector>

#include "orthofront/error.h"

#ifdef ORTHOFRONT_HAVE_MPI
#include <mpi.h>
#endif

namespace orthofront::cli {

namespace {

class Alone final : public WorkSharing {
 public:
  int rank() const override { return 0; }
  int size() const override { return 1; }
  long next(long count) override { return taken_ < count ? taken_++ : -1; }
  std::string broadcast(const std::string& message) override { return message; }
  void barrier() override {}
  [[noreturn]] void abort(int status) override { std::exit(status); }

 private:
  long taken_ = 0;
};

#ifdef ORTHOFRONT_HAVE_MPI
constexpr int kAsk = 1, kGive = 2;

// Rank 0 serves the other ranks' requests from a thread of its own while its main thread works
// too; it takes its own items from the same counter.
class Mpi final : public WorkSharing {
 public:
  Mpi() {
    int provided = 0;
    MPI_Init_thread(nullptr, nullptr, MPI_THREAD_MULTIPLE, &provided);
    if (provided < MPI_THREAD_MULTIPLE) {
      MPI_Finalize();
      throw InvalidArgument("batch under MPI needs an MPI library with MPI_THREAD_MULTIPLE");
    }
    MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
    MPI_Comm_size(MPI_COMM_WORLD, &size_);
  }
  ~Mpi() override {
    if (server_.joinable()) server_.join();
    MPI_Finalize();
  }
  int rank() const override { return rank_; }
  int size() const override { return size_; }

  long next(long count) override {
    if (rank_ == 0) {
      if (!server_.joinable() && size_ > 1) server_ = std::thread([this, count] { serve(count); });
      return take(count);
    }
    long item = -1;
    int ask = 1;
    MPI_Send(&ask, 1, MPI_INT, 0, kAsk, MPI_COMM_WORLD);
    MPI_Recv(&item, 1, MPI_LONG, 0, kGive, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    return item;
  }

  std::string broadcast(const std::string& message) override {
    long length = static_cast<long>(message.size());
    MPI_Bcast(&length, 1, MPI_LONG, 0, MPI_COMM_WORLD);
    std::string out = rank_ == 0 ? message : std::string(static_cast<std::size_t>(length), '\0');
    if (length > 0) MPI_Bcast(out.data(), static_cast<int>(length), MPI_CHAR, 0, MPI_COMM_WORLD);
    return out;
  }

  void barrier() override {
    if (server_.joinable()) server_.join();  // every other rank has been told "none left"
    MPI_Barrier(MPI_COMM_WORLD);
  }

  [[noreturn]] void abort(int status) override {
    MPI_Abort(MPI_COMM_WORLD, status);
    std::exit(status);
  }

 private:
  long take(long count) {
    std::lock_guard<std::mutex> lock(mutex_);
    return taken_ < count ? taken_++ : -1;
  }
  // Answers every request; each rank asks until it gets -1, so size - 1 such answers end it.
  // Polls (a blocking receive spins a core in most MPI libraries: one the work needs).
  void serve(long count) {
    int finished = 0;
    while (finished < size_ - 1) {
      int ask = 0;
      MPI_Status status;
      MPI_Request request;
      MPI_Irecv(&ask, 1, MPI_INT, MPI_ANY_SOURCE, kAsk, MPI_COMM_WORLD, &request);
      for (int arrived = 0;;) {
        MPI_Test(&request, &arrived, &status);
        if (arrived) break;
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
      }
      const long item = take(count);
      MPI_Send(&item, 1, MPI_LONG, status.MPI_SOURCE, kGive, MPI_COMM_WORLD);
      if (item < 0) ++finished;
    }
  }

  int rank_ = 0, size_ = 1;
  std::mutex mutex_;
  long taken_ = 0;
  std::thread server_;
};
#endif

}  // namespace

bool launched_by_mpi() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK", "MPI_LOCALNRANKS"})
    if (std::getenv(name) != nullptr) return true;
  return false;
}

bool have_mpi() {
#ifdef ORTHOFRONT_HAVE_MPI
  return true;
#else
  return false;
#endif
}

std::string mpi_launcher() {
#ifdef ORTHOFRONT_MPIEXEC
  return ORTHOFRONT_MPIEXEC;
#else
  return "";
#endif
}

std::unique_ptr<WorkSharing> start_work_sharing() {
  if (!launched_by_mpi()) return std::make_unique<Alone>();
#ifdef ORTHOFRONT_HAVE_MPI
  return std::make_unique<Mpi>();
#else
  throw InvalidArgument(
      "batch was started by an MPI launcher, but this orthofront was built without MPI "
      "(install libopenmpi-dev and configure with -DORTHOFRONT_MPI=ON)");
#endif
}

}  // namespace orthofront::cli
