#include "orthofront/io/mesh_io.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <fstream>
#include <string>
#include <system_error>

#include "orthofront/error.h"
#include "orthofront/io/atomic_file.h"
#include "orthofront/io/error.h"
#include "orthofront/io/mesh_attributes.h"
#include "orthofront/io/obj_codec.h"
#include "orthofront/io/ply_codec.h"
#include "orthofront/io/vtp_codec.h"

namespace orthofront::io {
namespace {

enum class MeshFormat { kUnknown, kPly, kObj, kVtp };

MeshFormat format_of(const std::filesystem::path& path) {
  std::string extension = path.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (extension == ".ply") return MeshFormat::kPly;
  if (extension == ".obj") return MeshFormat::kObj;
  if (extension == ".vtp") return MeshFormat::kVtp;
  return MeshFormat::kUnknown;
}

[[noreturn]] void unknown_extension(const std::filesystem::path& path) {
  throw InvalidArgument(path.string() + ": unknown mesh file extension '" +
                        path.extension().string() + "' (expected .ply, .obj or .vtp)");
}

/// A mesh whose arrays disagree would be written as a file that is wrong or unreadable.
void check_consistent(const Mesh& mesh, const std::filesystem::path& path) {
  const std::size_t n = mesh.positions.size();
  const auto check_size = [&](const char* name, std::size_t size) {
    if (size != 0 && size != n) {
      throw InvalidArgument("cannot write " + path.string() + ": attribute " + name + " has " +
                            std::to_string(size) + " values for " + std::to_string(n) +
                            " vertices");
    }
  };
  for (const detail::RealAttribute& attribute : detail::kRealAttributes) {
    check_size(attribute.name, (mesh.*attribute.values).size());
  }
  for (const detail::IntAttribute& attribute : detail::kIntAttributes) {
    check_size(attribute.name, (mesh.*attribute.values).size());
  }
  for (std::size_t i = 0; i < mesh.faces.size(); ++i) {
    const Face& face = mesh.faces[i];
    if (face.size != 3 && face.size != 4) {
      throw InvalidArgument("cannot write " + path.string() + ": face " + std::to_string(i) +
                            " has size " + std::to_string(face.size) + " (3 or 4 expected)");
    }
    for (int k = 0; k < face.size; ++k) {
      if (face.v[k] < 0 || static_cast<std::size_t>(face.v[k]) >= n) {
        throw InvalidArgument("cannot write " + path.string() + ": face " + std::to_string(i) +
                              " refers to vertex " + std::to_string(face.v[k]) + " but there are " +
                              std::to_string(n) + " vertices");
      }
    }
  }
}

std::string read_file(const std::filesystem::path& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    throw IoError("cannot read " + path.string() + ": it is a directory");
  }
  errno = 0;
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    throw IoError("cannot read " + path.string() + ": " +
                  std::generic_category().message(errno != 0 ? errno : EIO));
  }
  std::string data;
  if (const auto size = std::filesystem::file_size(path, ec); !ec) data.reserve(size);
  char chunk[1 << 16];
  while (in.read(chunk, sizeof(chunk)) || in.gcount() > 0) {
    data.append(chunk, static_cast<std::size_t>(in.gcount()));
  }
  if (in.bad()) {
    throw IoError("cannot read " + path.string() + ": " +
                  std::generic_category().message(errno != 0 ? errno : EIO));
  }
  return data;
}

}  // namespace

bool is_mesh_extension(const std::filesystem::path& path) {
  return format_of(path) != MeshFormat::kUnknown;
}

void write_mesh(const Mesh& mesh, const std::filesystem::path& path, AtomicFileSet& files) {
  const MeshFormat format = format_of(path);
  if (format == MeshFormat::kUnknown) unknown_extension(path);
  check_consistent(mesh, path);
  check_writable(path);
  files.add(path, [&](std::ofstream& out) {
    switch (format) {
      case MeshFormat::kPly:
        detail::write_ply(mesh, out);
        break;
      case MeshFormat::kObj:
        detail::write_obj(mesh, out);
        break;
      case MeshFormat::kVtp:
        detail::write_vtp(mesh, out);
        break;
      case MeshFormat::kUnknown:
        break;
    }
  });
}

void write_mesh(const Mesh& mesh, const std::filesystem::path& path) {
  AtomicFileSet files;
  write_mesh(mesh, path, files);
  files.commit();
}

Mesh read_mesh(const std::filesystem::path& path) {
  const MeshFormat format = format_of(path);
  if (format == MeshFormat::kUnknown) unknown_extension(path);
  const std::string data = read_file(path);
  switch (format) {
    case MeshFormat::kPly:
      return detail::read_ply(data, path.string());
    case MeshFormat::kObj:
      return detail::read_obj(data, path.string());
    case MeshFormat::kVtp:
      return detail::read_vtp(data, path.string());
    case MeshFormat::kUnknown:
      break;
  }
  unknown_extension(path);
}

}  // namespace orthofront::io
