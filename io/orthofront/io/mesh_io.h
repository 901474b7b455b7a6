#pragma once
/// Mesh writers and readers chosen by file extension: .ply (binary little-endian, polygon faces,
/// all attributes as vertex properties), .obj (positions and faces), .vtp (VTK XML PolyData, all
/// attributes as point data, readable by ParaView).
#include <filesystem>

#include "orthofront/mesh/mesh.h"

namespace orthofront::io {

class AtomicFileSet;

/// Writes `mesh` to `path` atomically; the format follows the extension (.ply, .obj, .vtp).
/// Throws IoError / InvalidArgument (unknown extension) naming the path.
void write_mesh(const Mesh& mesh, const std::filesystem::path& path);

/// As above, but into `files`: `path` is replaced only when files.commit() is called (with the
/// other files of the set, e.g. the mesh's report).
void write_mesh(const Mesh& mesh, const std::filesystem::path& path, AtomicFileSet& files);

/// Reads a mesh written by write_mesh (and ordinary files of these formats). Attributes that a
/// format does not carry are left empty. Throws IoError / FormatError naming file and value.
Mesh read_mesh(const std::filesystem::path& path);

/// True when the extension is one write_mesh understands.
bool is_mesh_extension(const std::filesystem::path& path);

}  // namespace orthofront::io
