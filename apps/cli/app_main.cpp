#include "cli/app_main.h"

#include <malloc.h>

#include <cstring>
#include <filesystem>
#include <iostream>
#include <new>

#include "cli/progress_bar.h"
#include "orthofront/error.h"
#include "orthofront/io/input_files.h"

namespace orthofront::cli {

int run_app(CLI::App& app, const char* program, int argc, char** argv) {
  // A surface's arrays grow by doubling and the quality measure allocates and frees large
  // scratch arrays: served from mmap, each of those touches fresh pages again. Keep blocks below
  // 64 MiB on the heap and the heap's top mapped, so the pages are reused instead of faulted in
  // again (the stitch and quality stages gain most; docs/benchmarks/measurements.md).
  mallopt(M_MMAP_THRESHOLD, 64 << 20);
  mallopt(M_TRIM_THRESHOLD, 128 << 20);
  mallopt(M_TOP_PAD, 16 << 20);
  // One command, one job: no output of it may replace a file it read.
  const io::InputScope job_inputs;
  app.require_subcommand(1);
  install_interrupt_handler();
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help and --version print and succeed; every other parse error is bad input: exit 2 as
    // for any other bad value (CLI11's own codes run from 101 to 120).
    if (e.get_exit_code() == static_cast<int>(CLI::ExitCodes::Success)) return app.exit(e);
    std::cerr << program << ": error: " << e.what() << "\n";
    if (const CLI::App* command = app.get_subcommands().empty() ? nullptr : app.get_subcommands().front())
      std::cerr << "Run '" << program << " " << command->get_name() << " --help' for the options.\n";
    else if (argc > 1 && std::strncmp(argv[1], "bench", 5) == 0 && std::strcmp(program, "orthofront") == 0)
      std::cerr << "The benchmarks are in their own program: run 'orthofront-bench --help'.\n";
    else
      std::cerr << "Run '" << program << " --help' for the commands.\n";
    return 2;
  } catch (const Error& e) {
    std::cerr << program << ": error: " << e.what() << "\n";
    return 2;
  } catch (const std::bad_alloc&) {
    std::cerr << program << ": error: out of memory in '" << (argc > 1 ? argv[1] : "") << "': "
              << "the job needs more memory than is available; lower --max-vertices or "
                 "--cache-budget, or raise --edge\n";
    return 3;
  } catch (const std::exception& e) {
    std::cerr << program << ": unexpected error: " << e.what() << "\n";
    return 3;
  }
  return 0;
}

std::string program_beside(const std::string& name) {
  return (std::filesystem::read_symlink("/proc/self/exe").parent_path() / name).string();
}

}  // namespace orthofront::cli
