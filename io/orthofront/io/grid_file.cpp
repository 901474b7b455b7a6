#include "orthofront/io/grid_file.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <sstream>

#include "orthofront/error.h"
#include "orthofront/io/amira_reader.h"
#include "orthofront/io/error.h"
#include "orthofront/io/grid_decode.h"
#include "orthofront/io/nrrd_reader.h"
#include "orthofront/io/vdb_grid.h"
#include "orthofront/io/vec_reader.h"
#include "orthofront/io/vti_reader.h"
#include "orthofront/io/vtk_legacy_reader.h"

namespace orthofront::io {

GridFormat grid_format_of(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext == ".vec") return GridFormat::kVec;
  if (ext == ".am") return GridFormat::kAmira;
  if (ext == ".nrrd" || ext == ".nhdr") return GridFormat::kNrrd;
  if (ext == ".vti") return GridFormat::kVti;
  if (ext == ".vtk") return GridFormat::kVtkLegacy;
  if (ext == ".vdb") return GridFormat::kVdb;
  return GridFormat::kUnknown;
}

const char* grid_format_name(GridFormat format) {
  switch (format) {
    case GridFormat::kVec:
      return "OSUFlow .vec";
    case GridFormat::kAmira:
      return "AmiraMesh";
    case GridFormat::kNrrd:
      return "NRRD";
    case GridFormat::kVti:
      return "VTK XML ImageData";
    case GridFormat::kVtkLegacy:
      return "legacy VTK";
    case GridFormat::kVdb:
      return "OpenVDB";
    case GridFormat::kUnknown:
      break;
  }
  return "unknown";
}

std::string grid_extensions_text() { return ".vec, .am, .nrrd, .nhdr, .vti, .vtk, .vdb"; }

std::optional<GridSource> parse_grid_source(const std::string& spec) {
  if (grid_format_of(spec) != GridFormat::kUnknown) return GridSource{spec, {}};
  const std::size_t colon = spec.rfind(':');
  if (colon == std::string::npos || colon == 0) return std::nullopt;
  const std::string path = spec.substr(0, colon);
  if (grid_format_of(path) == GridFormat::kUnknown) return std::nullopt;
  return GridSource{path, spec.substr(colon + 1)};
}

namespace {

void no_selector(GridFormat format, const std::string& selector, const std::filesystem::path& path) {
  if (!selector.empty()) {
    throw InvalidArgument(path.string() + ": a " + grid_format_name(format) +
                          " file holds one field; ':" + selector + "' selects nothing");
  }
}

}  // namespace

VectorGrid parse_vector_grid(std::string_view content, const std::filesystem::path& path,
                             const std::string& selector) {
  const GridFormat format = grid_format_of(path);
  const std::string file = path.string();
  switch (format) {
    case GridFormat::kVec:
      no_selector(format, selector, path);
      return parse_vec(content, file);
    case GridFormat::kAmira:
      return parse_amira(content, file, selector);
    case GridFormat::kNrrd:
      no_selector(format, selector, path);
      return parse_nrrd(content, path);
    case GridFormat::kVti:
      return parse_vti(content, file, selector);
    case GridFormat::kVtkLegacy:
      return parse_vtk_legacy(content, file, selector);
    case GridFormat::kVdb:
      return parse_vdb_grid(content, file, selector);
    case GridFormat::kUnknown:
      break;
  }
  throw InvalidArgument(file + ": unknown grid file extension (expected " +
                        grid_extensions_text() + ")");
}

VectorGrid read_vector_grid(const std::filesystem::path& path, const std::string& selector) {
  if (grid_format_of(path) == GridFormat::kUnknown) {
    throw InvalidArgument(path.string() + ": unknown grid file extension (expected " +
                          grid_extensions_text() + ")");
  }
  if (grid_format_of(path) == GridFormat::kVdb) return read_vdb_grid(path, selector);
  return parse_vector_grid(detail::read_file_bytes(path), path, selector);
}

std::string describe_grid(const VectorGrid& grid) {
  const GridGeometry& g = grid.geometry;
  std::ostringstream out;
  out << detail::size_text(g) << " x " << grid.components << " float32";
  if (g.rectilinear()) {
    out << ", rectilinear";
  } else {
    out << ", origin (" << g.origin[0] << ", " << g.origin[1];
    if (g.dimension == 3) out << ", " << g.origin[2];
    out << "), spacing (" << g.spacing[0] << ", " << g.spacing[1];
    if (g.dimension == 3) out << ", " << g.spacing[2];
    out << ")";
  }
  return out.str();
}

}  // namespace orthofront::io
