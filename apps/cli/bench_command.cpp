#include "cli/commands.h"
namespace orthofront::cli {
void add_bench_command(CLI::App& app) { (void)app; }
}
