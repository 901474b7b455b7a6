#pragma once
/// Mesh writers and readers chosen by file extension: .ply (binary little-endian, polygon faces,
/// all attributes as vertex properties), .obj (positions and faces), .vtp (VTK XML PolyData, all
/// attributes as point data, readable by ParaView).
#include <filesystem>

#include "orthofront/mesh/mesh.h"

namespace orthofront::io {

/// Writes `mesh` to `path` atomically; the format follows the extension (.ply, .obj, .vtp).
/// Throws IoError / InvalidArgument (unknown extension) naming the path.
void write_mesh(const Mesh& mesh, const std::filesystem::path& path);

/// Reads a mesh written by write_mesh (and ordinary files of these formats). Attributes that a
/// format does not carry are left empty. Throws IoError / FormatError naming file and value.
Mesh read_mesh(const std::filesystem::path& path);

/// True when the extension is one write_mesh understands.
bool is_mesh_extension(const std::filesystem::path& path);

}  // namespace orthofront::io
