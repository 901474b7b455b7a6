#pragma once
/// A pipeline input as the project's grid: vtkImageData (uniform) or vtkRectilinearGrid (one
/// coordinate array per axis), 2D where it is one point thick in z (the vectors' x and y).
#include <memory>

#include "orthofront/field/grid.h"

class vtkDataArray;
class vtkDataSet;

namespace orthofront::paraview {

/// Throws InvalidArgument naming what does not fit: another dataset type, a rotated image, axes
/// that do not increase, a vector array of the wrong size or component count.
std::shared_ptr<const VectorGrid> dataset_grid(vtkDataSet* data, vtkDataArray* vectors);

}  // namespace orthofront::paraview
