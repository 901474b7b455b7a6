#include "cli/pictures.h"

#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "orthofront/error.h"
#include "orthofront/io/atomic_file.h"

namespace orthofront::cli {

namespace {

/// The interpreter and package folder found at configure time; ORTHOFRONT_PYTHON overrides the
/// interpreter.
std::string python_interpreter() {
  if (const char* given = std::getenv("ORTHOFRONT_PYTHON"); given && *given) return given;
#ifdef ORTHOFRONT_PYTHON3
  return ORTHOFRONT_PYTHON3;
#else
  return {};
#endif
}

/// The installed package, where this program is installed (PREFIX/bin); else the build tree's.
std::string python_package_dir() {
#ifdef ORTHOFRONT_PYTHON_DIR
  std::error_code error;
  const std::filesystem::path program = std::filesystem::read_symlink("/proc/self/exe", error);
  const std::filesystem::path installed =
      program.parent_path().parent_path() / ORTHOFRONT_PYTHON_INSTALL_DIR;
  if (!error && std::filesystem::exists(installed / "orthofront" / "preview.py", error))
    return installed.string();
  return ORTHOFRONT_PYTHON_DIR;
#else
  return {};
#endif
}

}  // namespace

std::filesystem::path histograms_path(const std::filesystem::path& report) {
  std::filesystem::path out = report;
  out.replace_extension(".histograms.svg");
  return out;
}

bool histograms_wanted() {
  const char* value = std::getenv("ORTHOFRONT_HISTOGRAMS");
  return value == nullptr || std::string(value) != "0";
}

std::string draw_pictures(const PictureRequest& request) {
  const std::string python = python_interpreter();
  const std::string package = python_package_dir();
  if (python.empty() || package.empty())
    return "this build has no Python module (install pybind11-dev, python3-dev, python3-numpy, "
           "python3-paraview, python3-matplotlib and xvfb, and configure again)";
  std::vector<std::string> args = {python, "-m", "orthofront.preview"};
  for (const PictureRequest::Render& r : request.renders)
    args.insert(args.end(), {"--mesh", r.mesh.string(), "--png", r.png.string(), "--color",
                             r.color_by.empty() ? "auto" : r.color_by});
  for (const PictureRequest::Plot& p : request.plots)
    args.insert(args.end(), {"--report", p.report.string(), "--histograms", p.histograms.string()});
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  std::fflush(stdout);
  std::fflush(stderr);
  const pid_t child = fork();
  if (child < 0) return "cannot start " + python;
  if (child == 0) {
    const char* old = std::getenv("PYTHONPATH");
    const std::string path = package + (old && *old ? ":" + std::string(old) : "");
    setenv("PYTHONPATH", path.c_str(), 1);
    execv(argv[0], argv.data());
    std::fprintf(stderr, "orthofront: cannot run %s\n", argv[0]);
    _exit(127);
  }
  int status = 0;
  while (waitpid(child, &status, 0) < 0) {
  }
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0) return {};
  return python + " -m orthofront.preview " +
         (WIFEXITED(status) ? "exited with status " + std::to_string(WEXITSTATUS(status))
                            : std::string("was killed"));
}

void write_report_histograms(const std::filesystem::path& report, bool quiet) {
  if (!histograms_wanted()) return;
  PictureRequest request;
  request.plots.push_back({report, histograms_path(report)});
  if (const std::string why = draw_pictures(request); !why.empty())
    std::fprintf(stderr, "orthofront: warning: no histograms beside %s: %s\n",
                 report.string().c_str(), why.c_str());
  else if (!quiet)
    std::printf("Wrote the quality histograms to %s\n",
                request.plots.front().histograms.string().c_str());
}

void add_preview_flags(CLI::App& command, PreviewFlags& flags) {
  command.add_option("--preview", flags.png,
                     "Also write a rendered picture of the surface (PNG; streak: the last frame)");
  command.add_option("--preview-color", flags.color,
                     "Attribute the --preview picture is coloured by (time, age, alpha, s, error, "
                     "speed, step, quality; default: time, age or alpha)");
}

void check_preview(const PreviewFlags& flags) {
  if (flags.png.empty()) {
    if (!flags.color.empty()) throw InvalidArgument("--preview-color needs --preview FILE.png");
    return;
  }
  if (std::filesystem::path(flags.png).extension() != ".png")
    throw InvalidArgument("--preview '" + flags.png + "' must name a .png file");
  io::check_writable(flags.png);
}

void draw_run_pictures(const PreviewFlags& flags, const std::filesystem::path& mesh,
                       const std::string& report, bool quiet) {
  if (!report.empty()) write_report_histograms(report, quiet);
  if (flags.png.empty()) return;
  PictureRequest request;
  request.renders.push_back({mesh, flags.png, flags.color});
  if (const std::string why = draw_pictures(request); !why.empty())
    throw Error("--preview: no picture written to " + flags.png + ": " + why +
                " (the surface is in " + mesh.string() + ")");
  if (!quiet) std::printf("Wrote the picture %s\n", flags.png.c_str());
}

}  // namespace orthofront::cli
