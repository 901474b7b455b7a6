#include "orthofront/field/mesh_field.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "orthofront/error.h"
#include "orthofront/field/grid.h"  // next_interior_coordinate

namespace orthofront {

MeshGeometry::MeshGeometry(UnstructuredMesh mesh, std::string what)
    : mesh_(std::move(mesh)), what_(std::move(what)) {
  check_mesh(mesh_, what_);
  locator_ = std::make_unique<CellLocator>(mesh_);
  domain_ = mesh_.bounds();
  // One cell thick in z: every point on the lowest or the highest z plane.
  const double z0 = domain_.lo.z(), z1 = domain_.hi.z();
  const double xy = std::max(domain_.hi.x() - domain_.lo.x(), domain_.hi.y() - domain_.lo.y());
  const double slack = 1e-9 * std::max(xy, z1 - z0);
  bool two_planes = z1 - z0 > 0;
  for (std::size_t i = 0; two_planes && i < mesh_.point_count(); ++i) {
    const double z = mesh_.points[3 * i + 2];
    two_planes = std::fabs(z - z0) <= slack || std::fabs(z - z1) <= slack;
  }
  if (two_planes) {
    planar_ = true;
    plane_z_ = 0.5 * (z0 + z1);
    domain_.lo.z() = plane_z_ - 0.5 * xy;
    domain_.hi.z() = plane_z_ + 0.5 * xy;
  }
}

std::int32_t MeshGeometry::locate(const Vec3& x, double xi[3]) const {
  // Each thread's last cell in the last geometry it asked: one entry is enough, since a thread
  // follows one particle (or a front's neighbouring vertices) at a time.
  struct LastCell {
    const MeshGeometry* owner = nullptr;
    std::int32_t cell = -1;
  };
  thread_local LastCell last;
  const double p[3] = {x.x(), x.y(), planar_ ? plane_z_ : x.z()};
  if (planar_ && !(x.z() >= domain_.lo.z() && x.z() <= domain_.hi.z())) return -1;
  const std::int32_t hint = last.owner == this ? last.cell : -1;
  const std::int32_t c = locate::cell_of(locator_->view(), p, hint, xi);
  if (c >= 0) last = {this, c};
  return c;
}

FieldStatus interpolate_point_vectors(const MeshGeometry& geometry, const float* values,
                                      std::int32_t c, const double xi[3], Vec3& v, Mat3* J) {
  const UnstructuredMesh& mesh = geometry.mesh();
  const CellShape shape = mesh.shapes[static_cast<std::size_t>(c)];
  const std::int32_t* ids = mesh.cell_points(static_cast<std::size_t>(c));
  const int n = cell::point_count(shape);
  double N[8], dN[8][3];
  cell::shape_functions(shape, xi, N, dN);
  v.setZero();
  double dv[3][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}};  // ∂v_r/∂ξ_b
  for (int i = 0; i < n; ++i) {
    const float* vi = values + 3 * static_cast<std::size_t>(ids[i]);
    for (int r = 0; r < 3; ++r) {
      const double value = vi[r];
      if (std::isnan(value)) return FieldStatus::no_data;
      v[r] += N[i] * value;
      if (J)
        for (int b = 0; b < 3; ++b) dv[r][b] += dN[i][b] * value;
    }
  }
  if (J) {
    double p[8][3], x[3], A[3][3], B[3][3];
    mesh.gather(static_cast<std::size_t>(c), p);
    cell::map_point(shape, p, xi, x, A);
    if (!cell::invert3(A, B)) return FieldStatus::no_data;  // refused by check_mesh; defensive
    for (int r = 0; r < 3; ++r)
      for (int k = 0; k < 3; ++k)
        (*J)(r, k) = dv[r][0] * B[0][k] + dv[r][1] * B[1][k] + dv[r][2] * B[2][k];
  }
  if (geometry.planar()) {
    v.z() = 0;
    if (J) J->row(2).setZero(), J->col(2).setZero();
  }
  return FieldStatus::inside;
}

namespace {

void check_values(const MeshGeometry& g, const std::vector<float>& values,
                  const std::string& which) {
  if (values.size() != 3 * g.mesh().point_count())
    throw InvalidArgument(g.what() + which + ": " + std::to_string(values.size()) +
                          " vector components for " + std::to_string(g.mesh().point_count()) +
                          " points (3 a point expected)");
  if (!g.planar()) return;
  double largest = 0, largest_z = 0;
  for (std::size_t i = 0; i < values.size(); i += 3) {
    const double speed = std::hypot(values[i], values[i + 1], values[i + 2]);
    if (std::isfinite(speed)) largest = std::max(largest, speed);
    if (std::isfinite(values[i + 2])) largest_z = std::max(largest_z, std::fabs(double{values[i + 2]}));
  }
  if (largest_z > 1e-3 * largest)
    throw InvalidArgument(g.what() + which +
                          ": the mesh is one cell thick in z (a 2D case) but the z component of "
                          "the vectors reaches " + std::to_string(largest_z) + " against a largest "
                          "speed of " + std::to_string(largest) + "; a 2D case needs w = 0");
}

}  // namespace

MeshField::MeshField(std::shared_ptr<const MeshGeometry> geometry, std::vector<float> values,
                     std::string description)
    : geometry_(std::move(geometry)), values_(std::move(values)),
      description_(std::move(description)) {
  check_values(*geometry_, values_, "");
}

FieldStatus MeshField::velocity(const Vec3& x, Vec3& v) const {
  double xi[3];
  const std::int32_t c = geometry_->locate(x, xi);
  if (c < 0) return FieldStatus::outside;
  return interpolate_point_vectors(*geometry_, values_.data(), c, xi, v, nullptr);
}

FieldStatus MeshField::velocity_jacobian(const Vec3& x, Vec3& v, Mat3& J) const {
  double xi[3];
  const std::int32_t c = geometry_->locate(x, xi);
  if (c < 0) return FieldStatus::outside;
  return interpolate_point_vectors(*geometry_, values_.data(), c, xi, v, &J);
}

MeshSeriesField::MeshSeriesField(std::shared_ptr<const MeshGeometry> geometry,
                                 std::vector<double> times, std::vector<std::vector<float>> steps,
                                 std::string description)
    : geometry_(std::move(geometry)), times_(std::move(times)), steps_(std::move(steps)),
      description_(std::move(description)) {
  if (times_.size() < 2 || steps_.size() != times_.size())
    throw InvalidArgument(geometry_->what() + ": a time series needs at least two steps (" +
                          std::to_string(times_.size()) + " times, " +
                          std::to_string(steps_.size()) + " steps)");
  for (std::size_t k = 0; k < times_.size(); ++k) {
    if (!std::isfinite(times_[k]) || (k > 0 && !(times_[k] > times_[k - 1])))
      throw InvalidArgument(geometry_->what() + ": step times must increase strictly (step " +
                            std::to_string(k) + " at t = " + std::to_string(times_[k]) + ")");
    check_values(*geometry_, steps_[k], " (step " + std::to_string(k) + ")");
  }
}

FieldStatus MeshSeriesField::evaluate(const Vec3& x, double t, Vec3& v, Mat3* J,
                                      Vec3* dvdt) const {
  if (!(t >= times_.front() && t <= times_.back())) return FieldStatus::outside;
  double xi[3];
  const std::int32_t c = geometry_->locate(x, xi);
  if (c < 0) return FieldStatus::outside;
  // The step interval [k, k + 1] holding t (the last interval for t = the last time).
  const auto above = std::upper_bound(times_.begin(), times_.end(), t);
  const std::size_t k =
      std::min(static_cast<std::size_t>(above - times_.begin()), times_.size() - 1) - 1;
  const double span = times_[k + 1] - times_[k];
  const double w = (t - times_[k]) / span;
  Vec3 v0, v1;
  Mat3 J0, J1;
  FieldStatus s = interpolate_point_vectors(*geometry_, steps_[k].data(), c, xi, v0, J ? &J0 : nullptr);
  if (s != FieldStatus::inside) return s;
  s = interpolate_point_vectors(*geometry_, steps_[k + 1].data(), c, xi, v1, J ? &J1 : nullptr);
  if (s != FieldStatus::inside) return s;
  v = (1 - w) * v0 + w * v1;
  if (J) *J = (1 - w) * J0 + w * J1;
  if (dvdt) *dvdt = (v1 - v0) / span;
  return FieldStatus::inside;
}

FieldStatus MeshSeriesField::velocity(const Vec3& x, double t, Vec3& v) const {
  return evaluate(x, t, v, nullptr, nullptr);
}

FieldStatus MeshSeriesField::velocity_jacobian(const Vec3& x, double t, Vec3& v, Mat3& J,
                                               Vec3& dvdt) const {
  return evaluate(x, t, v, &J, &dvdt);
}

double MeshSeriesField::next_kink(const Vec3& x, double t, const Vec3& w, double w_t,
                                  double after, double before) const {
  (void)x, (void)w;
  if (w_t == 0) return std::numeric_limits<double>::infinity();
  const double step = next_interior_coordinate(times_, t + after * w_t, w_t > 0);
  const double tau = (step - t) / w_t;
  return tau > after && tau < before ? tau : std::numeric_limits<double>::infinity();
}

}  // namespace orthofront
