#pragma once
/// OSUFlow .vec files (the tornado data): three little-endian int32 nx, ny, nz, then
/// nx*ny*nz*3 little-endian float32, x fastest, (u, v, w) interleaved. The format stores no
/// geometry: the samples lie at `origin + (i, j, k) * spacing`, unit spacing at 0 by default.
#include <filesystem>
#include <string>
#include <string_view>

#include "orthofront/field/grid.h"

namespace orthofront::io {

/// Where the samples of a .vec file lie.
struct VecPlacement {
  Vec3 origin = Vec3::Zero();
  Vec3 spacing = Vec3::Ones();
};

/// Reads a .vec file. Throws IoError (unreadable) or FormatError naming the file and the bad value
/// (non-positive sizes, a file length that does not match the sizes in its header).
VectorGrid read_vec(const std::filesystem::path& path, const VecPlacement& placement = {});

/// Parses the content of a .vec file; `file` names it in messages.
VectorGrid parse_vec(std::string_view content, const std::string& file,
                     const VecPlacement& placement = {});

}  // namespace orthofront::io
