#include "orthofront/io/grid_series.h"

#include <glob.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <sstream>

#include "orthofront/error.h"
#include "orthofront/io/input_files.h"
#include "orthofront/io/error.h"
#include "orthofront/io/grid_decode.h"
#include "orthofront/io/grid_file.h"
#include "orthofront/io/number_text.h"
#include "orthofront/io/vtk_xml.h"

namespace orthofront::io {
namespace {

bool same_geometry(const GridGeometry& a, const GridGeometry& b) {
  if (a.dimension != b.dimension || a.size != b.size || a.rectilinear() != b.rectilinear())
    return false;
  const auto close = [](double x, double y) {
    return std::abs(x - y) <= 1e-9 * std::max({1.0, std::abs(x), std::abs(y)});
  };
  for (int i = 0; i < 3; ++i) {
    if (a.rectilinear()) {
      const auto& ax = a.axes[static_cast<std::size_t>(i)];
      const auto& bx = b.axes[static_cast<std::size_t>(i)];
      if (ax.size() != bx.size()) return false;
      for (std::size_t k = 0; k < ax.size(); ++k) {
        if (!close(ax[k], bx[k])) return false;
      }
    } else if (!close(a.origin[i], b.origin[i]) || !close(a.spacing[i], b.spacing[i])) {
      return false;
    }
  }
  return true;
}

}  // namespace

MemorySeries::MemorySeries(GridGeometry geometry, int components,
                           std::vector<std::vector<float>> steps, std::vector<double> times,
                           std::string description, bool zero_is_no_data)
    : geometry_(std::move(geometry)),
      components_(components),
      steps_(std::move(steps)),
      times_(std::move(times)),
      description_(std::move(description)),
      zero_is_no_data_(zero_is_no_data) {
  if (steps_.empty()) throw InvalidArgument(description_ + ": a time series needs a step");
  if (times_.size() != steps_.size())
    throw InvalidArgument(description_ + ": " + std::to_string(steps_.size()) + " steps but " +
                          std::to_string(times_.size()) + " times");
  const std::size_t floats = geometry_.point_count() * static_cast<std::size_t>(components_);
  for (std::size_t i = 0; i < steps_.size(); ++i) {
    if (steps_[i].size() != floats)
      throw InvalidArgument(description_ + ": step " + std::to_string(i) + " holds " +
                            std::to_string(steps_[i].size()) + " values, the grid needs " +
                            std::to_string(floats));
    if (!std::isfinite(times_[i]) || (i > 0 && !(times_[i] > times_[i - 1])))
      throw InvalidArgument(description_ + ": times must be finite and strictly increasing (step " +
                            std::to_string(i) + ")");
  }
}

GridFileSeries::GridFileSeries(std::vector<std::filesystem::path> files, std::vector<double> times,
                               std::string selector)
    : files_(std::move(files)), times_(std::move(times)), selector_(std::move(selector)) {
  if (files_.empty()) throw InvalidArgument("a time series needs at least one file");
  if (times_.size() != files_.size()) {
    throw InvalidArgument(std::to_string(files_.size()) + " files but " +
                          std::to_string(times_.size()) + " times");
  }
  for (std::size_t i = 0; i < times_.size(); ++i) {
    if (!std::isfinite(times_[i]) || (i > 0 && !(times_[i] > times_[i - 1]))) {
      throw InvalidArgument("times must be finite and strictly increasing (step " +
                            std::to_string(i) + ", " + files_[i].string() + ")");
    }
  }
  for (const auto& file : files_) {
    if (grid_format_of(file) == GridFormat::kUnknown) {
      throw InvalidArgument(file.string() + ": unknown grid file extension (expected " +
                            grid_extensions_text() + ")");
    }
  }
  const VectorGrid first = read_vector_grid(files_.front(), selector_);
  geometry_ = first.geometry;
  components_ = first.components;
}

std::string GridFileSeries::describe() const {
  std::ostringstream out;
  out << files_.size() << " " << grid_format_name(grid_format_of(files_.front())) << " file"
      << (files_.size() == 1 ? "" : "s") << " (" << files_.front().filename().string();
  if (files_.size() > 1) out << " .. " << files_.back().filename().string();
  out << "), " << detail::size_text(geometry_) << " x " << components_;
  return out.str();
}

RawStep GridFileSeries::read_raw(std::size_t step) const {
  if (step >= files_.size()) {
    throw InvalidArgument("step " + std::to_string(step) + " out of range (the series has " +
                          std::to_string(files_.size()) + ")");
  }
  const std::string content = detail::read_file_bytes(files_[step]);
  RawStep raw;
  raw.step = step;
  raw.encoded = true;
  raw.bytes.resize(content.size());
  std::memcpy(raw.bytes.data(), content.data(), content.size());
  return raw;
}

void GridFileSeries::decode(const RawStep& raw, std::span<float> values) const {
  const std::filesystem::path& file = files_.at(raw.step);
  const std::string_view content(reinterpret_cast<const char*>(raw.bytes.data()), raw.bytes.size());
  const VectorGrid grid = parse_vector_grid(content, file, selector_);
  if (!same_geometry(grid.geometry, geometry_) || grid.components != components_) {
    throw FormatError(file.string() + " (step " + std::to_string(raw.step) + "): grid " +
                      describe_grid(grid) + " differs from the first step's " +
                      detail::size_text(geometry_) + " x " + std::to_string(components_) + " (" +
                      files_.front().string() + ")");
  }
  if (values.size() != grid.values.size()) {
    throw InvalidArgument("decode: buffer of " + std::to_string(values.size()) +
                          " floats for a step of " + std::to_string(grid.values.size()));
  }
  std::memcpy(values.data(), grid.values.data(), grid.values.size() * sizeof(float));
}

std::unique_ptr<GridFileSeries> open_pvd(const std::filesystem::path& path,
                                         const std::string& selector) {
  const std::string content = detail::read_file_bytes(path);
  const std::string file = path.string();
  detail::XmlScanner xml(content, file);
  detail::XmlTag tag;
  bool root = false;
  std::vector<std::pair<double, std::filesystem::path>> entries;
  while (xml.next(tag)) {
    if (tag.end) continue;
    if (tag.name == "VTKFile") {
      const std::string* type = tag.attribute("type");
      if (type == nullptr || *type != "Collection") {
        throw FormatError(file + ": VTK file type is '" + (type ? *type : std::string()) +
                          "', expected Collection");
      }
      root = true;
    } else if (tag.name == "DataSet") {
      if (!root) throw FormatError(file + ": <DataSet> outside <VTKFile type=\"Collection\">");
      const std::string* name = tag.attribute("file");
      if (name == nullptr || name->empty())
        throw FormatError(file + ": <DataSet> entry " + std::to_string(entries.size()) +
                          " has no file");
      double t = static_cast<double>(entries.size());
      if (const std::string* ts = tag.attribute("timestep")) {
        if (!detail::parse_number(*ts, t) || !std::isfinite(t))
          throw FormatError(file + ": bad timestep '" + *ts + "' of " + *name);
      }
      if (const std::string* part = tag.attribute("part")) {
        if (*part != "0")
          throw FormatError(file + ": " + *name + " is part " + *part +
                            " of a time step; multi-part collections are not supported");
      }
      std::filesystem::path data = *name;
      if (data.is_relative()) data = path.parent_path() / data;
      note_input(data);
      entries.emplace_back(t, data);
    }
  }
  if (!root)
    throw FormatError(file + ": not a ParaView collection (no <VTKFile type=\"Collection\">)");
  if (entries.empty()) throw FormatError(file + ": the collection lists no <DataSet>");
  std::stable_sort(entries.begin(), entries.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<std::filesystem::path> files;
  std::vector<double> times;
  for (std::size_t i = 0; i < entries.size(); ++i) {
    if (i > 0 && entries[i].first == entries[i - 1].first) {
      throw FormatError(file + ": timestep " + std::to_string(entries[i].first) +
                        " is listed twice (" + entries[i - 1].second.string() + ", " +
                        entries[i].second.string() + ")");
    }
    times.push_back(entries[i].first);
    files.push_back(entries[i].second);
  }
  return std::make_unique<GridFileSeries>(std::move(files), std::move(times), selector);
}

std::vector<double> evenly_spaced_times(std::size_t count, double t0, double dt) {
  std::vector<double> times(count);
  for (std::size_t i = 0; i < count; ++i) times[i] = t0 + static_cast<double>(i) * dt;
  return times;
}

bool natural_less(const std::string& a, const std::string& b) {
  std::size_t i = 0;
  std::size_t j = 0;
  while (i < a.size() && j < b.size()) {
    if (std::isdigit(static_cast<unsigned char>(a[i])) &&
        std::isdigit(static_cast<unsigned char>(b[j]))) {
      std::size_t ie = i;
      std::size_t je = j;
      while (ie < a.size() && std::isdigit(static_cast<unsigned char>(a[ie]))) ++ie;
      while (je < b.size() && std::isdigit(static_cast<unsigned char>(b[je]))) ++je;
      std::string x = a.substr(i, ie - i);
      std::string y = b.substr(j, je - j);
      x.erase(0, std::min(x.find_first_not_of('0'), x.size()));
      y.erase(0, std::min(y.find_first_not_of('0'), y.size()));
      if (x.size() != y.size()) return x.size() < y.size();
      if (x != y) return x < y;
      i = ie;
      j = je;
    } else {
      if (a[i] != b[j]) return a[i] < b[j];
      ++i;
      ++j;
    }
  }
  return a.size() - i < b.size() - j;
}

bool is_netcdf_path(const std::filesystem::path& path) {
  std::string e = path.extension().string();
  std::transform(e.begin(), e.end(), e.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return e == ".nc" || e == ".nc4" || e == ".cdf" || e == ".netcdf";
}

std::vector<std::filesystem::path> expand_file_pattern(const std::string& pattern) {
  std::vector<std::filesystem::path> files;
  std::size_t begin = 0;
  for (;;) {
    const std::size_t end = pattern.find(',', begin);
    std::string item = pattern.substr(begin, end - begin);
    item.erase(0, item.find_first_not_of(" \t"));
    item.erase(item.find_last_not_of(" \t") + 1);
    if (item.find_first_of("*?[") == std::string::npos) {
      files.emplace_back(item);
    } else {
      glob_t g{};
      const int status = ::glob(item.c_str(), 0, nullptr, &g);
      std::vector<std::string> found;
      if (status == 0)
        for (std::size_t i = 0; i < g.gl_pathc; ++i) found.emplace_back(g.gl_pathv[i]);
      ::globfree(&g);
      if (found.empty()) throw InvalidArgument("'" + item + "' matches no file");
      std::sort(found.begin(), found.end(), natural_less);
      files.insert(files.end(), found.begin(), found.end());
    }
    if (end == std::string::npos) break;
    begin = end + 1;
  }
  for (const auto& f : files) note_input(f);
  return files;
}

}  // namespace orthofront::io
