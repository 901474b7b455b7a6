#pragma once
/// Wavefront OBJ mesh codec (internal to mesh_io): positions and polygon faces only.
#include <ostream>
#include <string>
#include <string_view>

#include "orthofront/mesh/mesh.h"

namespace orthofront::io::detail {

/// Writes "v x y z" lines (shortest text that reads back exactly) and 1-based "f" lines.
void write_obj(const Mesh& mesh, std::ostream& out);

/// Parses v and f lines (f entries like 7, 7/1, 7//2, 7/1/2, negative = relative); ignores the
/// rest. `file` names the file in FormatError messages.
Mesh read_obj(std::string_view data, const std::string& file);

}  // namespace orthofront::io::detail
