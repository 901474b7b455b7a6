// OpenVDB: VectorGrid → .vdb → VectorGrid round trips, the VDB field (exact on linear fields,
// consistent Jacobian, sparse domains, staggered grids, rotated transforms), scalar triples,
// several grids per file as a time series, and bad files.
#include <openvdb/openvdb.h>
#include <openvdb/tools/Interpolation.h>

#include <cmath>

#include "io/grid_test_support.h"
#include "orthofront/error.h"
#include "orthofront/io/error.h"
#include "orthofront/io/grid_file.h"
#include "orthofront/io/vdb_field.h"
#include "orthofront/io/vdb_grid.h"

using Catch::Matchers::Contains;
using orthofront::FieldStatus;
using orthofront::Mat3;
using orthofront::Vec3;
using orthofront::VectorGrid;
using orthofront::io::FormatError;
using orthofront::io::IoError;
using orthofront::io::VdbField;
using namespace grid_test;

namespace {

/// v(x) = A x + b with dyadic coefficients (exact in float on dyadic points).
const Mat3 kA = (Mat3() << 0.5, -1.0, 0.25, 2.0, 0.125, -0.5, -0.75, 1.5, 1.0).finished();
const Vec3 kB(1.0, -2.0, 0.5);

Vec3 linear(const Vec3& x) { return kA * x + kB; }

/// A uniform grid sampling `linear` (origin (1, -2, 0.5), spacing (0.5, 0.25, 1)).
VectorGrid linear_grid(std::int64_t n = 6) {
  VectorGrid grid;
  grid.geometry.size = {n, n + 1, n - 1};
  grid.geometry.origin = Vec3(1, -2, 0.5);
  grid.geometry.spacing = Vec3(0.5, 0.25, 1);
  for (std::int64_t k = 0; k < grid.geometry.size[2]; ++k) {
    for (std::int64_t j = 0; j < grid.geometry.size[1]; ++j) {
      for (std::int64_t i = 0; i < grid.geometry.size[0]; ++i) {
        const Vec3 x(grid.geometry.coordinate(0, i), grid.geometry.coordinate(1, j),
                     grid.geometry.coordinate(2, k));
        const Vec3 v = linear(x);
        for (int c = 0; c < 3; ++c) grid.values.push_back(static_cast<float>(v[c]));
      }
    }
  }
  return grid;
}

void check_linear(const orthofront::Field3& field, const Vec3& x) {
  Vec3 v;
  Mat3 J;
  REQUIRE(field.velocity_jacobian(x, v, J) == FieldStatus::inside);
  CHECK((v - linear(x)).norm() < 1e-12);
  CHECK((J - kA).norm() < 1e-12);
  Vec3 v_only;
  REQUIRE(field.velocity(x, v_only) == FieldStatus::inside);
  CHECK(v_only == v);
}

}  // namespace

TEST_CASE("vdb: a VectorGrid written to .vdb reads back identical", "[vdb]") {
  TempDir dir("vdb");
  SECTION("3D, with NaN points and zero vectors") {
    VectorGrid grid = sample_grid(7, 5, 4);
    grid.geometry.origin = Vec3(-1, 2, 0.5);
    grid.geometry.spacing = Vec3(0.5, 0.25, 2);
    for (int c = 0; c < 3; ++c) {
      grid.values[3 * 8 + static_cast<std::size_t>(c)] = NAN;  // an inactive voxel
      grid.values[static_cast<std::size_t>(c)] = NAN;           // on the box corner
      grid.values[3 * 20 + static_cast<std::size_t>(c)] = 0.0f;  // zero stays zero (active)
    }
    orthofront::io::write_vdb(grid, dir / "a.vdb");
    const VectorGrid back = orthofront::io::read_vdb_grid(dir / "a.vdb");
    CHECK(back.geometry.size == grid.geometry.size);
    CHECK(back.geometry.origin == grid.geometry.origin);
    CHECK(back.geometry.spacing == grid.geometry.spacing);
    CHECK(back.components == 3);
    CHECK(same_values(back.values, grid.values));
    // Through the format dispatch, by name, and from bytes in memory.
    CHECK(same_values(orthofront::io::read_vector_grid(dir / "a.vdb", "velocity").values, grid.values));
    CHECK(same_values(orthofront::io::parse_vector_grid(read_file(dir / "a.vdb"), dir / "a.vdb").values,
                      grid.values));
    const auto infos = orthofront::io::list_vdb_grids(dir / "a.vdb");
    REQUIRE(infos.size() == 1);
    CHECK(infos[0].name == "velocity");
    CHECK(infos[0].value_type == "vec3s");
    CHECK(infos[0].active_voxels == grid.geometry.point_count() - 2);
  }
  SECTION("2D, two components") {
    VectorGrid grid = sample_grid(6, 4, 1, 2, true);
    grid.values[3] = NAN;  // a whole point is missing (a voxel is active or not, not a component)
    orthofront::io::write_vdb(grid, dir / "flat.vdb", "flow");
    const VectorGrid back = orthofront::io::read_vdb_grid(dir / "flat.vdb", "flow");
    CHECK(back.geometry.dimension == 2);
    CHECK(back.geometry.size == grid.geometry.size);
    CHECK(back.components == 2);
    CHECK(same_values(back.values, grid.values));
  }
  SECTION("rectilinear grids are refused") {
    VectorGrid grid = sample_grid(2, 2, 2);
    grid.geometry.axes = {std::vector<double>{0, 1}, {0, 2}, {0, 3}};
    CHECK_THAT(thrown<orthofront::InvalidArgument>([&] { orthofront::io::write_vdb(grid, dir / "r.vdb"); }),
               Contains("rectilinear"));
    CHECK_FALSE(fs::exists(dir / "r.vdb"));
  }
}

TEST_CASE("vdb field: a linear field is reproduced exactly, with its Jacobian", "[vdb]") {
  TempDir dir("vdb");
  const VectorGrid grid = linear_grid();
  orthofront::io::write_vdb(grid, dir / "lin.vdb");
  const auto field = VdbField::open(dir / "lin.vdb");
  CHECK_FALSE(field->staggered());
  const auto box = field->domain();
  CHECK(box.lo == grid.geometry.bounds().lo);
  CHECK(box.hi == grid.geometry.bounds().hi);
  for (const Vec3& x : {Vec3(1.3, -1.9, 0.7), Vec3(2.9, -0.55, 4.5), Vec3(1, -2, 0.5),
                        grid.geometry.bounds().hi, Vec3(2.25, -1.0, 2.0)}) {
    INFO("x = " << x.transpose());
    check_linear(*field, x);
  }
  // The same values as OpenVDB's own sampler (float arithmetic there).
  openvdb::initialize();
  openvdb::io::File file((dir / "lin.vdb").string());
  file.open();
  auto vdb = openvdb::gridPtrCast<openvdb::Vec3SGrid>(file.readGrid("velocity"));
  file.close();
  openvdb::tools::GridSampler<openvdb::Vec3SGrid, openvdb::tools::BoxSampler> sampler(*vdb);
  for (const Vec3& x : {Vec3(1.3, -1.9, 0.7), Vec3(2.9, -0.55, 4.5)}) {
    const openvdb::Vec3s s = sampler.wsSample(openvdb::Vec3d(x[0], x[1], x[2]));
    Vec3 v;
    REQUIRE(field->velocity(x, v) == FieldStatus::inside);
    for (int c = 0; c < 3; ++c) CHECK(v[c] == Approx(s[c]).epsilon(1e-6));
  }
  // Outside the box.
  Vec3 v;
  CHECK(field->velocity(Vec3(0.9, -1.0, 1.0), v) == FieldStatus::outside);
  CHECK(field->velocity(Vec3(2.0, -1.0, 100.0), v) == FieldStatus::outside);
}

TEST_CASE("vdb field: the Jacobian is the exact derivative of the trilinear cell", "[vdb]") {
  VectorGrid grid = sample_grid(4, 4, 4);
  for (std::size_t i = 0; i < grid.values.size(); ++i)
    grid.values[i] = std::sin(static_cast<float>(i) * 0.37f);  // anything non-linear
  const auto field = VdbField::from_grid(grid);
  const Vec3 x(1.3, 1.6, 2.2);
  Vec3 v;
  Mat3 J;
  REQUIRE(field->velocity_jacobian(x, v, J) == FieldStatus::inside);
  const double h = 1e-6;
  for (int c = 0; c < 3; ++c) {
    Vec3 vp;
    Vec3 vm;
    Vec3 e = Vec3::Zero();
    e[c] = h;
    REQUIRE(field->velocity(x + e, vp) == FieldStatus::inside);
    REQUIRE(field->velocity(x - e, vm) == FieldStatus::inside);
    const Vec3 fd = (vp - vm) / (2 * h);
    CHECK((fd - J.col(c)).norm() < 1e-7);
  }
}

TEST_CASE("vdb field: inactive voxels give no_data (sparse domains)", "[vdb]") {
  VectorGrid grid = linear_grid(8);
  // Deactivate one voxel in the middle and a whole slab at the top.
  const auto& g = grid.geometry;
  const std::size_t hole = g.index(3, 3, 3);
  for (int c = 0; c < 3; ++c) grid.values[3 * hole + static_cast<std::size_t>(c)] = NAN;
  for (std::int64_t j = 0; j < g.size[1]; ++j) {
    for (std::int64_t i = 0; i < g.size[0]; ++i) {
      for (int c = 0; c < 3; ++c) grid.values[3 * g.index(i, j, 6) + static_cast<std::size_t>(c)] = NAN;
    }
  }
  const auto field = VdbField::from_grid(grid);
  Vec3 v;
  const auto at = [&](double i, double j, double k) {
    return Vec3(g.origin[0] + i * g.spacing[0], g.origin[1] + j * g.spacing[1], g.origin[2] + k * g.spacing[2]);
  };
  CHECK(field->velocity(at(3.5, 3.5, 3.5), v) == FieldStatus::no_data);  // a corner is the hole
  CHECK(field->velocity(at(2.5, 2.5, 2.5), v) == FieldStatus::no_data);
  CHECK(field->velocity(at(1.5, 1.5, 1.5), v) == FieldStatus::inside);
  CHECK((v - linear(at(1.5, 1.5, 1.5))).norm() < 1e-12);
  CHECK(field->velocity(at(2.5, 2.5, 5.5), v) == FieldStatus::no_data);  // touches the slab
  CHECK(field->velocity(at(2.5, 2.5, 4.5), v) == FieldStatus::inside);
}

TEST_CASE("vdb field: staggered grids, scalar triples, rotated transforms", "[vdb]") {
  TempDir dir("vdb");
  openvdb::initialize();
  const double voxel = 0.5;
  auto xform = openvdb::math::Transform::createLinearTransform(voxel);
  // Staggered: component c of voxel ijk lives at the face centre (ijk - e_c / 2) * voxel.
  auto staggered = openvdb::Vec3SGrid::create();
  staggered->setTransform(xform->copy());
  staggered->setGridClass(openvdb::GRID_STAGGERED);
  staggered->setName("mac");
  // Three scalar grids u, v, w (collocated).
  std::array<openvdb::FloatGrid::Ptr, 3> scalars;
  const char* names[3] = {"u", "v", "w"};
  for (int c = 0; c < 3; ++c) {
    scalars[static_cast<std::size_t>(c)] = openvdb::FloatGrid::create();
    scalars[static_cast<std::size_t>(c)]->setTransform(xform->copy());
    scalars[static_cast<std::size_t>(c)]->setName(names[c]);
  }
  auto mac = staggered->getAccessor();
  for (int k = 0; k < 6; ++k) {
    for (int j = 0; j < 6; ++j) {
      for (int i = 0; i < 6; ++i) {
        openvdb::Vec3s value;
        for (int c = 0; c < 3; ++c) {
          Vec3 face(i * voxel, j * voxel, k * voxel);
          face[c] -= 0.5 * voxel;
          value[c] = static_cast<float>(linear(face)[c]);
          scalars[static_cast<std::size_t>(c)]->tree().setValue(openvdb::Coord(i, j, k),
                                                              static_cast<float>(linear(Vec3(i, j, k) * voxel)[c]));
        }
        mac.setValue(openvdb::Coord(i, j, k), value);
      }
    }
  }
  openvdb::io::File((dir / "mix.vdb").string()).write({staggered, scalars[0], scalars[1], scalars[2]});

  const auto mac_field = VdbField::open(dir / "mix.vdb", "mac");
  CHECK(mac_field->staggered());
  check_linear(*mac_field, Vec3(1.1, 0.7, 1.3));
  // As OpenVDB's StaggeredBoxSampler gives it.
  openvdb::tools::GridSampler<openvdb::Vec3SGrid, openvdb::tools::StaggeredBoxSampler> sampler(*staggered);
  const openvdb::Vec3s s = sampler.wsSample(openvdb::Vec3d(1.1, 0.7, 1.3));
  Vec3 v;
  REQUIRE(mac_field->velocity(Vec3(1.1, 0.7, 1.3), v) == FieldStatus::inside);
  for (int c = 0; c < 3; ++c) CHECK(v[c] == Approx(s[c]).epsilon(1e-6));
  // Dense: the centre values (mean of the faces), exact for a linear field.
  const VectorGrid dense = orthofront::io::read_vdb_grid(dir / "mix.vdb", "mac");
  const std::size_t p = dense.geometry.index(2, 3, 1);
  const Vec3 expected = linear(Vec3(2, 3, 1) * voxel);
  for (int c = 0; c < 3; ++c) CHECK(dense.values[3 * p + static_cast<std::size_t>(c)] == Approx(expected[c]));

  // u, v, w found without a selector (no vector grid... but "mac" is one: name them).
  const auto triple = VdbField::open(dir / "mix.vdb", "u,v,w");
  CHECK(triple->grid_name() == "u,v,w");
  check_linear(*triple, Vec3(1.1, 0.7, 1.3));
  openvdb::io::File((dir / "uvw.vdb").string()).write({scalars[0], scalars[1], scalars[2]});
  check_linear(*VdbField::open(dir / "uvw.vdb"), Vec3(0.3, 2.2, 1.9));

  // A rotated, non-uniformly scaled transform: the field maps J to world space.
  openvdb::Mat4d m = openvdb::Mat4d::identity();
  m.preScale(openvdb::Vec3d(0.5, 0.25, 1.0));
  m.postRotate(openvdb::math::Z_AXIS, 0.3);
  m.postTranslate(openvdb::Vec3d(0.1, -0.2, 0.3));
  auto rotated_xform = openvdb::math::Transform::createLinearTransform(m);
  auto rotated = openvdb::Vec3SGrid::create();
  rotated->setTransform(rotated_xform);
  rotated->setName("rot");
  for (int k = 0; k < 6; ++k) {
    for (int j = 0; j < 6; ++j) {
      for (int i = 0; i < 6; ++i) {
        const openvdb::Vec3d w = rotated_xform->indexToWorld(openvdb::Coord(i, j, k));
        const Vec3 value = linear(Vec3(w[0], w[1], w[2]));
        rotated->tree().setValue(openvdb::Coord(i, j, k),
                                 openvdb::Vec3s(static_cast<float>(value[0]), static_cast<float>(value[1]),
                                                static_cast<float>(value[2])));
      }
    }
  }
  openvdb::io::File((dir / "rot.vdb").string()).write({rotated});
  const auto rot_field = VdbField::open(dir / "rot.vdb");
  const openvdb::Vec3d inside = rotated_xform->indexToWorld(openvdb::Vec3d(2.3, 3.1, 2.7));
  const Vec3 x(inside[0], inside[1], inside[2]);
  Mat3 J;
  REQUIRE(rot_field->velocity_jacobian(x, v, J) == FieldStatus::inside);
  CHECK((v - linear(x)).norm() < 1e-5);  // float samples of non-dyadic positions
  CHECK((J - kA).norm() < 1e-4);
  CHECK_THAT(thrown<FormatError>([&] { orthofront::io::read_vdb_grid(dir / "rot.vdb"); }),
             Contains("rot.vdb") && Contains("rotated"));
}

TEST_CASE("vdb: several grids of one file as a time series", "[vdb][series]") {
  TempDir dir("vdb");
  const VectorGrid a = sample_grid(4, 3, 2);
  VectorGrid b = a;
  for (float& x : b.values) x += 1.0f;
  VectorGrid c = a;
  for (float& x : c.values) x *= 2.0f;
  orthofront::io::write_vdb(dir / "steps.vdb", {{"late", &c, 2.5}, {"early", &a, 0.0}, {"middle", &b, 1.0}});
  const auto series = orthofront::io::open_vdb_file_series(dir / "steps.vdb");
  REQUIRE(series->step_count() == 3);
  CHECK(series->time(0) == 0.0);
  CHECK(series->time(1) == 1.0);
  CHECK(series->time(2) == 2.5);
  CHECK(series->geometry().size == a.geometry.size);
  std::vector<float> values(series->step_floats());
  series->read(0, values);
  CHECK(same_values(values, a.values));
  series->read(2, values);
  CHECK(same_values(values, c.values));

  // One file per step.
  orthofront::io::write_vdb(a, dir / "s0.vdb");
  orthofront::io::write_vdb(b, dir / "s1.vdb");
  const auto files = orthofront::io::open_vdb_series({{dir / "s0.vdb", ""}, {dir / "s1.vdb", ""}}, {0.0, 0.5});
  files->read(1, values);
  CHECK(same_values(values, b.values));
}

TEST_CASE("vdb: bad files and selectors are rejected naming the file", "[vdb]") {
  TempDir dir("vdb");
  const VectorGrid grid = sample_grid(3, 3, 3);
  orthofront::io::write_vdb(grid, dir / "a.vdb", "velocity");
  CHECK_THAT(thrown<FormatError>([&] { orthofront::io::read_vdb_grid(dir / "a.vdb", "density"); }),
             Contains("a.vdb") && Contains("no grid named 'density'") && Contains("velocity (vec3s)"));
  CHECK_THAT(thrown<FormatError>([&] { VdbField::open(dir / "a.vdb", "a,b"); }),
             Contains("a.vdb") && Contains("neither 1 nor 3"));
  write_file(dir / "junk.vdb", "this is not a vdb file at all");
  CHECK_THAT(thrown<FormatError>([&] { orthofront::io::read_vdb_grid(dir / "junk.vdb"); }),
             Contains("junk.vdb") && Contains("not a readable OpenVDB file"));
  CHECK_THAT(thrown<IoError>([&] { VdbField::open(dir / "none.vdb"); }), Contains("none.vdb"));
  openvdb::initialize();
  auto density = openvdb::FloatGrid::create();
  density->setName("density");
  density->tree().setValue(openvdb::Coord(0, 0, 0), 1.0f);
  openvdb::io::File((dir / "scalar.vdb").string()).write({density});
  CHECK_THAT(thrown<FormatError>([&] { VdbField::open(dir / "scalar.vdb"); }),
             Contains("scalar.vdb") && Contains("no Vec3f/Vec3d grid") && Contains("density (float)"));
  CHECK_THAT(thrown<FormatError>([&] { VdbField::open(dir / "scalar.vdb", "density"); }),
             Contains("scalar.vdb") && Contains("not vectors"));
}

TEST_CASE("vdb: the bubble-chamber data through OpenVDB", "[vdb][realdata]") {
  const fs::path data = datasets_dir("bubble-chamber");
  if (data.empty()) return;
  TempDir dir("vdb");
  const VectorGrid grid = orthofront::io::read_vector_grid(data / "BubbleChamber_11x11x10_T0.am");
  orthofront::io::write_vdb(grid, dir / "bubble.vdb");
  const VectorGrid back = orthofront::io::read_vdb_grid(dir / "bubble.vdb");
  CHECK(back.geometry.size == grid.geometry.size);
  CHECK((back.geometry.origin - grid.geometry.origin).norm() < 1e-12);
  CHECK((back.geometry.spacing - grid.geometry.spacing).norm() < 1e-12);
  CHECK(same_values(back.values, grid.values));
  // The field agrees with the samples at a voxel centre.
  const auto field = VdbField::open(dir / "bubble.vdb");
  const std::size_t p = grid.geometry.index(5, 6, 4);
  const Vec3 x(grid.geometry.coordinate(0, 5), grid.geometry.coordinate(1, 6), grid.geometry.coordinate(2, 4));
  Vec3 v;
  REQUIRE(field->velocity(x, v) == FieldStatus::inside);
  for (int c = 0; c < 3; ++c) CHECK(v[c] == Approx(grid.values[3 * p + static_cast<std::size_t>(c)]).margin(1e-9));
}

TEST_CASE("vdb field: a single voxel layer is a planar field", "[vdb]") {
  // v = (x - 2 y, 0.5 x + y), 2 components, on one z layer at z = 3.
  VectorGrid grid;
  grid.geometry.dimension = 2;
  grid.geometry.size = {5, 4, 1};
  grid.geometry.origin = Vec3(-1, 0, 3);
  grid.geometry.spacing = Vec3(0.5, 0.25, 1);
  grid.components = 2;
  for (std::int64_t j = 0; j < 4; ++j) {
    for (std::int64_t i = 0; i < 5; ++i) {
      const double x = -1 + 0.5 * static_cast<double>(i);
      const double y = 0.25 * static_cast<double>(j);
      grid.values.push_back(static_cast<float>(x - 2 * y));
      grid.values.push_back(static_cast<float>(0.5 * x + y));
    }
  }
  const auto field = VdbField::from_grid(grid);
  const auto box = field->domain();
  CHECK(box.lo[2] < 3.0);
  CHECK(box.hi[2] > 3.0);
  for (const double z : {3.0, 3.4, 2.2}) {
    const Vec3 x(0.3, 0.6, z);
    Vec3 v;
    Mat3 J;
    REQUIRE(field->velocity_jacobian(x, v, J) == FieldStatus::inside);
    CHECK((v - Vec3(0.3 - 1.2, 0.15 + 0.6, 0)).norm() < 1e-12);
    const Mat3 expected = (Mat3() << 1, -2, 0, 0.5, 1, 0, 0, 0, 0).finished();
    CHECK((J - expected).norm() < 1e-12);
  }
  Vec3 v;
  CHECK(field->velocity(Vec3(0.3, 0.6, 100.0), v) == FieldStatus::outside);
  CHECK(field->velocity(Vec3(2.0, 0.6, 3.0), v) == FieldStatus::outside);
}
