#pragma once
/// AmiraMesh / Avizo lattice files (.am): `BINARY` (big-endian, version 2.0),
/// `BINARY-LITTLE-ENDIAN` (2.1) and `ASCII`, read from the header (never assumed). Understood:
/// `define Lattice nx ny [nz]`, data declarations `Lattice { float[3] Data } @1` (raw, or
/// `(HxZip,n)` zlib-compressed), `BoundingBox xmin xmax ymin ymax zmin zmax`, `CoordType`
/// "uniform" (point (i,j,k) = bbmin + (i,j,k) * (bbmax - bbmin) / (n - 1)) and "rectilinear"
/// (a `Coordinates { float xyz }` section of nx + ny + nz values).
#include <filesystem>
#include <string>
#include <string_view>

#include "orthofront/field/grid.h"

namespace orthofront::io {

/// Reads the vector field of an AmiraMesh file: the data declaration named `field` (e.g. "Data"),
/// or, when `field` is empty, the first lattice declaration with 2 or 3 components. Throws
/// IoError or FormatError naming the file and the bad value: not AmiraMesh, an unsupported
/// encoding or coordinate type, bad or missing sizes, no vector data, truncated data.
VectorGrid read_amira(const std::filesystem::path& path, const std::string& field = {});

/// Parses the content of an AmiraMesh file; `file` names it in messages.
VectorGrid parse_amira(std::string_view content, const std::string& file,
                       const std::string& field = {});

}  // namespace orthofront::io
