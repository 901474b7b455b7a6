#pragma once
/// NRRD (.nrrd with attached data, .nhdr with a detached data file), versions NRRD0001..0005:
/// one axis holds the vector components (2 or 3; kind vector/2-vector/3-vector/..., or a "none"
/// space direction, or a NaN spacing; the first axis when nothing says otherwise), the others
/// are 2 or 3 spatial axes. Geometry from `space directions` (axis-aligned) or `spacings`, and
/// `space origin` or `axis mins` (with `centers`). Types int8..uint64, float, double; encodings
/// raw, gzip (zlib), bzip2 (libbz2), hex and ascii; `endian`; `byte skip` (-1 with raw),
/// `line skip`.
#include <filesystem>
#include <string>
#include <string_view>

#include "orthofront/field/grid.h"

namespace orthofront::io {

/// Reads a vector field from a NRRD file. Throws IoError or FormatError naming the file and the
/// bad value (missing or bad fields, non-vector data, unsupported encoding, truncated data).
VectorGrid read_nrrd(const std::filesystem::path& path);

/// Parses the content of a NRRD file. `file` names it in messages and locates detached data files
/// (relative to its directory).
VectorGrid parse_nrrd(std::string_view content, const std::filesystem::path& file);

}  // namespace orthofront::io
