// orthofront: flow-orthogonal stream surfaces from the command line.
#include <malloc.h>

#include <CLI/CLI.hpp>
#include <iostream>
#include <new>

#include "cli/commands.h"
#include "cli/progress_bar.h"
#include "orthofront/error.h"
#include "orthofront/io/input_files.h"

int main(int argc, char** argv) {
  // A surface's arrays grow by doubling and the quality measure allocates and frees large
  // scratch arrays: served from mmap, each of those touches fresh pages again. Keep blocks below
  // 64 MiB on the heap and the heap's top mapped, so the pages are reused instead of faulted in
  // again (the stitch and quality stages gain most; docs/benchmarks/measurements.md).
  mallopt(M_MMAP_THRESHOLD, 64 << 20);
  mallopt(M_TRIM_THRESHOLD, 128 << 20);
  mallopt(M_TOP_PAD, 16 << 20);
  // One command, one job: no output of it may replace a file it read.
  const orthofront::io::InputScope job_inputs;
  CLI::App app{"orthofront: stream surfaces with flow-orthogonal front lines"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "orthofront 0.1.0");
  orthofront::cli::add_stream_command(app);
  orthofront::cli::add_fields_command(app);
  orthofront::cli::add_demo_command(app);
  orthofront::cli::add_bench_command(app);
  orthofront::cli::add_path_command(app);
  orthofront::cli::add_batch_command(app);
  orthofront::cli::add_bench_batch_command(app);
  orthofront::cli::add_streak_command(app);
  orthofront::cli::add_bench_path_command(app);
  orthofront::cli::add_bench_streak_command(app);
  orthofront::cli::add_bench_gpu_command(app);
  orthofront::cli::add_bench_front_command(app);
  orthofront::cli::add_bench_gpu_streak_command(app);
  orthofront::cli::add_generate_command(app);
  orthofront::cli::add_info_command(app);
  orthofront::cli::add_convert_command(app);
  orthofront::cli::add_bench_grid_command(app);
  orthofront::cli::install_interrupt_handler();
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help and --version print and succeed; every other parse error is bad input: exit 2 as
    // for any other bad value (CLI11's own codes run from 101 to 120).
    if (e.get_exit_code() == static_cast<int>(CLI::ExitCodes::Success)) return app.exit(e);
    std::cerr << "orthofront: error: " << e.what() << "\n";
    if (const CLI::App* command = app.get_subcommands().empty() ? nullptr : app.get_subcommands().front())
      std::cerr << "Run 'orthofront " << command->get_name() << " --help' for the options.\n";
    else
      std::cerr << "Run 'orthofront --help' for the commands.\n";
    return 2;
  } catch (const orthofront::Error& e) {
    std::cerr << "orthofront: error: " << e.what() << "\n";
    return 2;
  } catch (const std::bad_alloc&) {
    std::cerr << "orthofront: error: out of memory in '" << (argc > 1 ? argv[1] : "") << "': "
              << "the job needs more memory than is available; lower --max-vertices or "
                 "--cache-budget, or raise --edge\n";
    return 3;
  } catch (const std::exception& e) {
    std::cerr << "orthofront: unexpected error: " << e.what() << "\n";
    return 3;
  }
  return 0;
}
