#pragma once
/// VTK XML PolyData (.vtp) mesh codec (internal to mesh_io): writes inline base64 binary arrays;
/// reads inline ascii and binary arrays (uncompressed or zlib) with a small XML scan.
#include <ostream>
#include <string>
#include <string_view>

#include "orthofront/mesh/mesh.h"

namespace orthofront::io::detail {

/// Writes points (Float64), polygons (Int64 connectivity and offsets) and the recorded attributes
/// as point data (Float64 time, alpha, s, error; Int32 front_id, step).
void write_vtp(const Mesh& mesh, std::ostream& out);

/// Parses the whole content of a .vtp file: every Piece's points, polygons and triangle strips,
/// and point data arrays named like Mesh attributes. `file` names the file in FormatError
/// messages. Appended data is rejected with a FormatError.
Mesh read_vtp(std::string_view data, const std::string& file);

}  // namespace orthofront::io::detail
