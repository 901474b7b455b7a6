#pragma once
/// Pictures beside a run's outputs: a rendered PNG of the surface (--preview) and the paper's two
/// quality histograms beside every JSON report. They are drawn by the Python package's helper
/// (`python3 -m orthofront.preview`: VTK's renderer and matplotlib), so the commands and the
/// module draw the same pictures.
#include <CLI/CLI.hpp>
#include <filesystem>
#include <string>
#include <vector>

namespace orthofront::cli {

/// R.json -> R.histograms.svg
std::filesystem::path histograms_path(const std::filesystem::path& report);

/// False when the environment sets ORTHOFRONT_HISTOGRAMS=0 (runs that want the JSON only).
bool histograms_wanted();

struct PictureRequest {
  struct Render {
    std::filesystem::path mesh, png;
    std::string color_by;  ///< empty: time, age, alpha or s
  };
  struct Plot {
    std::filesystem::path report, histograms;
  };
  std::vector<Render> renders;
  std::vector<Plot> plots;
};

/// Runs the helper once for every picture of `request` and waits for it. Returns an empty string on
/// success, otherwise why not (no Python module in this build, the helper's exit status); the
/// helper's own message goes to stderr.
std::string draw_pictures(const PictureRequest& request);

/// The histograms of `report` beside it, when wanted: prints where they went, or a warning (a
/// missing picture never fails a run).
void write_report_histograms(const std::filesystem::path& report, bool quiet);

/// --preview FILE.png and --preview-color ATTR of stream, path and streak.
struct PreviewFlags {
  std::string png;
  std::string color;
};
void add_preview_flags(CLI::App& command, PreviewFlags& flags);
/// Before the run: refuses a --preview that is not a writable .png (InvalidArgument).
void check_preview(const PreviewFlags& flags);

/// After a run's outputs are in place: the histograms beside `report` (when one was written) and
/// the --preview picture of `mesh`. Throws Error when the picture asked for could not be drawn.
void draw_run_pictures(const PreviewFlags& flags, const std::filesystem::path& mesh,
                       const std::string& report, bool quiet);

}  // namespace orthofront::cli
