#include "dataset_grid.h"

#include <string>

#include "orthofront/error.h"
#include "vtkDataArray.h"
#include "vtkImageData.h"
#include "vtkMatrix3x3.h"
#include "vtkRectilinearGrid.h"

namespace orthofront::paraview {

namespace {

GridGeometry image_geometry(vtkImageData* image) {
  if (vtkMatrix3x3* direction = image->GetDirectionMatrix(); direction && !direction->IsIdentity())
    throw InvalidArgument("the input image is rotated (its direction matrix is not the "
                          "identity); resample it to an axis-aligned image first");
  int extent[6];
  image->GetExtent(extent);
  double origin[3], spacing[3];
  image->GetOrigin(origin);
  image->GetSpacing(spacing);
  GridGeometry g;
  for (int a = 0; a < 3; ++a) {
    g.size[static_cast<std::size_t>(a)] = extent[2 * a + 1] - extent[2 * a] + 1;
    g.origin[a] = origin[a] + extent[2 * a] * spacing[a];
    g.spacing[a] = spacing[a];
  }
  g.dimension = g.size[2] == 1 ? 2 : 3;
  if (g.dimension == 2) g.spacing.z() = 1;
  return g;
}

GridGeometry rectilinear_geometry(vtkRectilinearGrid* grid) {
  vtkDataArray* coordinates[3] = {grid->GetXCoordinates(), grid->GetYCoordinates(),
                                  grid->GetZCoordinates()};
  GridGeometry g;
  for (int a = 0; a < 3; ++a) {
    const auto ua = static_cast<std::size_t>(a);
    if (coordinates[a] == nullptr)
      throw InvalidArgument(std::string("the rectilinear grid has no ") + "xyz"[a] + " coordinates");
    g.size[ua] = coordinates[a]->GetNumberOfTuples();
    for (vtkIdType i = 0; i < coordinates[a]->GetNumberOfTuples(); ++i)
      g.axes[ua].push_back(coordinates[a]->GetComponent(i, 0));
  }
  g.dimension = g.size[2] == 1 ? 2 : 3;
  return g;  // GridField refuses axes that do not increase, naming the axis
}

}  // namespace

std::shared_ptr<const VectorGrid> dataset_grid(vtkDataSet* data, vtkDataArray* vectors) {
  auto grid = std::make_shared<VectorGrid>();
  GridGeometry& g = grid->geometry;
  if (auto* image = vtkImageData::SafeDownCast(data))
    g = image_geometry(image);
  else if (auto* rectilinear = vtkRectilinearGrid::SafeDownCast(data))
    g = rectilinear_geometry(rectilinear);
  else
    throw InvalidArgument(std::string("the input is a ") + (data ? data->GetClassName() : "null") +
                          "; the filters take image data or a rectilinear grid (resample "
                          "other meshes to an image first)");
  const int components = vectors->GetNumberOfComponents();
  const std::string name = vectors->GetName() ? vectors->GetName() : "";
  if (components < g.dimension || components > 3)
    throw InvalidArgument("the vector array '" + name + "' has " + std::to_string(components) +
                          " components; a " + std::to_string(g.dimension) + "D grid needs " +
                          std::to_string(g.dimension) + (g.dimension == 2 ? " or 3" : ""));
  const vtkIdType points = vectors->GetNumberOfTuples();
  if (static_cast<std::size_t>(points) != g.point_count())
    throw InvalidArgument("the vector array '" + name + "' has " + std::to_string(points) +
                          " tuples for a grid of " + std::to_string(g.point_count()) + " points");
  grid->components = g.dimension;
  grid->values.resize(g.point_count() * static_cast<std::size_t>(g.dimension));
  double tuple[3];
  for (vtkIdType i = 0; i < points; ++i) {  // VTK's point order is x fastest, as the grid's
    vectors->GetTuple(i, tuple);
    for (int c = 0; c < g.dimension; ++c)
      grid->values[static_cast<std::size_t>(i) * static_cast<std::size_t>(g.dimension) +
                   static_cast<std::size_t>(c)] = static_cast<float>(tuple[c]);
  }
  return grid;
}

}  // namespace orthofront::paraview
