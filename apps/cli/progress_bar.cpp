#include "cli/progress_bar.h"

#include <unistd.h>

#include <csignal>
#include <cstdio>

#include "jobs/process_memory.h"

namespace orthofront::cli {

using namespace jobs;

namespace {
volatile std::sig_atomic_t g_interrupted = 0;
// The first SIGINT or SIGTERM asks the run to stop and write what it built; a second one
// (a user who does not want to wait for that write) ends the process at once.
extern "C" void on_interrupt(int signal) {
  if (g_interrupted != 0) {
    std::signal(signal, SIG_DFL);
    std::raise(signal);
    return;
  }
  g_interrupted = 1;
}
}  // namespace

bool interrupted() { return g_interrupted != 0; }

void install_interrupt_handler() {
  std::signal(SIGINT, on_interrupt);
  std::signal(SIGTERM, on_interrupt);
}

ProgressBar::ProgressBar(std::string label, std::size_t vertex_cap)
    : label_(std::move(label)), vertex_cap_(vertex_cap), enabled_(isatty(STDERR_FILENO) != 0) {}

ProgressBar::~ProgressBar() { finish(); }

bool ProgressBar::update(const Progress& p) {
  if (enabled_ && (p.elapsed_seconds - last_draw_ >= 0.1 || p.step == p.max_steps)) {
    last_draw_ = p.elapsed_seconds;
    const int width = 30;
    const double share = p.max_steps > 0 ? static_cast<double>(p.step) / p.max_steps : 1.0;
    const int filled = static_cast<int>(share * width);
    std::string bar(static_cast<std::size_t>(filled), '#');
    bar.resize(width, '.');
    char vertices[64];
    if (vertex_cap_ > 0)
      std::snprintf(vertices, sizeof vertices, "%zu of %zu vertices", p.vertices, vertex_cap_);
    else
      std::snprintf(vertices, sizeof vertices, "%zu vertices", p.vertices);
    // Resident memory is read only when a line is drawn (at most ~10 times a second).
    std::fprintf(stderr, "\r%s [%s] step %d/%d  %s  RSS %s  %zu fronts (%zu front vertices)  %.1fs ",
                 label_.c_str(), bar.c_str(), p.step, p.max_steps, vertices,
                 format_memory(current_rss_bytes()).c_str(), p.fronts, p.front_vertices,
                 p.elapsed_seconds);
    std::fflush(stderr);
    drawn_ = true;
  }
  return !interrupted();
}

void ProgressBar::finish() {
  if (drawn_) {
    std::fprintf(stderr, "\n");
    drawn_ = false;
  }
}

}  // namespace orthofront::cli
