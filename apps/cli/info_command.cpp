// `orthofront info FILE`: what a gridded data file holds (format, grid, steps, units, storage)
// and statistics over every step (value ranges, NaN/fill and zero vectors).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cli/commands.h"
#include "cli/progress_bar.h"
#include "orthofront/error.h"
#include "orthofront/io/data_file.h"

namespace orthofront::cli {

namespace {

struct InfoArgs {
  std::string file;
  bool json = false;
  bool no_stats = false;
};

struct Statistics {
  std::vector<double> min, max;
  std::uint64_t points = 0, missing = 0, zero = 0;
};

std::string number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.9g", value);
  return text;
}

std::string triple(const Vec3& v, int n) {
  std::string text = "(";
  for (int a = 0; a < n; ++a) text += (a ? ", " : "") + number(v[a]);
  return text + ")";
}

Statistics scan(const io::TimeSeries& series) {
  const int c = series.components();
  Statistics stats;
  stats.min.assign(static_cast<std::size_t>(c), std::numeric_limits<double>::infinity());
  stats.max.assign(static_cast<std::size_t>(c), -std::numeric_limits<double>::infinity());
  std::vector<float> values(series.step_floats());
  for (std::size_t s = 0; s < series.step_count(); ++s) {
    if (interrupted()) throw Error("interrupted while scanning step " + std::to_string(s));
    series.read(s, values);
    for (std::size_t p = 0; p < values.size(); p += static_cast<std::size_t>(c)) {
      ++stats.points;
      bool nan = false, zero = true;
      for (int k = 0; k < c; ++k) {
        const float v = values[p + static_cast<std::size_t>(k)];
        nan = nan || std::isnan(v);
        zero = zero && v == 0.0f;
      }
      if (nan) {
        ++stats.missing;
        continue;
      }
      if (zero) ++stats.zero;
      for (int k = 0; k < c; ++k) {
        const auto uk = static_cast<std::size_t>(k);
        const double v = values[p + uk];
        stats.min[uk] = std::min(stats.min[uk], v);
        stats.max[uk] = std::max(stats.max[uk], v);
      }
    }
  }
  return stats;
}

nlohmann::json describe(const std::string& spec, const io::DataFile& file,
                        const Statistics* stats) {
  const io::TimeSeries& series = *file.series;
  const GridGeometry& g = series.geometry();
  nlohmann::json j;
  j["file"] = spec;
  j["format"] = file.format;
  for (const auto& [key, value] : file.details) j["details"][key] = value;
  j["grid"]["type"] = g.rectilinear() ? "rectilinear" : "uniform";
  j["grid"]["dimension"] = g.dimension;
  j["grid"]["size"] = {g.size[0], g.size[1], g.size[2]};
  const Box<3> b = g.bounds();
  j["grid"]["bounds"] = {{b.lo.x(), b.hi.x()}, {b.lo.y(), b.hi.y()}, {b.lo.z(), b.hi.z()}};
  if (!g.rectilinear()) {
    j["grid"]["origin"] = {g.origin.x(), g.origin.y(), g.origin.z()};
    j["grid"]["spacing"] = {g.spacing.x(), g.spacing.y(), g.spacing.z()};
  }
  j["components"] = series.components();
  j["steady"] = file.steady;
  j["steps"] = series.step_count();
  std::vector<double> times;
  for (std::size_t s = 0; s < series.step_count(); ++s) times.push_back(series.time(s));
  j["times"] = times;
  j["bytes_per_step"] = series.step_bytes();
  if (file.stored_bytes > 0) j["stored_bytes"] = file.stored_bytes;
  if (stats) {
    const char* names[] = {"v_x", "v_y", "v_z"};
    for (int k = 0; k < series.components(); ++k) {
      const auto uk = static_cast<std::size_t>(k);
      j["ranges"][names[k]] = stats->points > stats->missing
                                  ? nlohmann::json{stats->min[uk], stats->max[uk]}
                                  : nlohmann::json();
    }
    j["points"] = stats->points;
    j["missing_points"] = stats->missing;
    j["zero_vectors"] = stats->zero;
  }
  return j;
}

std::string percent(std::uint64_t part, std::uint64_t whole) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3g%%",
                whole ? 100.0 * static_cast<double>(part) / static_cast<double>(whole) : 0.0);
  return text;
}

void print_text(const nlohmann::json& j, const io::DataFile& file, const Statistics* stats) {
  const io::TimeSeries& series = *file.series;
  const GridGeometry& g = series.geometry();
  std::cout << "file:         " << j["file"].get<std::string>() << "\n";
  std::cout << "format:       " << file.format << "\n";
  for (const auto& [key, value] : file.details) {
    std::string label = key + ":";
    label.resize(std::max<std::size_t>(label.size() + 1, 14), ' ');
    std::cout << label << value << "\n";
  }
  std::cout << "grid:         " << (g.rectilinear() ? "rectilinear " : "uniform ") << g.dimension
            << "D, " << g.size[0] << " x " << g.size[1];
  if (g.dimension == 3) std::cout << " x " << g.size[2];
  std::cout << " points\n";
  if (!g.rectilinear()) {
    std::cout << "origin:       " << triple(g.origin, 3) << "\n";
    std::cout << "spacing:      " << triple(g.spacing, g.dimension) << "\n";
  }
  const Box<3> b = g.bounds();
  std::cout << "bounds:       [" << number(b.lo.x()) << ", " << number(b.hi.x()) << "] x ["
            << number(b.lo.y()) << ", " << number(b.hi.y()) << "] x [" << number(b.lo.z()) << ", "
            << number(b.hi.z()) << "]\n";
  std::cout << "components:   " << series.components() << "\n";
  if (file.steady) {
    std::cout << "steps:        steady\n";
  } else {
    const std::size_t n = series.step_count();
    std::cout << "steps:        " << n << ", times";
    for (std::size_t s = 0; s < n; ++s) {
      if (n > 8 && s == 4) {
        std::cout << " ...";
        s = n - 3;
      }
      std::cout << " " << number(series.time(s));
    }
    std::cout << "\n";
  }
  char mib[32];
  std::snprintf(mib, sizeof mib, "%.1f",
                static_cast<double>(series.step_bytes()) / (1024.0 * 1024.0));
  std::cout << "bytes/step:   " << series.step_bytes() << " (" << mib << " MiB)\n";
  if (file.stored_bytes > 0) {
    const double total =
        static_cast<double>(series.step_bytes()) * static_cast<double>(series.step_count());
    char ratio[32];
    std::snprintf(ratio, sizeof ratio, "%.2f", total / static_cast<double>(file.stored_bytes));
    std::cout << "on disk:      " << file.stored_bytes << " bytes (" << ratio << ":1)\n";
  }
  if (stats) {
    const char* names[] = {"v_x", "v_y", "v_z"};
    std::cout << "ranges:      ";
    for (int k = 0; k < series.components(); ++k) {
      const auto uk = static_cast<std::size_t>(k);
      std::cout << " " << names[k] << " ";
      if (stats->points > stats->missing)
        std::cout << "[" << number(stats->min[uk]) << ", " << number(stats->max[uk]) << "]";
      else
        std::cout << "-";
    }
    std::cout << "  (over all steps)\n";
    std::cout << "NaN/fill:     " << stats->missing << " of " << stats->points << " points ("
              << percent(stats->missing, stats->points) << ")\n";
    std::cout << "zero vectors: " << stats->zero << " (" << percent(stats->zero, stats->points)
              << ")\n";
  }
}

}  // namespace

void add_info_command(CLI::App& app) {
  auto args = std::make_shared<InfoArgs>();
  CLI::App* c = app.add_subcommand(
      "info", "Describe a gridded data file: grid, steps, units, storage, value statistics");
  c->add_option("file", args->file, "FILE.ext[:SELECTOR] (e.g. flow.h5 or flow.h5:/group)")
      ->required();
  c->add_flag("--json", args->json, "Print JSON instead of text");
  c->add_flag("--no-stats", args->no_stats, "Skip reading the samples (ranges, NaN, zeros)");
  c->callback([args]() {
    const io::DataFile file = io::open_data_file(args->file);
    Statistics stats;
    if (!args->no_stats) stats = scan(*file.series);
    const Statistics* s = args->no_stats ? nullptr : &stats;
    const nlohmann::json j = describe(args->file, file, s);
    if (args->json)
      std::cout << j.dump(2) << "\n";
    else
      print_text(j, file, s);
  });
}

}  // namespace orthofront::cli
