#include "orthofront/io/vdb_field.h"

#include <array>
#include <cmath>
#include <sstream>

#include "orthofront/field/multilinear.h"
#include "orthofront/io/error.h"
#include "orthofront/io/vdb_detail.h"
#include "orthofront/io/vdb_grid.h"
#include "orthofront/io/vdb_module.h"

namespace orthofront::io::module {

/// VdbField over the sparse grid itself (vdb_field.h says how it samples).
class SparseVdbField final : public VdbField {
 public:
  struct Impl;
  explicit SparseVdbField(std::unique_ptr<Impl> impl);
  ~SparseVdbField() override;
  SparseVdbField(const SparseVdbField&) = delete;
  SparseVdbField& operator=(const SparseVdbField&) = delete;

  FieldStatus velocity(const Vec3& x, Vec3& v) const override;
  FieldStatus velocity_jacobian(const Vec3& x, Vec3& v, Mat3& J) const override;
  Box<3> domain() const override;
  std::string describe() const override;
  bool staggered() const override;
  const std::string& grid_name() const override;
  std::uint64_t active_voxels() const override;

 private:
  std::unique_ptr<Impl> impl_;
};

struct SparseVdbField::Impl {
  detail::LoadedVdbGrid grid;
  std::string source;                  // file (and selector) for describe()
  openvdb::math::Transform::Ptr xform;
  Mat3 world_to_index = Mat3::Identity();  // d(index) / d(world): linear transforms only
  std::array<double, 3> lo{};          // index box of possible samples
  std::array<double, 3> hi{};
  bool planar = false;                 // one voxel layer in z
  Box<3> domain;
  std::uint64_t active = 0;

  template <typename GridT>
  FieldStatus evaluate(const GridT& g, const Vec3& x, Vec3& v, Mat3* J) const;
};

namespace {

/// Cell and local coordinate along one axis; false when the cell is not inside [lo, hi].
bool cell_along(double q, double lo, double hi, int& i0, double& t) {
  if (!(q >= lo) || !(q <= hi)) return false;
  double f = std::floor(q);
  if (f >= hi) f = hi - 1.0;  // the last layer belongs to the last cell
  i0 = static_cast<int>(f);
  t = q - f;
  return true;
}

/// Fetches the 8 voxels of the cell at `ijk` as doubles, corner (bx, by, bz) at bx | by << 1 |
/// bz << 2; false when one is inactive or NaN.
template <typename Accessor>
bool fetch(const Accessor& acc, const openvdb::Coord& ijk, bool planar,
           openvdb::Vec3d (&data)[8]) {
  typename Accessor::ValueType value;
  for (int corner = 0; corner < (planar ? 4 : 8); ++corner) {
    const openvdb::Coord at = ijk.offsetBy(corner & 1, (corner >> 1) & 1, (corner >> 2) & 1);
    if (!acc.probeValue(at, value)) return false;
    const openvdb::Vec3d d(value[0], value[1], value[2]);
    if (!std::isfinite(d[0]) || !std::isfinite(d[1]) || !std::isfinite(d[2])) return false;
    data[corner] = d;
  }
  return true;
}

}  // namespace

template <typename GridT>
FieldStatus SparseVdbField::Impl::evaluate(const GridT& g, const Vec3& x, Vec3& v, Mat3* J) const {
  const openvdb::Vec3d q = xform->worldToIndex(openvdb::Vec3d(x[0], x[1], x[2]));
  for (int a = 0; a < (planar ? 2 : 3); ++a) {
    if (!(q[a] >= lo[static_cast<std::size_t>(a)]) || !(q[a] <= hi[static_cast<std::size_t>(a)]))
      return FieldStatus::outside;
  }
  if (planar && !domain.contains(x)) return FieldStatus::outside;
  const auto acc = g.getConstUnsafeAccessor();
  const bool staggered = grid.staggered;
  Mat3 J_index = Mat3::Zero();
  // One cell for collocated grids; one per component (shifted by half a voxel) for staggered ones.
  for (int comp = 0; comp < (staggered ? 3 : 1); ++comp) {
    openvdb::Vec3d p = q;
    if (staggered) p[comp] += 0.5;
    int ijk[3] = {0, 0, static_cast<int>(lo[2])};
    openvdb::Vec3d t(0.0);
    for (int a = 0; a < (planar ? 2 : 3); ++a) {
      if (!cell_along(p[a], lo[static_cast<std::size_t>(a)],
                      hi[static_cast<std::size_t>(a)] + (staggered && a == comp ? 1.0 : 0.0), ijk[a], t[a]))
        return FieldStatus::no_data;
    }
    openvdb::Vec3d data[8];
    if (!fetch(acc, openvdb::Coord(ijk[0], ijk[1], ijk[2]), planar, data)) return FieldStatus::no_data;
    // The project's one multilinear kernel, in index space (cells of width 1).
    const multilinear::AxisCell cells[3] = {{ijk[0], t[0], 1.0}, {ijk[1], t[1], 1.0},
                                            {ijk[2], t[2], 1.0}};
    const auto corner = [&data](int bx, int by, int bz) {
      return data[bx | by << 1 | bz << 2].asPointer();
    };
    Vec3 value;
    Mat3 derivative;
    Mat3* d = J != nullptr ? &derivative : nullptr;
    if (planar) {
      if (d) multilinear::interpolate<2, 3, true>(corner, cells, value, d);
      else multilinear::interpolate<2, 3, false>(corner, cells, value, d);
    } else {
      if (d) multilinear::interpolate<3, 3, true>(corner, cells, value, d);
      else multilinear::interpolate<3, 3, false>(corner, cells, value, d);
    }
    for (int r = 0; r < 3; ++r) {
      if (staggered && r != comp) continue;
      v[r] = value[r];
      if (d)
        for (int a = 0; a < (planar ? 2 : 3); ++a) J_index(r, a) = derivative(r, a);
    }
  }
  if (grid.components == 2) v[2] = 0.0;
  if (J != nullptr) {
    *J = J_index * world_to_index;
    if (grid.components == 2) J->row(2).setZero();
  }
  return FieldStatus::inside;
}

SparseVdbField::SparseVdbField(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
SparseVdbField::~SparseVdbField() = default;

namespace {

std::unique_ptr<SparseVdbField::Impl> make_impl(detail::LoadedVdbGrid grid, std::string source) {
  auto impl = std::make_unique<SparseVdbField::Impl>();
  impl->grid = std::move(grid);
  impl->source = std::move(source);
  const openvdb::GridBase& base = impl->grid.base();
  const std::string what = impl->source + ": grid '" + impl->grid.name + "'";
  if (!base.transform().isLinear())
    throw FormatError(what + " has a non-linear (frustum) transform, which is not supported");
  impl->xform = base.transform().copy();
  const openvdb::CoordBBox box = detail::dense_index_box(impl->grid);
  if (box.empty()) throw FormatError(what + " has no active voxels");
  impl->active = base.activeVoxelCount();
  for (int a = 0; a < 3; ++a) {
    impl->lo[static_cast<std::size_t>(a)] = box.min()[a];
    impl->hi[static_cast<std::size_t>(a)] = box.max()[a];
  }
  impl->planar = box.dim().z() == 1;
  const openvdb::Vec3d o = impl->xform->worldToIndex(openvdb::Vec3d(0.0));
  for (int c = 0; c < 3; ++c) {
    openvdb::Vec3d e(0.0);
    e[c] = 1.0;
    const openvdb::Vec3d d = impl->xform->worldToIndex(e) - o;
    for (int r = 0; r < 3; ++r) impl->world_to_index(r, c) = d[r];
  }
  // World box of the index box (the bounding box of its corners).
  Box<3> domain;
  domain.lo.setConstant(INFINITY);
  domain.hi.setConstant(-INFINITY);
  for (int corner = 0; corner < 8; ++corner) {
    openvdb::Vec3d p;
    for (int a = 0; a < 3; ++a)
      p[a] = (corner >> a & 1) ? impl->hi[static_cast<std::size_t>(a)] : impl->lo[static_cast<std::size_t>(a)];
    const openvdb::Vec3d w = impl->xform->indexToWorld(p);
    for (int a = 0; a < 3; ++a) {
      domain.lo[a] = std::min(domain.lo[a], w[a]);
      domain.hi[a] = std::max(domain.hi[a], w[a]);
    }
  }
  if (impl->planar) {
    const double half = 0.5 * std::max(domain.hi[0] - domain.lo[0], domain.hi[1] - domain.lo[1]);
    domain.lo[2] -= half;
    domain.hi[2] += half;
  }
  impl->domain = domain;
  return impl;
}

}  // namespace

std::unique_ptr<VdbField> open_vdb_field(const std::filesystem::path& path,
                                         const std::string& selector) {
  detail::LoadedVdbGrid grid = detail::load_vdb_grid(path, selector, path.string());
  std::string source = path.string() + (selector.empty() ? "" : ":" + selector);
  return std::make_unique<SparseVdbField>(make_impl(std::move(grid), std::move(source)));
}

std::unique_ptr<VdbField> vdb_field_from_grid(const VectorGrid& grid, const std::string& name) {
  detail::LoadedVdbGrid loaded;
  loaded.grid_f = detail::to_vdb(grid, name);
  loaded.name = name;
  loaded.components = grid.components;
  return std::make_unique<SparseVdbField>(make_impl(std::move(loaded), "memory"));
}

FieldStatus SparseVdbField::velocity(const Vec3& x, Vec3& v) const {
  return impl_->grid.grid_f ? impl_->evaluate(*impl_->grid.grid_f, x, v, nullptr)
                            : impl_->evaluate(*impl_->grid.grid_d, x, v, nullptr);
}

FieldStatus SparseVdbField::velocity_jacobian(const Vec3& x, Vec3& v, Mat3& J) const {
  return impl_->grid.grid_f ? impl_->evaluate(*impl_->grid.grid_f, x, v, &J)
                            : impl_->evaluate(*impl_->grid.grid_d, x, v, &J);
}

Box<3> SparseVdbField::domain() const { return impl_->domain; }

std::string SparseVdbField::describe() const {
  std::ostringstream out;
  const openvdb::Vec3d voxel = impl_->xform->voxelSize();
  out << "OpenVDB grid '" << impl_->grid.name << "' of " << impl_->source << " ("
      << (impl_->grid.grid_f ? "vec3s" : "vec3d") << (impl_->grid.staggered ? ", staggered" : "")
      << ", " << impl_->active << " active voxels, voxel " << voxel[0] << " x " << voxel[1] << " x "
      << voxel[2] << ")";
  return out.str();
}

bool SparseVdbField::staggered() const { return impl_->grid.staggered; }
const std::string& SparseVdbField::grid_name() const { return impl_->grid.name; }
std::uint64_t SparseVdbField::active_voxels() const { return impl_->active; }

}  // namespace orthofront::io::module
