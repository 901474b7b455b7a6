#include "mesh_polydata.h"

#include "orthofront/io/mesh_attributes.h"
#include "vtkCellArray.h"
#include "vtkDoubleArray.h"
#include "vtkFieldData.h"
#include "vtkIntArray.h"
#include "vtkPointData.h"
#include "vtkPoints.h"
#include "vtkPolyData.h"
#include "vtkStringArray.h"

namespace orthofront::paraview {

void mesh_to_polydata(const Mesh& mesh, vtkPolyData* out) {
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  points->SetNumberOfPoints(static_cast<vtkIdType>(mesh.vertex_count()));
  for (std::size_t i = 0; i < mesh.vertex_count(); ++i)
    points->SetPoint(static_cast<vtkIdType>(i), mesh.positions[i].data());
  vtkNew<vtkCellArray> polys;
  for (const Face& face : mesh.faces) {
    vtkIdType ids[4];
    for (int c = 0; c < face.size; ++c) ids[c] = face.v[static_cast<std::size_t>(c)];
    polys->InsertNextCell(face.size, ids);
  }
  out->SetPoints(points);
  out->SetPolys(polys);
  for (const auto& a : io::detail::kRealAttributes) {
    if (!io::detail::is_recorded(mesh, mesh.*a.values)) continue;
    vtkNew<vtkDoubleArray> array;
    array->SetName(a.name);
    array->SetNumberOfValues(static_cast<vtkIdType>(mesh.vertex_count()));
    for (std::size_t i = 0; i < mesh.vertex_count(); ++i)
      array->SetValue(static_cast<vtkIdType>(i), (mesh.*a.values)[i]);
    out->GetPointData()->AddArray(array);
  }
  for (const auto& a : io::detail::kIntAttributes) {
    if (!io::detail::is_recorded(mesh, mesh.*a.values)) continue;
    vtkNew<vtkIntArray> array;
    array->SetName(a.name);
    array->SetNumberOfValues(static_cast<vtkIdType>(mesh.vertex_count()));
    for (std::size_t i = 0; i < mesh.vertex_count(); ++i)
      array->SetValue(static_cast<vtkIdType>(i), (mesh.*a.values)[i]);
    out->GetPointData()->AddArray(array);
  }
  for (const auto& [name, text] : mesh.notes) add_text(out->GetFieldData(), name.c_str(), text);
}

void add_text(vtkFieldData* data, const char* name, const std::string& text) {
  vtkNew<vtkStringArray> array;
  array->SetName(name);
  array->InsertNextValue(text);
  data->AddArray(array);
}

}  // namespace orthofront::paraview
