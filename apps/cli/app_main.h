#pragma once
/// What `orthofront` and `orthofront-bench` do around their subcommands: the allocator's
/// settings, one input scope for the job, the interrupt handler, and exit codes (0 done, 2 bad
/// input, 3 an internal error or out of memory) with the error on stderr.
#include <CLI/CLI.hpp>
#include <string>

namespace orthofront::cli {

/// Parses and runs `app` (its subcommands registered); returns the exit code. Messages start
/// with `program`.
int run_app(CLI::App& app, const char* program, int argc, char** argv);

/// The path of the program `name` in this program's folder (the benchmarks run `orthofront`'s
/// commands as a user does, from the build or install folder they were started from).
std::string program_beside(const std::string& name);

}  // namespace orthofront::cli
