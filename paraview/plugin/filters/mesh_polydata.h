#pragma once
/// A surface mesh as ParaView's output: vtkPolyData with its triangles and quads, every
/// recorded per-vertex attribute as point data, and its notes as field data string arrays.
#include <string>

#include "orthofront/mesh/mesh.h"

class vtkFieldData;
class vtkPolyData;

namespace orthofront::paraview {

/// Replaces `out`'s points, polygons and point data by the mesh's; adds its notes.
void mesh_to_polydata(const Mesh& mesh, vtkPolyData* out);

/// Adds a one-string array `name` holding `text` to `data`.
void add_text(vtkFieldData* data, const char* name, const std::string& text);

}  // namespace orthofront::paraview
