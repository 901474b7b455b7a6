#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstring>
#include <random>

#include <hdf5.h>

#include "io/grid_test_support.h"
#include "orthofront/field/grid_field.h"
#include "orthofront/field/unsteady.h"
#include "orthofront/io/error.h"
#include "orthofront/io/hdf5_layout.h"
#include "orthofront/io/vdb_grid.h"
#include "orthofront/advect/dispatch.h"
#include "orthofront/spacetime/bulk_flow_map.h"
#include "orthofront/spacetime/lifted_field.h"
#include "orthofront/spacetime/path_surface.h"
#include "orthofront/spacetime/sampled_series.h"
#include "orthofront/spacetime/streak_line_field.h"
#include "orthofront/spacetime/streamed_field.h"

#include "bricked_series.h"

using namespace orthofront;
using namespace orthofront::spacetime;
using grid_test::TempDir;
using spacetime_test::write_bricked;

namespace {

bool same_bits(const Vec3& a, const Vec3& b) { return std::memcmp(a.data(), b.data(), sizeof(double) * 3) == 0; }
bool same_bits(const Mat3& a, const Mat3& b) { return std::memcmp(a.data(), b.data(), sizeof(double) * 9) == 0; }

GridGeometry test_grid(int dimension, bool rectilinear) {
  GridGeometry g;
  g.dimension = dimension;
  g.size = {11, 9, dimension == 3 ? 7 : 1};  // not multiples of the brick: partial edge bricks
  g.origin = Vec3(-1.0, 0.5, 0.25);
  g.spacing = Vec3(0.3, 0.2, dimension == 3 ? 0.1 : 1.0);
  if (rectilinear)
    for (std::size_t a = 0; a < 3; ++a) {
      double x = g.origin[static_cast<int>(a)];
      for (std::int64_t i = 0; i < g.size[a]; ++i) {
        g.axes[a].push_back(x);
        x += 0.1 + 0.05 * static_cast<double>((i * 7 + static_cast<std::int64_t>(a)) % 5);
      }
    }
  return g;
}

// Writes `steps` steps of smooth-ish pseudo-random vectors; returns the file.
std::filesystem::path write_series(const TempDir& dir, const GridGeometry& g, int components,
                                   std::size_t steps, std::int64_t brick, bool zero_is_no_data) {
  const auto file = dir.path() / ("series-" + std::to_string(g.dimension) + "-" +
                                  std::to_string(g.rectilinear()) + ".h5");
  io::Hdf5WriteOptions w;
  w.storage = io::Hdf5Storage::bricked;
  w.brick_size = brick;
  w.codec = io::Hdf5Codec::lz4;
  w.zero_is_no_data = zero_is_no_data;
  w.xdmf = false;
  std::vector<double> times;
  for (std::size_t k = 0; k < steps; ++k) times.push_back(0.5 * static_cast<double>(k));
  io::Hdf5SeriesWriter writer(file, g, components, times, w);
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::vector<float> values(g.point_count() * static_cast<std::size_t>(components));
  for (std::size_t k = 0; k < steps; ++k) {
    for (float& v : values) v = u(rng);
    writer.write_step(values);
  }
  writer.commit();
  return file;
}

}  // namespace

TEST_CASE("bricked series: sampling across bricks equals whole-step sampling bit for bit",
          "[spacetime][bricks]") {
  TempDir dir("bricks");
  for (int dimension : {2, 3})
    for (bool rectilinear : {false, true}) {
      const GridGeometry g = test_grid(dimension, rectilinear);
      const auto file = write_series(dir, g, dimension, 5, 4, false);
      const auto series = io::open_hdf5_series(file);
      REQUIRE(series->description().storage == io::Hdf5Storage::bricked);
      const io::BrickLayout layout = series->bricks();
      REQUIRE(layout.size[0] == 4);
      REQUIRE(layout.count[0] == 3);  // 11 points: bricks of 4, 4 and 3
      CacheOptions bricked;
      bricked.budget_bytes = 64 << 20;
      CacheOptions whole = bricked;
      whole.whole_steps = true;
      BrickCache brick_cache(*series, bricked), step_cache(*series, whole);
      StreamedField by_brick(brick_cache), by_step(step_cache);
      // Points on brick borders (index 3 and 4 along each axis), on corners and at random.
      std::vector<Vec3> points;
      const Box<3> box = g.bounds();
      std::mt19937 rng(5);
      std::uniform_real_distribution<double> u(0.0, 1.0);
      for (int i = 0; i < 400; ++i) {
        Vec3 x;
        for (int a = 0; a < 3; ++a) x[a] = box.lo[a] + u(rng) * (box.hi[a] - box.lo[a]);
        if (dimension == 2) x.z() = 0;
        if (i % 4 == 1)  // exactly on a brick border along x (sample 4), between samples elsewhere
          x.x() = g.coordinate(0, 4);
        if (i % 4 == 2)  // in a cell that straddles bricks on every axis
          for (int a = 0; a < dimension; ++a)
            x[a] = 0.5 * (g.coordinate(a, 3) + g.coordinate(a, 4));
        if (i % 4 == 3)  // a brick corner point
          for (int a = 0; a < dimension; ++a) x[a] = g.coordinate(a, 4);
        points.push_back(x);
      }
      for (const Vec3& x : points)
        for (double t : {0.0, 0.3, 1.0, 1.75, 2.0}) {
          Vec3 va, vb, da, db;
          Mat3 ja, jb;
          REQUIRE(by_brick.velocity_jacobian(x, t, va, ja, da) == FieldStatus::inside);
          REQUIRE(by_step.velocity_jacobian(x, t, vb, jb, db) == FieldStatus::inside);
          INFO("dimension " << dimension << " rectilinear " << rectilinear << " x " << x.transpose()
                            << " t " << t);
          REQUIRE(same_bits(va, vb));
          REQUIRE(same_bits(ja, jb));
          REQUIRE(same_bits(da, db));
        }
      // At a step's time the streamed value is the in-memory grid field's, bit for bit.
      GridFieldOptions go;
      go.zero_is_no_data = false;
      const GridField step2(std::make_shared<VectorGrid>(io::read_hdf5_grid(file, "/", 2)), go);
      for (const Vec3& x : points) {
        Vec3 a, b;
        REQUIRE(by_brick.velocity(x, 1.0, a) == FieldStatus::inside);
        REQUIRE(step2.velocity(x, b) == FieldStatus::inside);
        REQUIRE(same_bits(a, b));
      }
      CHECK(brick_cache.statistics().units_touched > 8);  // only some of the bricks were read
    }
}

TEST_CASE("bricked series: zero vectors are no data when the file says so, as in memory",
          "[spacetime][bricks]") {
  TempDir dir("zeros");
  GridGeometry g = test_grid(2, false);
  for (bool zero_is_no_data : {true, false}) {
    const auto file = dir.path() / (std::string("wall-") + (zero_is_no_data ? "1" : "0") + ".h5");
    io::Hdf5WriteOptions w;
    w.zero_is_no_data = zero_is_no_data;
    w.brick_size = 4;
    w.xdmf = false;
    io::Hdf5SeriesWriter writer(file, g, 2, {0.0, 1.0}, w);
    std::vector<float> values(g.point_count() * 2, 0.0f);
    for (std::int64_t j = 0; j < g.size[1]; ++j)
      for (std::int64_t i = 0; i < g.size[0]; ++i) {
        const std::size_t p = g.index(i, j, 0) * 2;
        values[p] = i == 6 ? 0.0f : 1.0f;  // a wall of zero vectors along x = sample 6
        values[p + 1] = 0.0f;
      }
    writer.write_step(values);
    writer.write_step(values);
    writer.commit();
    const auto series = io::open_hdf5_series(file);
    CHECK(series->zero_is_no_data() == zero_is_no_data);
    BrickCache cache(*series, CacheOptions{});
    StreamedField field(cache);
    GridFieldOptions go;
    go.zero_is_no_data = zero_is_no_data;
    const GridField memory(std::make_shared<VectorGrid>(io::read_hdf5_grid(file)), go);
    const Vec3 by_wall(0.5 * (g.coordinate(0, 5) + g.coordinate(0, 6)), 1.0, 0.0);
    const Vec3 away(g.coordinate(0, 1) + 0.1, 1.0, 0.0);
    Vec3 v;
    const FieldStatus expected = zero_is_no_data ? FieldStatus::no_data : FieldStatus::inside;
    CHECK(field.velocity(by_wall, 0.5, v) == expected);
    CHECK(memory.velocity(by_wall, v) == expected);
    CHECK(field.velocity(away, 0.5, v) == FieldStatus::inside);
    if (zero_is_no_data) {
      // A path surface flowing +x stops at the wall instead of flowing through it.
      const SeedCurve seed = SeedCurve::line(Vec3(g.coordinate(0, 1), 0.7, 0),
                                             Vec3(g.coordinate(0, 1), 2.0, 0));
      PathSurfaceOptions o;
      o.t0 = 0;
      o.t1 = 1;
      o.engine.edge = 0.1;
      o.engine.max_steps = 400;
      const PathSurfaceResult r = build_path_surface(cache, seed, 6, o);
      REQUIRE(r.mesh.vertex_count() > 6);
      double x_max = -1e9;
      for (const Vec3& p : r.mesh.positions) x_max = std::max(x_max, p.x());
      CHECK(x_max <= g.coordinate(0, 6));
    }
  }
}

TEST_CASE("path surface through bricks under a tiny budget equals the in-memory surface",
          "[spacetime][bricks][path]") {
  TempDir dir("tiny");
  const auto flow = make_unsteady_field("double-gyre-3d");
  const GridGeometry g = uniform_grid(flow->domain(), 3, 17);
  const std::vector<double> times = uniform_times(0, 6, 60);
  const SampledTimeSeries memory(*flow, g, times);
  const auto series = write_bricked(dir.path() / "gyre.h5", memory, 4);
  PathSurfaceOptions o;
  o.t0 = 0;
  o.t1 = 6;
  o.engine.edge = 0.05;
  o.engine.max_steps = 100000;
  const SeedCurve seed = SeedCurve::line(Vec3(0.3, 0.25, 0.3), Vec3(0.9, 0.7, 0.6));
  CacheOptions all;
  all.budget_bytes = 1 << 30;
  BrickCache in_memory_cache(memory, all);
  const PathSurfaceResult reference = build_path_surface(in_memory_cache, seed, 8, o);
  REQUIRE(reference.path.complete);
  REQUIRE(reference.mesh.vertex_count() > 500);
  for (bool prefetch : {true, false}) {
    CacheOptions tiny;
    tiny.budget_bytes = 400 * 768;  // 400 bricks of the 7,625 (125 per step)
    tiny.max_live_tokens = 4;       // the room left for the band whatever the machine's cores
    tiny.prefetch = prefetch;
    BrickCache cache(*series, tiny);
    const PathSurfaceResult r = build_path_surface(cache, seed, 8, o);
    INFO("prefetch " << prefetch << ": " << r.path.message);
    REQUIRE(r.path.complete);
    CHECK(r.path.cache.peak_bytes <= tiny.budget_bytes);
    CHECK(r.path.cache.units_touched < 125 * times.size() / 2);
    REQUIRE(r.mesh.vertex_count() == reference.mesh.vertex_count());
    REQUIRE(r.mesh.faces.size() == reference.mesh.faces.size());
    for (std::size_t i = 0; i < r.mesh.vertex_count(); ++i)
      REQUIRE(same_bits(r.mesh.positions[i], reference.mesh.positions[i]));
    for (std::size_t f = 0; f < r.mesh.faces.size(); ++f)
      REQUIRE(r.mesh.faces[f].v == reference.mesh.faces[f].v);
  }
}

namespace {
// Forwards to a series and fails one step's bricks, as a damaged file would.
class FailingSeries final : public io::TimeSeries {
 public:
  FailingSeries(const io::TimeSeries& inner, std::size_t bad_step) : inner_(inner), bad_(bad_step) {}
  std::size_t step_count() const override { return inner_.step_count(); }
  double time(std::size_t step) const override { return inner_.time(step); }
  const GridGeometry& geometry() const override { return inner_.geometry(); }
  int components() const override { return inner_.components(); }
  std::string describe() const override { return inner_.describe(); }
  io::RawStep read_raw(std::size_t step) const override { return inner_.read_raw(step); }
  void decode(const io::RawStep& raw, std::span<float> v) const override { inner_.decode(raw, v); }
  io::BrickLayout bricks() const override { return inner_.bricks(); }
  io::RawStep read_raw_brick(std::size_t step, std::size_t brick) const override {
    if (step == bad_)
      throw io::FormatError("gyre.h5: step " + std::to_string(step) + " of '/velocity', brick " +
                            std::to_string(brick) + ": damaged Blosc data");
    return inner_.read_raw_brick(step, brick);
  }
  void decode_brick(const io::RawStep& raw, std::span<float> v) const override {
    inner_.decode_brick(raw, v);
  }

 private:
  const io::TimeSeries& inner_;
  std::size_t bad_;
};
}  // namespace

TEST_CASE("a corrupt brick mid-run stops the surface, names file, step and brick, keeps the "
          "partial surface",
          "[spacetime][bricks][path]") {
  TempDir dir("corrupt");
  const auto flow = make_unsteady_field("double-gyre");
  const GridGeometry g = uniform_grid(flow->domain(), 2, 41);
  const std::vector<double> times = uniform_times(0, 10, 100);
  const SampledTimeSeries memory(*flow, g, times, 2);
  const auto series = write_bricked(dir.path() / "gyre.h5", memory, 8);
  FailingSeries failing(*series, 30);
  CacheOptions co;
  co.budget_bytes = 4 << 20;
  BrickCache cache(failing, co);
  PathSurfaceOptions o;
  o.t0 = 0;
  o.t1 = 6;
  o.engine.edge = 0.05;
  o.engine.max_steps = 100000;
  const PathSurfaceResult r =
      build_path_surface(cache, SeedCurve::line(Vec3(0.3, 0.25, 0), Vec3(0.9, 0.7, 0)), 8, o);
  CHECK_FALSE(r.path.complete);
  CHECK_FALSE(r.report.complete);
  CHECK_THAT(r.path.message, Catch::Contains("time step 30, brick") &&
                                 Catch::Contains("gyre.h5") && Catch::Contains("damaged"));
  CHECK(r.mesh.vertex_count() > 50);
  CHECK(r.path.time_reached < 3.0 + 1e-9);
}

TEST_CASE("the README's out-of-core recipe, small: t = 0 to 20 on a budget the whole-step cache "
          "cannot use",
          "[spacetime][bricks][path][heavy]") {
  // Same shape as the README recipe (double-gyre-3d, 2:1:1 grid, 201 steps to t = 20, seed line
  // at mid-depth), 8x fewer points per axis, budget scaled with the data.
  TempDir dir("recipe");
  const auto flow = make_unsteady_field("double-gyre-3d");
  GridGeometry g = uniform_grid(flow->domain(), 3, 2);
  g.size = {32, 16, 16};
  for (int a = 0; a < 3; ++a)
    g.spacing[a] = flow->domain().extent()[a] / static_cast<double>(g.size[static_cast<std::size_t>(a)] - 1);
  const std::vector<double> times = uniform_times(0, 20, 200);
  const SampledTimeSeries memory(*flow, g, times);
  const auto series = write_bricked(dir.path() / "gyre.h5", memory, 4);
  PathSurfaceOptions o;
  o.t0 = 0;
  o.t1 = 20;
  o.engine.edge = 0.04;
  o.engine.max_steps = 100000;
  const SeedCurve seed = SeedCurve::line(Vec3(0.1, 0.5, 0.5), Vec3(0.6, 0.5, 0.5));
  CacheOptions co;
  co.budget_bytes = 10 * series->step_bytes();  // 5 % of the series
  BrickCache bricks(*series, co);
  const PathSurfaceResult r = build_path_surface(bricks, seed, 20, o);
  INFO(r.path.message);
  REQUIRE(r.path.complete);
  CHECK(r.path.time_reached >= 19.9);
  CHECK(r.path.cache.peak_bytes <= co.budget_bytes);
  CHECK(r.path.cache.read_amplification() < 2.5);  // prefetch guesses, timing-dependent
  // On demand, only the bricks the front samples are read, and (nearly) each once.
  co.prefetch = false;
  BrickCache on_demand(*series, co);
  const PathSurfaceResult d = build_path_surface(on_demand, seed, 20, o);
  REQUIRE(d.path.complete);
  INFO("on-demand read amplification " << d.path.cache.read_amplification());
  CHECK(d.path.cache.read_amplification() < 1.2);
  CHECK(d.mesh.positions == r.mesh.positions);
  co.prefetch = true;
  co.whole_steps = true;
  co.max_live_tokens = 1;
  BrickCache steps(*series, co);
  const PathSurfaceResult s = build_path_surface(steps, seed, 20, o);
  CHECK_FALSE(s.path.complete);  // the front's time band holds more steps than fit
  CHECK_THAT(s.path.message, Catch::Contains("raise --cache-budget"));
}

namespace {

// The double gyre on 21 x 21 points at 10 times, and a cache budget of three of its steps plus
// one load in flight.
struct ThreeStepBudget {
  std::unique_ptr<UnsteadyField> flow = make_unsteady_field("double-gyre");
  SampledTimeSeries series{*flow, uniform_grid(flow->domain(), 2, 21), uniform_times(0, 10, 10), 2};
  CacheOptions options() const {
    CacheOptions co;
    co.max_live_tokens = 1;
    co.budget_bytes = 3 * series.step_bytes() + 3 * series.step_bytes();
    return co;
  }
};

}  // namespace

TEST_CASE("a new band fits where only the band itself fits: the old band's pins go first",
          "[spacetime][bricks]") {
  const ThreeStepBudget data;
  BrickCache cache(data.series, data.options());
  StreamedField field(cache);
  field.update_band(0.0, 1.5);  // steps 0..2
  field.update_band(5.0, 6.5);  // steps 5..7: fits only once 0..2 are released
  CHECK(cache.statistics().peak_bytes <= data.options().budget_bytes);
  Vec3 a, b;
  REQUIRE(field.velocity(Vec3(0.7, 0.3, 0), 5.5, a) == FieldStatus::inside);
  REQUIRE(data.flow->velocity(Vec3(0.7, 0.3, 0), 5.5, b) == FieldStatus::inside);
  CHECK((a - b).norm() < 0.05);
  CHECK(field.slow_evaluations() == 0);
}

TEST_CASE("a brick never written reads as the whole-step read does (fill values)",
          "[spacetime][bricks]") {
  TempDir dir("unwritten");
  const auto file = dir.path() / "sparse.h5";
  // A bricked 2D series written by hand: 8 x 8 points, bricks of 4 x 4, one chunk left out.
  {
    const hid_t f = H5Fcreate(file.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    const hsize_t tdims[1] = {2};
    const double times[2] = {0.0, 1.0};
    const hid_t tspace = H5Screate_simple(1, tdims, nullptr);
    const hid_t tset = H5Dcreate2(f, "times", H5T_IEEE_F64LE, tspace, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    H5Dwrite(tset, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, times);
    const hsize_t dims[4] = {2, 8, 8, 2}, chunk[4] = {1, 4, 4, 2};
    const hid_t space = H5Screate_simple(4, dims, nullptr);
    const hid_t create = H5Pcreate(H5P_DATASET_CREATE);
    H5Pset_chunk(create, 4, chunk);
    const hid_t set = H5Dcreate2(f, "velocity", H5T_IEEE_F32LE, space, H5P_DEFAULT, create, H5P_DEFAULT);
    std::vector<float> brick(4 * 4 * 2, 1.5f);
    for (hsize_t step = 0; step < 2; ++step)
      for (hsize_t j = 0; j < 8; j += 4)
        for (hsize_t i = 0; i < 8; i += 4) {
          if (step == 1 && i == 4 && j == 4) continue;  // never written
          const hsize_t offset[4] = {step, j, i, 0};
          H5Dwrite_chunk(set, H5P_DEFAULT, 0, offset, brick.size() * sizeof(float), brick.data());
        }
    const double origin[3] = {0, 0, 0}, spacing[3] = {1, 1, 1};
    const hsize_t three = 3;
    const hid_t aspace = H5Screate_simple(1, &three, nullptr);
    for (const auto& [name, values] : {std::pair{"origin", origin}, std::pair{"spacing", spacing}}) {
      const hid_t attribute = H5Acreate2(f, name, H5T_IEEE_F64LE, aspace, H5P_DEFAULT, H5P_DEFAULT);
      H5Awrite(attribute, H5T_NATIVE_DOUBLE, values);
      H5Aclose(attribute);
    }
    H5Sclose(aspace);
    H5Dclose(set);
    H5Pclose(create);
    H5Sclose(space);
    H5Dclose(tset);
    H5Sclose(tspace);
    H5Fclose(f);
  }
  const auto series = io::open_hdf5_series(file);
  REQUIRE(series->description().storage == io::Hdf5Storage::bricked);
  REQUIRE(series->bricks().bricks() == 4);
  std::vector<float> whole(series->step_floats()), brick(series->brick_floats());
  series->decode_brick(series->read_raw_brick(1, 3), brick);  // before HDF5 has read it
  CHECK(brick[0] == 0.0f);
  series->read(1, whole);
  // Again, now that HDF5 has read the brick's fill values (a chunk cache would hold them, and
  // the chunk would look stored).
  series->decode_brick(series->read_raw_brick(1, 3), brick);
  for (std::int64_t j = 0; j < 4; ++j)
    for (std::int64_t i = 0; i < 4; ++i)
      for (std::size_t c = 0; c < 2; ++c)
        REQUIRE(brick[static_cast<std::size_t>(j * 4 + i) * 2 + c] ==
                whole[static_cast<std::size_t>((j + 4) * 8 + i + 4) * 2 + c]);
  CHECK(brick[0] == 0.0f);  // HDF5's default fill value
  series->decode_brick(series->read_raw_brick(1, 0), brick);
  CHECK(brick[0] == 1.5f);
}

TEST_CASE("an OpenVDB series is read brick by brick, with the values of whole-step reads",
          "[spacetime][bricks][vdb]") {
  TempDir dir("vdb");
  const auto flow = make_unsteady_field("double-gyre-3d");
  GridGeometry g = uniform_grid(flow->domain(), 3, 2);
  g.size = {70, 36, 36};  // 3 x 2 x 2 bricks of 32³, partial at the far edges
  for (int a = 0; a < 3; ++a)
    g.spacing[a] = flow->domain().extent()[a] / static_cast<double>(g.size[static_cast<std::size_t>(a)] - 1);
  const std::vector<double> times = uniform_times(0, 3, 15);
  const SampledTimeSeries memory(*flow, g, times);
  const auto file = dir.path() / "gyre.vdb";
  {
    io::VdbFileWriter writer(file);
    for (std::size_t k = 0; k < times.size(); ++k) {
      VectorGrid grid;
      grid.geometry = g;
      grid.values.resize(memory.step_floats());
      memory.sample(k, grid.values.data());
      writer.add("v" + std::to_string(k), grid, times[k]);
    }
    writer.commit();
  }
  const auto series = io::open_vdb_file_series(file);
  REQUIRE(series->step_count() == times.size());
  const io::BrickLayout layout = series->bricks();
  REQUIRE(layout.bricks() == 12);
  // A brick holds exactly the whole step's values over its region.
  std::vector<float> whole(series->step_floats()), brick(series->brick_floats());
  series->read(4, whole);
  const GridGeometry& sg = series->geometry();
  for (std::size_t b : {std::size_t{0}, std::size_t{5}, std::size_t{11}}) {
    series->decode_brick(series->read_raw_brick(4, b), brick);
    const auto bi = static_cast<std::int64_t>(b) % 3, bj = static_cast<std::int64_t>(b) / 3 % 2,
               bk = static_cast<std::int64_t>(b) / 6;
    for (std::int64_t k = 0; k < 32 && bk * 32 + k < sg.size[2]; ++k)
      for (std::int64_t j = 0; j < 32 && bj * 32 + j < sg.size[1]; ++j)
        for (std::int64_t i = 0; i < 32 && bi * 32 + i < sg.size[0]; ++i)
          for (std::size_t c = 0; c < 3; ++c)
            REQUIRE(brick[static_cast<std::size_t>((k * 32 + j) * 32 + i) * 3 + c] ==
                    whole[sg.index(bi * 32 + i, bj * 32 + j, bk * 32 + k) * 3 + c]);
  }
  // The same path surface through bricks on a small budget and through whole steps.
  PathSurfaceOptions o;
  o.t0 = 0;
  o.t1 = 3;
  o.engine.edge = 0.05;
  o.engine.max_steps = 100000;
  const SeedCurve seed = SeedCurve::line(Vec3(0.3, 0.25, 0.3), Vec3(0.6, 0.4, 0.5));
  CacheOptions small;
  small.budget_bytes = 64 * series->brick_floats() * sizeof(float);
  BrickCache bricks(*series, small);
  const PathSurfaceResult r = build_path_surface(bricks, seed, 8, o);
  CacheOptions all;
  all.whole_steps = true;
  all.budget_bytes = std::size_t{1} << 30;
  BrickCache steps(*series, all);
  const PathSurfaceResult w = build_path_surface(steps, seed, 8, o);
  INFO(r.path.message);
  REQUIRE(r.path.complete);
  REQUIRE(w.path.complete);
  CHECK(r.path.cache.units_touched < layout.bricks() * times.size() / 2);
  CHECK(r.path.cache.peak_bytes <= small.budget_bytes);
  REQUIRE(r.mesh.vertex_count() == w.mesh.vertex_count());
  CHECK(r.mesh.positions == w.mesh.positions);
}

TEST_CASE("bricked series: whole steps gathered from bricks give a slab StreamedField's values, "
          "bit for bit, and copy_step the same floats",
          "[spacetime][bricks][advect]") {
  TempDir dir("bricks-gather");
  for (int dimension : {2, 3})
    for (bool rectilinear : {false, true}) {
      INFO(dimension << "D, " << (rectilinear ? "rectilinear" : "uniform"));
      const GridGeometry g = test_grid(dimension, rectilinear);
      const auto file = write_series(dir, g, dimension, 3, 4, false);
      const auto series = io::open_hdf5_series(file);
      CacheOptions bricked;
      bricked.budget_bytes = 64 << 20;
      BrickCache cache(*series, bricked);
      StreamedField field(cache);
      field.update_band(series->time(0), series->time(2));
      CachedSteps steps(cache);
      const advect::GridTables tables(g, dimension, false);
      std::mt19937_64 rng(5);
      std::uniform_real_distribution<double> u(0, 1);
      const Box<3> box = g.bounds();
      for (std::size_t k = 0; k < 2; ++k) {
        advect::SlabView slab;
        slab.grid = tables.view();
        slab.step0 = steps.acquire(k);
        slab.step1 = steps.acquire(k + 1);
        slab.t0 = series->time(k);
        slab.t1 = series->time(k + 1);
        for (int i = 0; i < 500; ++i) {
          Vec3 x = box.lo + (box.hi - box.lo).cwiseProduct(Vec3(u(rng), u(rng), u(rng)));
          if (dimension == 2) x.z() = 0;
          const double t = slab.t0 + (slab.t1 - slab.t0) * u(rng);
          Vec3 want;
          REQUIRE(field.velocity(x, t, want) == FieldStatus::inside);
          double got[3] = {0, 0, 0};
          advect::SampleStatus status = advect::SampleStatus::outside;
          advect::dispatch_grid(slab.grid, [&]<int Axes, int Components, bool Rectilinear>() {
            status = advect::sample_slab<Axes, Components, Rectilinear>(slab, x.data(), t, got);
          });
          REQUIRE(status == advect::SampleStatus::inside);
          for (int d = 0; d < 3; ++d) REQUIRE(got[d] == want[d]);
        }
        // copy_step gives the same floats, from the held step or gathered straight from the
        // bricks, and leaves a held step held.
        const std::size_t floats = g.point_count() * static_cast<std::size_t>(dimension);
        std::vector<float> from_held(floats, -1.0f), gathered(floats, -2.0f);
        steps.copy_step(k, from_held.data());
        CHECK(std::memcmp(from_held.data(), slab.step0, floats * sizeof(float)) == 0);
        CHECK(steps.acquire(k) == slab.step0);
        steps.release(k);
        steps.copy_step(k, gathered.data());
        CHECK(std::memcmp(gathered.data(), from_held.data(), floats * sizeof(float)) == 0);
      }
    }
}

TEST_CASE("a unit the full budget cannot take fails the evaluation once, later misses fail at "
          "once, not after another wait each",
          "[spacetime][bricks]") {
  const ThreeStepBudget data;
  BrickCache cache(data.series, data.options());
  StreamedField field(cache);
  field.update_band(5.0, 6.5);  // steps 5..7 pinned: the budget holds one more step at most
  Vec3 v;
  FieldStatus first = FieldStatus::inside;
  for (const double t : {1.0, 2.0, 3.0}) {
    first = field.velocity(Vec3(0.7, 0.3, 0), t, v);
    if (first != FieldStatus::inside) break;
  }
  REQUIRE(first == FieldStatus::no_data);
  CHECK_THAT(field.error(), Catch::Contains("full of pinned units"));
  const auto t0 = std::chrono::steady_clock::now();
  for (int k = 0; k < 20; ++k)
    CHECK(field.velocity(Vec3(0.7, 0.3, 0), 0.2 + 0.1 * k, v) == FieldStatus::no_data);
  // Each of these waited a second on the cache before.
  CHECK(std::chrono::steady_clock::now() - t0 < std::chrono::seconds(3));
  // The band itself still reads.
  CHECK(field.velocity(Vec3(0.7, 0.3, 0), 5.5, v) == FieldStatus::inside);
}

TEST_CASE("a streamed field's kinks are its cell faces and time steps, the lifted field "
          "forwards them",
          "[spacetime][bricks][kinks]") {
  TempDir dir("bricks-kinks");
  for (int dimension : {2, 3})
    for (bool rectilinear : {false, true}) {
      INFO(dimension << "D, " << (rectilinear ? "rectilinear" : "uniform"));
      const GridGeometry g = test_grid(dimension, rectilinear);
      const auto file = write_series(dir, g, dimension, 5, 4, false);
      const auto series = io::open_hdf5_series(file);
      CacheOptions options;
      options.budget_bytes = 64 << 20;
      BrickCache cache(*series, options);
      const StreamedField field(cache);
      // Interior faces and interior time steps below a space-time point, counted.
      const auto key = [&](const Vec3& p, double t) {
        std::array<long, 4> k{0, 0, 0, 0};
        for (int a = 0; a < dimension; ++a)
          for (std::int64_t i = 1; i + 1 < g.size[static_cast<std::size_t>(a)]; ++i)
            k[static_cast<std::size_t>(a)] += g.coordinate(a, i) <= p[a];
        for (std::size_t s = 1; s + 1 < series->step_count(); ++s) k[3] += series->time(s) <= t;
        return k;
      };
      std::mt19937_64 rng(31);
      std::uniform_real_distribution<double> u(0, 1);
      const Box<3> box = g.bounds();
      for (int i = 0; i < 200; ++i) {
        Vec3 x = box.lo + (box.hi - box.lo).cwiseProduct(Vec3(u(rng), u(rng), u(rng)));
        Vec3 w(u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5);
        const double t = 2 * u(rng), w_t = i % 5 == 0 ? 0.0 : u(rng) - 0.3;
        const double after = i % 2 ? 0.0 : 0.05 * u(rng), before = 0.4;
        const double tau = field.next_kink(x, t, w, w_t, after, before);
        const double end = std::isfinite(tau) ? tau : before;
        const auto at = [&](double s) { return key(x + s * w, t + s * w_t); };
        const auto inside = at(0.5 * (after + end));
        for (int j = 0; j < 40; ++j) REQUIRE(at(after + (end - after) * (j + 0.5) / 40) == inside);
        if (std::isfinite(tau)) {
          REQUIRE(tau > after);
          REQUIRE(tau < before);
          REQUIRE(at(tau - 1e-9) != at(tau + 1e-9));
        }
        // The lifted field: coordinates (x, c t), velocity (w, c w_t).
        if (dimension == 3) {
          const LiftedField<4> lifted(field, 2.0, field.time_range());
          const Vec<4> X(x.x(), x.y(), x.z(), 2.0 * t), W(w.x(), w.y(), w.z(), 2.0 * w_t);
          CHECK(lifted.next_kink(X, W, after, before) == tau);
        }
      }
    }
}

namespace {

// A flow that hides its kinks from integrators: steps cross cell faces and time steps as before.
class KinksHidden final : public UnsteadyField {
 public:
  explicit KinksHidden(const UnsteadyField& flow) : flow_(flow) {}
  int dimension() const override { return flow_.dimension(); }
  FieldStatus velocity(const Vec3& x, double t, Vec3& v) const override {
    return flow_.velocity(x, t, v);
  }
  FieldStatus velocity_jacobian(const Vec3& x, double t, Vec3& v, Mat3& J,
                                Vec3& dvdt) const override {
    return flow_.velocity_jacobian(x, t, v, J, dvdt);
  }
  Box<3> domain() const override { return flow_.domain(); }
  TimeRange time_range() const override { return flow_.time_range(); }
  std::string describe() const override { return flow_.describe(); }

 private:
  const UnsteadyField& flow_;
};

}  // namespace

// Closer to the interpolant's flow map than steps across the kinks, for fewer evaluations.
TEST_CASE("flow-map gradients step to a streamed series' cell faces and time steps",
          "[spacetime][bricks][kinks]") {
  TempDir dir("bricks-kink-paths");
  const auto flow = make_unsteady_field("double-gyre-3d");
  const GridGeometry g = uniform_grid(flow->domain(), 3, 17);
  const SampledTimeSeries memory(*flow, g, uniform_times(0, 2, 9));
  const auto series = write_bricked(dir.path() / "gyre.h5", memory, 4);
  CacheOptions options;
  options.budget_bytes = 64 << 20;
  BrickCache cache(*series, options);
  StreamedField field(cache);
  field.update_band(series->time(0), series->time(series->step_count() - 1));
  const KinksHidden hidden(field);
  const Tolerance tol{1e-9, 1e-9}, tight{1e-13, 1e-13};
  const Box<3> box = g.bounds();
  const Vec3 center = 0.5 * (box.lo + box.hi), half = 0.3 * (box.hi - box.lo);
  std::mt19937_64 rng(37);
  std::uniform_real_distribution<double> u(-1, 1);
  long with_kinks = 0, without = 0, compared = 0;
  double worst_with = 0, worst_without = 0, gradient_with = 0, gradient_without = 0;
  for (int i = 0; i < 30; ++i) {
    const Vec3 x = center + half.cwiseProduct(Vec3(u(rng), u(rng), u(rng)));
    const double t0 = 0.1, t1 = 0.1 + 0.8 * (1 + u(rng));  // across up to seven time steps
    const FlowMapGradient a = flow_map_gradient(field, x, t0, t1, tol);
    const FlowMapGradient b = flow_map_gradient(hidden, x, t0, t1, tol);
    // The reference steps across faces and time steps (it knows nothing of them), tightly.
    const FlowMapGradient exact = flow_map_gradient(hidden, x, t0, t1, tight);
    if (a.status != FieldStatus::inside || b.status != FieldStatus::inside ||
        exact.status != FieldStatus::inside)
      continue;
    ++compared;
    with_kinks += a.evaluations;
    without += b.evaluations;
    worst_with = std::max(worst_with, (a.x - exact.x).norm());
    worst_without = std::max(worst_without, (b.x - exact.x).norm());
    gradient_with = std::max(gradient_with, (a.gradient - exact.gradient).norm());
    gradient_without = std::max(gradient_without, (b.gradient - exact.gradient).norm());
  }
  REQUIRE(compared >= 10);
  INFO("evaluations " << with_kinks << " against " << without << "; position errors " << worst_with
                      << " against " << worst_without << "; gradient errors " << gradient_with
                      << " against " << gradient_without);
  // Sampled double-gyre-3d, 17^3 x 9 steps: 20,694 against 23,382 evaluations, position errors
  // 3.3e-9 against 9.2e-8, gradient errors 6.6e-8 against 5.9e-7.
  CHECK(with_kinks < without);
  CHECK(worst_with < 0.25 * worst_without);
  CHECK(gradient_with < 0.25 * gradient_without);
}

TEST_CASE("bricked series: NaN and infinite samples are no data at every weight, as in memory",
          "[spacetime][bricks]") {
  // The streamed field finds a non-finite corner from the interpolated value; the in-memory
  // field from its mask of cells. Points on sample coordinates give such a corner weight 0 or 1.
  TempDir dir("nonfinite");
  const GridGeometry g = test_grid(3, false);
  const auto file = dir.path() / "holes.h5";
  io::Hdf5WriteOptions w;
  w.brick_size = 4;
  w.xdmf = false;
  w.zero_is_no_data = false;  // no corner is looked at: the value alone tells
  io::Hdf5SeriesWriter writer(file, g, 3, {0.0, 1.0}, w);
  std::vector<float> values(g.point_count() * 3);
  for (std::size_t p = 0; p < g.point_count(); ++p)
    for (std::size_t c = 0; c < 3; ++c) values[3 * p + c] = 0.25f + 0.01f * static_cast<float>(p % 17 + c);
  values[3 * g.index(2, 2, 2) + 0] = std::numeric_limits<float>::quiet_NaN();
  values[3 * g.index(7, 4, 3) + 1] = std::numeric_limits<float>::infinity();
  values[3 * g.index(4, 6, 5) + 2] = -std::numeric_limits<float>::infinity();  // on a brick border
  writer.write_step(values);
  writer.write_step(values);
  writer.commit();
  const auto series = io::open_hdf5_series(file);
  BrickCache cache(*series, CacheOptions{});
  StreamedField field(cache);
  REQUIRE_FALSE(series->zero_is_no_data());
  GridFieldOptions go;
  go.zero_is_no_data = false;
  const GridField memory(std::make_shared<VectorGrid>(io::read_hdf5_grid(file)), go);
  std::size_t no_data = 0, checked = 0;
  for (std::int64_t k = 0; k + 1 < g.size[2]; ++k)
    for (std::int64_t j = 0; j + 1 < g.size[1]; ++j)
      for (std::int64_t i = 0; i + 1 < g.size[0]; ++i)
        for (const double f : {0.0, 0.5, 1.0}) {
          const Vec3 x(g.coordinate(0, i) + f * g.spacing.x(), g.coordinate(1, j) + f * g.spacing.y(),
                       g.coordinate(2, k) + f * g.spacing.z());
          Vec3 v_streamed, v_memory;
          const FieldStatus streamed = field.velocity(x, 0.5, v_streamed);
          INFO("cell " << i << " " << j << " " << k << ", fraction " << f);
          REQUIRE(streamed == memory.velocity(x, v_memory));
          ++checked;
          if (streamed == FieldStatus::no_data) ++no_data;
        }
  CHECK(checked == 3 * 10 * 8 * 6);
  // Each bad sample takes the cells around it: their inner points, and points on their faces.
  CHECK(no_data >= 3 * 8);
}

TEST_CASE("locate_time finds the interval upper_bound finds: even and uneven steps, the ends and repeats",
          "[spacetime]") {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const std::vector<std::vector<double>> series = {
      {0, 1},
      {0, 0.5, 1, 1.5, 2, 2.5},
      {1e9, 1e9 + 3600, 1e9 + 7200, 1e9 + 10800},
      {0, 0.001, 0.002, 5, 9, 10, 10.5, 40},  // uneven: the walk gives way to the search
      {0, 1, 1, 2, 3},                        // a repeated time
  };
  for (const auto& times : series) {
    std::vector<double> probes = times;
    for (int i = 0; i < 200; ++i) probes.push_back(times.front() + unit(rng) * (times.back() - times.front()));
    for (const double t : probes) {
      const auto it = std::upper_bound(times.begin(), times.end(), t);
      const std::size_t want = std::min(
          static_cast<std::size_t>(std::max<std::ptrdiff_t>(it - times.begin() - 1, 0)), times.size() - 2);
      std::size_t k = 99;
      double w = -1;
      REQUIRE(locate_time(times, t, k, w));
      CHECK(k == want);
      CHECK(w == (t - times[want]) / (times[want + 1] - times[want]));
    }
    std::size_t k = 0;
    double w = 0;
    CHECK_FALSE(locate_time(times, times.front() - 1e-3, k, w));
    CHECK_FALSE(locate_time(times, times.back() + 1e-3, k, w));
    CHECK_FALSE(locate_time(times, std::nan(""), k, w));
  }
}
