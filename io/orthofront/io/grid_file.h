#pragma once
/// Vector-grid files of every supported format, chosen by extension: .vec (OSUFlow), .am
/// (AmiraMesh), .nrrd/.nhdr (NRRD), .vti (VTK XML ImageData), .vtk (legacy VTK), .vdb (OpenVDB).
/// A file may be followed by ":NAME" to pick an array (VTK), a data field (Amira) or a grid
/// (OpenVDB): "flow.vdb:velocity".
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

#include "orthofront/field/grid.h"

namespace orthofront::io {

enum class GridFormat { kUnknown, kVec, kAmira, kNrrd, kVti, kVtkLegacy, kVdb };

/// The format of a file by its extension (case-insensitive); kUnknown for anything else.
GridFormat grid_format_of(const std::filesystem::path& path);

/// "OSUFlow .vec", "AmiraMesh", "NRRD", "VTK XML ImageData", "legacy VTK", "OpenVDB".
const char* grid_format_name(GridFormat format);

/// The extensions grid_format_of knows, for messages: ".vec, .am, .nrrd, .nhdr, .vti, .vtk, .vdb".
std::string grid_extensions_text();

/// A grid file and the name of what to read from it (empty: the reader's default choice).
struct GridSource {
  std::filesystem::path path;
  std::string selector;
};

/// Splits "FILE.ext" or "FILE.ext:NAME" when ext is a grid extension; nullopt otherwise.
std::optional<GridSource> parse_grid_source(const std::string& spec);

/// Reads the vector grid of a file (the format by extension). Throws InvalidArgument for an
/// unknown extension, IoError / FormatError naming the file and the bad value otherwise.
VectorGrid read_vector_grid(const std::filesystem::path& path, const std::string& selector = {});

/// The same from content already in memory (`path` gives the format, the name in messages and the
/// folder of detached data files).
VectorGrid parse_vector_grid(std::string_view content, const std::filesystem::path& path,
                             const std::string& selector = {});

/// A short description: "48 x 48 x 48 x 3 float32, origin (0, 0, 0), spacing (1, 1, 1)".
std::string describe_grid(const VectorGrid& grid);

}  // namespace orthofront::io
