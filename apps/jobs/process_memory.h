#pragma once
/// What this process and the machine have of memory (Linux /proc; 0 where it is not available),
/// and the limits a run derives from the memory it may use (--memory).
#include <cstddef>
#include <string>

namespace orthofront::jobs {

/// This process's peak resident set (VmHWM).
std::size_t peak_rss_bytes();
/// This process's resident set now (/proc/self/statm).
std::size_t current_rss_bytes();
/// Memory this process can still take: the least of the machine's MemAvailable, what its
/// cgroups' memory limits leave and what RLIMIT_AS (ulimit -v) leaves of its address space.
std::size_t available_memory_bytes();

/// Bytes a mesh vertex costs with everything that grows with it (mesh, fronts, quality
/// measurement): measured 266 B on a 1.56 M-vertex Lorenz stream surface and 260-290 B on
/// 1-3 M-vertex double-gyre path surfaces.
inline constexpr std::size_t kBytesPerVertex = 300;
/// The most vertices any default allows (a mesh of 50 M vertices is ~15 GB).
inline constexpr std::size_t kMaxDefaultVertices = 50'000'000;

/// Vertex cap for a run that may use `memory_bytes`: half of it at kBytesPerVertex, at most
/// kMaxDefaultVertices (0 bytes, i.e. unknown: kMaxDefaultVertices). The other half is for the
/// process itself, path's data cache (a quarter) and the final write.
std::size_t vertex_budget_for(std::size_t memory_bytes);
/// Default vertex budget when no --memory is given: vertex_budget_for(available memory), at
/// least 100,000 (MemAvailable can be momentarily tiny on a busy machine).
std::size_t default_vertex_budget();
/// Default data-cache budget of `path` for a run that may use `memory_bytes`: a quarter of it
/// (512 MiB when the memory is unknown).
std::size_t cache_budget_for(std::size_t memory_bytes);

/// "123 MiB", "1.5 GiB": memory figures in messages and on the progress line.
std::string format_memory(std::size_t bytes);

}  // namespace orthofront::jobs
