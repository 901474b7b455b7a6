#pragma once
/// Fields that interpolate point vectors on an unstructured mesh: steady (MeshField) and a time
/// series on a fixed mesh, linear in time between steps (MeshSeriesField). Both share one
/// MeshGeometry (the mesh, its locator and whether it is a 2D case).
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "orthofront/field/cell_locator.h"
#include "orthofront/field/field.h"
#include "orthofront/field/unsteady.h"
#include "orthofront/field/unstructured_mesh.h"

namespace orthofront {

/// A mesh with its locator. A mesh one cell thick in z (every point on one of two z planes: how
/// OpenFOAM and other solvers write 2D cases) is planar: its fields are evaluated on the middle
/// plane whatever z is asked, have v_z = 0, and span the middle plane ± half the larger of the x
/// and y extents in z (as 2D grids do, so that seeds may be tilted out of the plane).
class MeshGeometry {
 public:
  /// Checks the mesh (check_mesh; `what` names its file in messages) and builds the locator.
  MeshGeometry(UnstructuredMesh mesh, std::string what);
  MeshGeometry(const MeshGeometry&) = delete;
  MeshGeometry& operator=(const MeshGeometry&) = delete;

  const UnstructuredMesh& mesh() const { return mesh_; }
  const CellLocator& locator() const { return *locator_; }
  const std::string& what() const { return what_; }
  bool planar() const { return planar_; }
  double plane_z() const { return plane_z_; }
  Box<3> domain() const { return domain_; }

  /// The cell containing x (the z of planar meshes replaced by the middle plane) and its
  /// parametric coordinates; -1 outside. Remembers each thread's last cell per geometry, so
  /// that a thread following one particle walks a cell or two instead of searching the bins.
  std::int32_t locate(const Vec3& x, double xi[3]) const;

 private:
  UnstructuredMesh mesh_;
  std::string what_;
  std::unique_ptr<CellLocator> locator_;
  bool planar_ = false;
  double plane_z_ = 0;
  Box<3> domain_;
};

/// Interpolates vectors given at the points (3 floats a point; NaN where there is no data) in the
/// cell found for x: v = Σ N_i v_i and J = Σ v_i ∇N_iᵀ, the exact derivative of the interpolant,
/// so a linear field is reproduced exactly on tetrahedra (and on any cell whose map is affine).
/// A cell with a NaN point value has no data; zero vectors are flow (no-slip walls are zero).
/// Returns false outside the mesh or without data.
FieldStatus interpolate_point_vectors(const MeshGeometry& geometry, const float* values,
                                      std::int32_t cell, const double xi[3], Vec3& v, Mat3* J);

class MeshField final : public Field3 {
 public:
  /// `values`: 3 floats per point of the mesh. Throws InvalidArgument on a size mismatch, and
  /// for a planar mesh whose vectors have a z component above 1e-3 of their largest magnitude
  /// (the case is not 2D after all).
  MeshField(std::shared_ptr<const MeshGeometry> geometry, std::vector<float> values,
            std::string description);

  FieldStatus velocity(const Vec3& x, Vec3& v) const override;
  FieldStatus velocity_jacobian(const Vec3& x, Vec3& v, Mat3& J) const override;
  Box<3> domain() const override { return geometry_->domain(); }
  std::string describe() const override { return description_; }

  const MeshGeometry& geometry() const { return *geometry_; }

 private:
  std::shared_ptr<const MeshGeometry> geometry_;
  std::vector<float> values_;
  std::string description_;
};

/// Steps of point vectors on one mesh at increasing times, linear in time between them (as grid
/// series are). Dimension 2 on planar meshes.
class MeshSeriesField final : public UnsteadyField {
 public:
  /// `steps[k]` holds 3 floats per point at `times[k]` (strictly increasing, at least two).
  /// Throws InvalidArgument as MeshField does, naming the step.
  MeshSeriesField(std::shared_ptr<const MeshGeometry> geometry, std::vector<double> times,
                  std::vector<std::vector<float>> steps, std::string description);

  int dimension() const override { return geometry_->planar() ? 2 : 3; }
  FieldStatus velocity(const Vec3& x, double t, Vec3& v) const override;
  FieldStatus velocity_jacobian(const Vec3& x, double t, Vec3& v, Mat3& J,
                                Vec3& dvdt) const override;
  Box<3> domain() const override { return geometry_->domain(); }
  TimeRange time_range() const override { return {times_.front(), times_.back()}; }
  std::string describe() const override { return description_; }
  /// The interior time steps (the interpolant's derivative jumps there).
  double next_kink(const Vec3& x, double t, const Vec3& w, double w_t, double after,
                   double before) const override;

  const MeshGeometry& geometry() const { return *geometry_; }
  const std::vector<double>& times() const { return times_; }

 private:
  FieldStatus evaluate(const Vec3& x, double t, Vec3& v, Mat3* J, Vec3* dvdt) const;

  std::shared_ptr<const MeshGeometry> geometry_;
  std::vector<double> times_;
  std::vector<std::vector<float>> steps_;
  std::string description_;
};

}  // namespace orthofront
