// orthofront: stream, path and streak surfaces with flow-orthogonal front lines.
#include <CLI/CLI.hpp>

#include "cli/app_main.h"
#include "cli/commands.h"

int main(int argc, char** argv) {
  CLI::App app{"orthofront: stream, path and streak surfaces with flow-orthogonal front lines "
               "(benchmarks: orthofront-bench)"};
  app.set_version_flag("--version", "orthofront 0.1.0");
  orthofront::cli::add_stream_command(app);
  orthofront::cli::add_path_command(app);
  orthofront::cli::add_streak_command(app);
  orthofront::cli::add_batch_command(app);
  orthofront::cli::add_fields_command(app);
  orthofront::cli::add_generate_command(app);
  orthofront::cli::add_convert_command(app);
  orthofront::cli::add_info_command(app);
  orthofront::cli::add_demo_command(app);
  return orthofront::cli::run_app(app, "orthofront", argc, argv);
}
