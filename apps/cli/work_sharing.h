#pragma once
/// How the processes of a batch job share its work: one process alone, or the ranks of an MPI
/// launch (`mpirun -np K orthofront batch JOB`), where rank 0 hands out work items as ranks ask
/// for them (dynamic load balancing: a rank that finishes early takes the next item).
#include <memory>
#include <string>

namespace orthofront::cli {

class WorkSharing {
 public:
  virtual ~WorkSharing() = default;
  virtual int rank() const = 0;
  virtual int size() const = 0;
  /// The next work item in [0, count) for this process, or -1 when every item is taken. Every
  /// process calls it until it returns -1, with the same count.
  virtual long next(long count) = 0;
  /// Rank 0's `message` on every rank (empty: go on); for errors found before the work starts.
  virtual std::string broadcast(const std::string& message) = 0;
  /// Returns when every process got here.
  virtual void barrier() = 0;
  /// Stops every process (an error on one rank after the work started).
  [[noreturn]] virtual void abort(int status) = 0;
};

/// True when this process was started by an MPI launcher (mpirun / mpiexec).
bool launched_by_mpi();
/// MPI when launched by an MPI launcher (throws InvalidArgument when this build has no MPI);
/// else one process alone.
std::unique_ptr<WorkSharing> start_work_sharing();
/// Whether this build can run under MPI, and the launcher it was built with ("" if none).
bool have_mpi();
std::string mpi_launcher();

}  // namespace orthofront::cli
