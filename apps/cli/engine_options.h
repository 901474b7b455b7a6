#pragma once
/// Command-line flags for the engine options, shared by the subcommands that run the engine.
#include <CLI/CLI.hpp>

#include "orthofront/engine/options.h"

namespace orthofront::cli {

/// Adds --edge, --steps, --method, --mu-mode, ... bound to `options`.
void add_engine_flags(CLI::App& command, StreamSurfaceOptions& options);

}  // namespace orthofront::cli
