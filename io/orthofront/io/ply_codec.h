#pragma once
/// PLY mesh codec (internal to mesh_io): binary little-endian writer; reader for ascii and binary
/// files of either byte order with any scalar property types.
#include <ostream>
#include <string>
#include <string_view>

#include "orthofront/mesh/mesh.h"

namespace orthofront::io::detail {

/// Writes vertices (x y z and the recorded attributes) and polygon faces.
void write_ply(const Mesh& mesh, std::ostream& out);

/// Parses the whole content of a PLY file; `file` names it in FormatError messages.
Mesh read_ply(std::string_view data, const std::string& file);

}  // namespace orthofront::io::detail
