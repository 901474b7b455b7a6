// orthofront-bench: the benchmarks, each with its baselines side by side in one run, apart from
// the user's commands.
#include <CLI/CLI.hpp>

#include "cli/app_main.h"
#include "cli/commands.h"

int main(int argc, char** argv) {
  CLI::App app{"orthofront-bench: benchmarks of orthofront, each beside its baselines in one run"};
  app.set_version_flag("--version", "orthofront-bench 0.1.0");
  orthofront::cli::add_bench_command(app);
  orthofront::cli::add_bench_path_command(app);
  orthofront::cli::add_bench_streak_command(app);
  orthofront::cli::add_bench_gpu_streak_command(app);
  orthofront::cli::add_bench_batch_command(app);
  orthofront::cli::add_bench_grid_command(app);
  orthofront::cli::add_bench_gpu_command(app);
  orthofront::cli::add_bench_front_command(app);
  return orthofront::cli::run_app(app, "orthofront-bench", argc, argv);
}
