#pragma once
/// A one-line progress bar on stderr, drawn only when stderr is a terminal: steps, vertices
/// (against the vertex cap when one is given), fronts and the resident memory.
#include <string>

#include "orthofront/engine/stream_surface.h"

namespace orthofront::cli {

class ProgressBar {
 public:
  /// `vertex_cap` > 0: show the vertices as "N of CAP" (how close the run is to stopping).
  explicit ProgressBar(std::string label, std::size_t vertex_cap = 0);
  ~ProgressBar();
  ProgressBar(const ProgressBar&) = delete;
  ProgressBar& operator=(const ProgressBar&) = delete;
  /// Draws the bar (at most ~10 times a second); returns false once Ctrl-C was pressed.
  bool update(const Progress& progress);
  void finish();

 private:
  std::string label_;
  std::size_t vertex_cap_ = 0;
  bool enabled_ = false;
  bool drawn_ = false;
  double last_draw_ = -1;
};

/// True once SIGINT or SIGTERM arrived (the handler is installed by install_interrupt_handler;
/// a second signal ends the process at once).
bool interrupted();
void install_interrupt_handler();

}  // namespace orthofront::cli
