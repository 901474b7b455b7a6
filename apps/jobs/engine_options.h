#pragma once
/// The engine's options (ℓ, steps, method, ...) and the memory a run may use, as every surface
/// kind that runs the engine takes them.
#include <cstddef>
#include <nlohmann/json.hpp>
#include <string>

#include "jobs/option_set.h"
#include "orthofront/engine/options.h"

namespace orthofront::jobs {

/// Adds edge, steps, method, mu-mode, ... bound to `options` (the vertex cap's default from the
/// memory available now).
void add_engine_options(OptionSet& set, StreamSurfaceOptions& options);

/// --memory: what a run may use. The vertex cap (and the cache budgets) derive from it unless
/// given themselves.
struct MemoryLimits {
  std::string memory;             ///< memory as given; empty: the memory available at start
  std::size_t memory_bytes = 0;   ///< resolved by apply_memory_limits (0: unknown)
  bool memory_given = false;
  bool max_vertices_given = false;
  std::size_t max_vertices = 0;   ///< the cap in force

  /// Where the cap comes from, e.g. "half of --memory 128 MiB at ~300 B a vertex".
  std::string cap_source() const;
  /// What raises the cap, e.g. "raise --memory (or --max-vertices, which wins over it)".
  std::string raise_advice() const;
  /// The limits as the JSON report records them.
  nlohmann::json to_json() const;
};

/// Adds memory (the byte syntax of the cache budget: 512MiB, 2GiB, 100MB, 65536).
void add_memory_option(OptionSet& set, MemoryLimits& limits);
/// After parsing: resolves the memory and sets options.max_vertices from it unless max-vertices
/// was given (an explicit cap wins).
void apply_memory_limits(const OptionSet& set, MemoryLimits& limits,
                         StreamSurfaceOptions& options);
/// What a run reached when the vertex cap stopped it: the cap and where it comes from, the
/// vertices, the resident memory now and at its peak.
std::string vertex_cap_reached(const MemoryLimits& limits, std::size_t vertices);

}  // namespace orthofront::jobs
