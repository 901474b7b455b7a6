#pragma once
/// A job's options (jobs/option_set.h) as command-line flags: --NAME for each, with its doc,
/// default and group (a benchmark's baseline accepted but left out of --help).
#include <CLI/CLI.hpp>
#include <memory>

#include "jobs/option_set.h"

namespace orthofront::cli {

/// Registers every option of `options` on `command`. The flags parse into the set (which
/// records what was given, jobs::OptionSet::given); a value it refuses is a CLI11 validation
/// error naming the flag.
void add_option_flags(CLI::App& command, const std::shared_ptr<jobs::OptionSet>& options);

}  // namespace orthofront::cli
