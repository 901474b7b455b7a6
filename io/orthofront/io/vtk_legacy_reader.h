#pragma once
/// Legacy VTK files (.vtk), ASCII or BINARY (big-endian, as the format prescribes): DATASET
/// STRUCTURED_POINTS (DIMENSIONS, ORIGIN, SPACING or ASPECT_RATIO) or RECTILINEAR_GRID
/// (X/Y/Z_COORDINATES), with a VECTORS array in POINT_DATA (other arrays, FIELD data, CELL_DATA
/// and METADATA blocks are skipped).
#include <filesystem>
#include <string>
#include <string_view>

#include "orthofront/field/grid.h"

namespace orthofront::io {

/// Reads the POINT_DATA vectors named `array` (VECTORS, 2/3-component SCALARS or FIELD arrays),
/// or when empty the first VECTORS. Throws IoError or FormatError naming the file and the bad
/// value (unsupported dataset or type, bad dimensions, non-vector data, truncated data).
VectorGrid read_vtk_legacy(const std::filesystem::path& path, const std::string& array = {});

/// Parses the content of a legacy .vtk file; `file` names it in messages.
VectorGrid parse_vtk_legacy(std::string_view content, const std::string& file,
                            const std::string& array = {});

}  // namespace orthofront::io
