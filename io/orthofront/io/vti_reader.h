#pragma once
/// VTK XML ImageData (.vti): point-data vector arrays stored as ascii, inline base64 binary, or
/// appended (raw or base64) data, uncompressed or zlib-compressed (vtkZLibDataCompressor, as
/// ParaView writes them), UInt32 or UInt64 headers, either byte order, one or several pieces.
/// The grid point (i, j, k) of WholeExtent "x0 x1 y0 y1 z0 z1" lies at
/// Origin + (x0 + i, y0 + j, z0 + k) * Spacing; a Direction other than identity is rejected.
#include <filesystem>
#include <string>
#include <string_view>

#include "orthofront/field/grid.h"

namespace orthofront::io {

/// Reads the point-data array named `array`, or when empty: the array the PointData element names
/// as its Vectors, else the first with 3 components, else the first with 2. Throws IoError or
/// FormatError naming the file and the bad value.
VectorGrid read_vti(const std::filesystem::path& path, const std::string& array = {});

/// Parses the content of a .vti file; `file` names it in messages.
VectorGrid parse_vti(std::string_view content, const std::string& file,
                     const std::string& array = {});

}  // namespace orthofront::io
