#pragma once
/// What this process and the machine have of memory (Linux /proc; 0 where it is not available).
#include <cstddef>

namespace orthofront::cli {

/// This process's peak resident set (VmHWM).
std::size_t peak_rss_bytes();
/// Memory the machine can still give (MemAvailable).
std::size_t available_memory_bytes();
/// Default vertex budget: what half the available memory holds at about 300 bytes a vertex
/// (mesh, fronts, quality measurement; measured 266 B on a 1.56 M-vertex Lorenz surface), at most
/// 50 M.
std::size_t default_vertex_budget();

}  // namespace orthofront::cli
