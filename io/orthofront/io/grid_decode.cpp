#include "orthofront/io/grid_decode.h"

#include <bit>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <system_error>

#include "orthofront/io/error.h"
#include "orthofront/io/input_files.h"
#include "orthofront/io/readable_file.h"

namespace orthofront::io::detail {

std::string read_file_bytes(const std::filesystem::path& path) {
  // A device or pipe (/dev/zero, a FIFO) has no end: reading it would allocate without bound.
  if (const std::string why = why_unreadable(path); !why.empty())
    throw IoError("cannot read " + path.string() + ": " + why);
  note_input(path);
  errno = 0;
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    throw IoError("cannot read " + path.string() + ": " +
                  std::generic_category().message(errno != 0 ? errno : EIO));
  }
  std::string data;
  std::error_code ec;
  if (const auto size = std::filesystem::file_size(path, ec); !ec) {
    data.resize(static_cast<std::size_t>(size));
    in.read(data.data(), static_cast<std::streamsize>(size));
    data.resize(static_cast<std::size_t>(in.gcount()));
  }
  char chunk[1 << 16];  // the rest, if the file grew or its size was unknown
  while (in.read(chunk, sizeof(chunk)) || in.gcount() > 0)
    data.append(chunk, static_cast<std::size_t>(in.gcount()));
  if (in.bad()) {
    throw IoError("cannot read " + path.string() + ": " +
                  std::generic_category().message(errno != 0 ? errno : EIO));
  }
  return data;
}

std::size_t checked_point_count(const std::array<std::int64_t, 3>& size, int components,
                                const std::string& file, const std::string& what) {
  // At most 2^40 floats: far beyond any real grid, far below overflow of byte counts.
  constexpr double kLimit = 1099511627776.0;
  double total = components;
  for (const std::int64_t n : size) {
    if (n < 1) {
      throw FormatError(file + ": " + what + " " + std::to_string(size[0]) + " x " +
                        std::to_string(size[1]) + " x " + std::to_string(size[2]) +
                        " has a size below 1");
    }
    total *= static_cast<double>(n);
  }
  if (total > kLimit) {
    throw FormatError(file + ": " + what + " " + std::to_string(size[0]) + " x " +
                      std::to_string(size[1]) + " x " + std::to_string(size[2]) +
                      " is implausibly large");
  }
  return static_cast<std::size_t>(size[0] * size[1] * size[2]);
}

void scalars_to_floats(ScalarType type, const unsigned char* bytes, std::size_t count,
                       bool little_endian, float* out) {
  if (type == ScalarType::kFloat32 &&
      little_endian == (std::endian::native == std::endian::little)) {
    std::memcpy(out, bytes, count * sizeof(float));
    return;
  }
  const std::size_t step = scalar_size(type);
  if (type == ScalarType::kFloat32) {
    for (std::size_t i = 0; i < count; ++i) out[i] = load<float>(bytes + i * step, little_endian);
    return;
  }
  for (std::size_t i = 0; i < count; ++i)
    out[i] = static_cast<float>(load_real(type, bytes + i * step, little_endian));
}

std::string size_text(const GridGeometry& geometry) {
  std::string text = std::to_string(geometry.size[0]) + " x " + std::to_string(geometry.size[1]);
  if (geometry.dimension == 3) text += " x " + std::to_string(geometry.size[2]);
  return text;
}

void validate_grid(const VectorGrid& grid, const std::string& file) {
  const GridGeometry& g = grid.geometry;
  if (g.dimension != 2 && g.dimension != 3)
    throw FormatError(file + ": dimension " + std::to_string(g.dimension) + " (need 2 or 3)");
  if (grid.components != 2 && grid.components != 3) {
    throw FormatError(file + ": " + std::to_string(grid.components) +
                      " components per point: not a 2- or 3-vector field");
  }
  if (g.dimension == 2 && g.size[2] != 1)
    throw FormatError(file + ": a 2D grid must have one sample along z");
  for (int a = 0; a < 3; ++a) {
    const auto n = static_cast<std::size_t>(g.size[static_cast<std::size_t>(a)]);
    if (g.rectilinear()) {
      const auto& axis = g.axes[static_cast<std::size_t>(a)];
      if (axis.size() != n) {
        throw FormatError(file + ": axis " + std::to_string(a) + " has " +
                          std::to_string(axis.size()) + " coordinates for " + std::to_string(n) +
                          " samples");
      }
      for (std::size_t i = 0; i < axis.size(); ++i) {
        if (!std::isfinite(axis[i]) || (i > 0 && !(axis[i] > axis[i - 1]))) {
          throw FormatError(file + ": coordinates of axis " + std::to_string(a) +
                            " are not finite and strictly increasing (at index " +
                            std::to_string(i) + ")");
        }
      }
    } else {
      if (!std::isfinite(g.origin[a]))
        throw FormatError(file + ": origin is not finite on axis " + std::to_string(a));
      if (!(g.spacing[a] > 0.0) || !std::isfinite(g.spacing[a])) {
        throw FormatError(file + ": spacing " + std::to_string(g.spacing[a]) + " on axis " +
                          std::to_string(a) + " is not positive");
      }
    }
  }
  if (grid.values.size() != g.point_count() * static_cast<std::size_t>(grid.components)) {
    throw FormatError(file + ": holds " + std::to_string(grid.values.size()) + " values for " +
                      size_text(g) + " points of " + std::to_string(grid.components) +
                      " components");
  }
}

}  // namespace orthofront::io::detail
