#pragma once
/// Reading a file with a library that trusts its input (OpenVDB) in a child process first: a
/// corrupt file may crash that reader, loop in it or make it allocate without bound, and each of
/// those must end as a message naming the file, not take this process down. The child runs the
/// same reads under a memory and time limit; only when it finishes cleanly does this process read
/// the file itself (from the page cache the child warmed).
#include <cstddef>
#include <functional>
#include <string>

namespace orthofront::io {

struct ChildReadLimits {
  std::size_t memory_bytes = 0;  ///< address space the child may add (0: no limit)
  /// CPU time the child may use (RLIMIT_CPU: a reader looping on a damaged file burns CPU, and
  /// a busy machine does not count against it); the child is also killed after ten times this in
  /// wall-clock time (a reader blocked for good).
  double seconds = 60;
};

/// True when the environment variable ORTHOFRONT_TRUST_FILES is set to 1: files are read here
/// directly, without the child (for data from a known source, when every second counts).
bool files_trusted();

/// The CPU-time limit for a first read of a file of `bytes`: 10 s plus 1 s per 20 MB, or the
/// environment variable ORTHOFRONT_READ_TIMEOUT (seconds) where it is set.
double child_read_seconds(std::size_t bytes);

/// Runs `read` in a forked child under `limits`. Returns when the child returned from `read`.
/// Throws FormatError naming `file` and `format` otherwise: the child's own error message when it
/// threw one of the project's errors; "needs more than N MiB" when it ran out of its memory limit;
/// "did not finish within N s" when it was killed at a time limit; the signal when it crashed.
/// Without a sanitizer build, the memory limit is RLIMIT_AS over the current address space (a
/// sanitizer reserves terabytes of it, so there only the time limit applies).
void read_in_child(const std::string& file, const std::string& format,
                   const std::function<void()>& read, const ChildReadLimits& limits);

}  // namespace orthofront::io
