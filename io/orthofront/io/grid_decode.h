#pragma once
/// Helpers shared by the vector-grid readers (internal): whole-file reads, grid-size checks and
/// the conversion of stored scalars to float.
#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

#include "orthofront/field/grid.h"
#include "orthofront/io/scalar_codec.h"

namespace orthofront::io::detail {

/// The whole content of a file. Throws IoError naming it.
std::string read_file_bytes(const std::filesystem::path& path);

/// Checks that every size is at least 1 and that the grid's float count fits in memory
/// arithmetic; throws FormatError "<file>: <what> ..." otherwise. Returns the point count.
std::size_t checked_point_count(const std::array<std::int64_t, 3>& size, int components,
                                const std::string& file, const std::string& what);

/// Converts `count` stored scalars of `type` (byte order `little_endian`) to floats.
void scalars_to_floats(ScalarType type, const unsigned char* bytes, std::size_t count,
                       bool little_endian, float* out);

/// "48 x 48 x 48" (2D: "192 x 64").
std::string size_text(const GridGeometry& geometry);

/// Throws FormatError unless the grid holds 2 or 3 components of finite geometry, positive
/// spacing and increasing rectilinear axes, and values.size() matches (a reader's last check).
void validate_grid(const VectorGrid& grid, const std::string& file);

}  // namespace orthofront::io::detail
