#include "cli/commands.h"
namespace orthofront::cli {
void add_demo_command(CLI::App& app) { (void)app; }
}
