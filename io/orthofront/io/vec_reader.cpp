#include "orthofront/io/vec_reader.h"

#include <cstdint>

#include "orthofront/io/error.h"
#include "orthofront/io/grid_decode.h"

namespace orthofront::io {

VectorGrid parse_vec(std::string_view content, const std::string& file,
                     const VecPlacement& placement) {
  constexpr std::size_t kHeader = 3 * sizeof(std::int32_t);
  if (content.size() < kHeader) {
    throw FormatError(file + ": truncated: " + std::to_string(content.size()) +
                      " bytes, shorter than the 12-byte .vec header (nx, ny, nz)");
  }
  const auto* bytes = reinterpret_cast<const unsigned char*>(content.data());
  VectorGrid grid;
  GridGeometry& g = grid.geometry;
  for (std::size_t a = 0; a < 3; ++a)
    g.size[a] = detail::load<std::int32_t>(bytes + 4 * a, true);
  const std::size_t points = detail::checked_point_count(g.size, 3, file, ".vec header size");
  const std::size_t expected = kHeader + points * 3 * sizeof(float);
  if (content.size() != expected) {
    throw FormatError(file + ": " + (content.size() < expected ? "truncated: " : "") +
                      "header says " + detail::size_text(g) + " x 3 float32 (" +
                      std::to_string(expected) + " bytes with the header) but the file has " +
                      std::to_string(content.size()) + " bytes");
  }
  g.dimension = 3;
  g.origin = placement.origin;
  g.spacing = placement.spacing;
  grid.components = 3;
  grid.values.resize(points * 3);
  detail::scalars_to_floats(detail::ScalarType::kFloat32, bytes + kHeader, grid.values.size(),
                            true, grid.values.data());
  detail::validate_grid(grid, file);
  return grid;
}

VectorGrid read_vec(const std::filesystem::path& path, const VecPlacement& placement) {
  return parse_vec(detail::read_file_bytes(path), path.string(), placement);
}

}  // namespace orthofront::io
