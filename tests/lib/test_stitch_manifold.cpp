// Regressions for non-manifold stream surfaces found by tools/soak.sh: faces stitched across a
// merge between two vertices that kept their old mesh vertices (abc), and a closed front merged
// down to two vertices (focus-sink). Each surface must be a manifold with no face written twice.
// Also the zero-area faces it found on abc: a fan of collinear triangles from a kept vertex, a
// new mesh vertex made on top of an existing one of its face, and a front run along one stream
// line where the seed parameter could no longer tell its vertices' stream lines apart.
#include <catch2/catch.hpp>
#include <algorithm>
#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "orthofront/engine/stream_surface.h"
#include "orthofront/field/analytic.h"
#include "orthofront/quality/quality.h"
#include "orthofront/seed/seed.h"

using namespace orthofront;

namespace {

struct Incidence {
  std::size_t over_shared_edges = 0;  ///< edges with more than two faces
  std::size_t repeated_faces = 0;     ///< faces whose vertex set an earlier face already has
};

/// Counts edge-face incidences and repeated vertex sets directly from the faces, independently of
/// measure_quality.
Incidence count_incidence(const Mesh& mesh) {
  std::map<std::pair<std::int32_t, std::int32_t>, int> edges;
  std::set<std::vector<std::int32_t>> seen;
  Incidence out;
  for (const Face& f : mesh.faces) {
    for (int k = 0; k < f.size; ++k) {
      std::int32_t a = f.v[static_cast<std::size_t>(k)];
      std::int32_t b = f.v[static_cast<std::size_t>((k + 1) % f.size)];
      if (a > b) std::swap(a, b);
      ++edges[{a, b}];
    }
    std::vector<std::int32_t> key(f.v.begin(), f.v.begin() + f.size);
    std::sort(key.begin(), key.end());
    if (!seen.insert(key).second) ++out.repeated_faces;
  }
  for (const auto& [edge, count] : edges)
    if (count > 2) ++out.over_shared_edges;
  return out;
}

void check_manifold(const SurfaceResult& r) {
  REQUIRE(r.mesh.face_count() > 100);
  const QualityReport q = measure_quality(r.mesh);
  CHECK(q.non_manifold_edges == 0);
  CHECK(q.inconsistent_edges == 0);
  CHECK(r.report.quality.non_manifold_edges == 0);
  const Incidence inc = count_incidence(r.mesh);
  CHECK(inc.over_shared_edges == 0);
  CHECK(inc.repeated_faces == 0);
}

}  // namespace

TEST_CASE("abc: no face is stitched twice across a merge between waiting vertices",
          "[engine][stitch]") {
  // Soak job: `stream --field abc --seed line:8.72851,0.252792,5.38944:2.8971,3.7232,9.39517
  // --seed-count 7 --edge 0.4316 --steps 165`. A fan from a waiting vertex left a front vertex
  // whose two front edges belonged to one triangle; merging that vertex away while both
  // neighbours kept their mesh vertices wrote the same triangle again, reversed.
  const auto field = make_analytic_field("abc");
  StreamSurfaceOptions o;
  o.edge = 0.4316;
  o.max_steps = 165;
  const auto seed = make_seed(SeedCurve::line(Vec3(8.72851, 0.252792, 5.38944),
                                              Vec3(2.8971, 3.7232, 9.39517)),
                              7);
  check_manifold(build_stream_surface<3>(*field, seed, o));
}

TEST_CASE("abc with vertex row skipping: manifold across merges", "[engine][stitch]") {
  // Soak job with --row-skip vertex (2 non-manifold edges before the fix).
  const auto field = make_analytic_field("abc");
  StreamSurfaceOptions o;
  o.edge = 0.3349;
  o.max_steps = 118;
  o.row_skip = RowSkip::vertex;
  const auto seed = make_seed(SeedCurve::line(Vec3(-2.07651, -0.954354, 4.93052),
                                              Vec3(5.17846, 7.73136, 5.32879)),
                              15);
  check_manifold(build_stream_surface<3>(*field, seed, o));
}

TEST_CASE("focus-sink: a closed front is not merged down to two vertices", "[engine][stitch]") {
  // Soak job: a circle around the sink's axis shrank to a closed front of two vertices, whose two
  // segments join the same pair, so each step's two quads shared both of their side edges.
  const auto field = make_analytic_field("focus-sink");
  StreamSurfaceOptions o;
  o.edge = 0.3803;
  o.max_steps = 82;
  o.integrator = IntegratorKind::rk4;
  // The stitch is the subject: the fold guard would end this front (five vertices around a
  // circle of radius 0.31 at ℓ = 0.38, a tube whose faces meet at more than 90°) at once.
  o.fold_guard = false;
  const auto seed = make_seed(SeedCurve::circle(Vec3(-3.35657, -2.17437, 2.33267),
                                                Vec3(0.247819, -0.280342, 0.369121), 0.310606),
                              36);
  const SurfaceResult r = build_stream_surface<3>(*field, seed, o);
  check_manifold(r);
  CHECK(r.report.closed_seed);
}

namespace {

/// No zero-area face (quality's definition), and still a manifold without T-junctions, on a
/// surface of more than `min_faces` faces.
void check_no_degenerate(const SurfaceResult& r, std::size_t min_faces = 1000) {
  REQUIRE(r.mesh.face_count() > min_faces);
  const QualityReport q = measure_quality(r.mesh);
  CHECK(q.degenerate_faces == 0);
  CHECK(r.report.quality.degenerate_faces == 0);
  CHECK(q.non_manifold_edges == 0);
  CHECK(q.inconsistent_edges == 0);
  CHECK(q.t_junctions == 0);
  const Incidence inc = count_incidence(r.mesh);
  CHECK(inc.over_shared_edges == 0);
  CHECK(inc.repeated_faces == 0);
}

}  // namespace

TEST_CASE("abc: no collinear fan from a kept vertex across vertices inserted in line with it",
          "[engine][stitch]") {
  // Soak job (seed 2, job 16): `stream --field abc --seed
  // line:1.70774,6.31526,9.72642:6.23884,2.72689,10.108 --seed-count 24 --edge 0.8607
  // --steps 342 --memory 64MiB`. On step 332 a front lying along one stream line had a first
  // vertex that kept its mesh vertex (α clamped to 0) and a long first segment, split by the
  // cubic fallback into vertices on one line with it; zipper fanned from the kept vertex across
  // them: a triangle with edges 2.83, 1.88 and 0.94 (ℓ = 0.86) and zero area.
  const auto field = make_analytic_field("abc");
  StreamSurfaceOptions o;
  o.edge = 0.8607;
  o.max_steps = 342;
  // The stitch is the subject, on a surface that folds over itself: the fold guard would end it
  // within a few dozen steps (see the fold guard's test below).
  o.fold_guard = false;
  const auto seed = make_seed(SeedCurve::line(Vec3(1.70774, 6.31526, 9.72642),
                                              Vec3(6.23884, 2.72689, 10.108)),
                              24);
  check_no_degenerate(build_stream_surface<3>(*field, seed, o));
}

TEST_CASE("abc with linear insertion: no collinear fans at either end of a chain",
          "[engine][stitch]") {
  // Soak job (seed 4, job 51) with --insertion linear: 34 zero-area triangles before, fans from
  // a kept vertex at the start or at the end of a split segment.
  const auto field = make_analytic_field("abc");
  StreamSurfaceOptions o;
  o.edge = 0.4724;
  o.max_steps = 144;
  o.insertion = Insertion::linear;
  const auto seed = make_seed(SeedCurve::line(Vec3(-3.90083, -1.08281, -0.74432),
                                              Vec3(3.63385, -1.5148, 6.38269)),
                              32);
  check_no_degenerate(build_stream_surface<3>(*field, seed, o));
}

TEST_CASE("abc: no new mesh vertex on top of a mesh vertex of its own faces", "[engine][stitch]") {
  // Soak job (seed 5, job 7): `stream --field abc --seed
  // circle:-0.294639,-1.11774,2.57763:0.803721,-0.774879,0.64411:2.1236:open --seed-count 14
  // --edge 0.7794 --steps 260`. A stalled front folded onto one stream line cycled with a period
  // of 7 steps: a vertex renewed by row smoothing came back within 5e-7 and less of the mesh
  // vertex its waiting neighbour kept from 7 steps before, and the face across them had two
  // coincident corners (11 degenerate faces, 2 T-junctions).
  const auto field = make_analytic_field("abc");
  StreamSurfaceOptions o;
  o.edge = 0.7794;
  o.max_steps = 260;
  // The stitch is the subject, on a surface that folds over itself: the fold guard would end it
  // within a few dozen steps (see the fold guard's test below).
  o.fold_guard = false;
  const auto seed = make_seed(SeedCurve::circle(Vec3(-0.294639, -1.11774, 2.57763),
                                                Vec3(0.803721, -0.774879, 0.64411), 2.1236, true),
                              14);
  check_no_degenerate(build_stream_surface<3>(*field, seed, o));
}

TEST_CASE("abc with negative alpha kept: no front along one stream line where the seed "
          "parameter runs out",
          "[engine][stitch]") {
  // Soak job (seed 11, job 162): `stream --field abc --seed
  // line:2.73419,7.32986,5.6956:-2.01563,3.59467,1.83745 --seed-count 35 --edge 0.8906
  // --steps 357 --negative-alpha keep`. Near a separating stream line the seed interval between
  // neighbouring front vertices halved every step until, on step 24, vertices were inserted with
  // the seed parameter of an end. From then on the front ran along that one stream line, growing
  // by three vertices a step, and settled into a cycle that each step inserted new mesh vertices
  // exactly on the previous step's: 584 zero-area faces and 941 T-junctions. Such a segment is
  // now cut instead of split.
  const auto field = make_analytic_field("abc");
  StreamSurfaceOptions o;
  o.edge = 0.8906;
  o.max_steps = 357;
  o.negative_alpha = NegativeAlpha::keep;
  // The stitch is the subject, on a surface that folds over itself: the fold guard would end it
  // within a few dozen steps (see the fold guard's test below).
  o.fold_guard = false;
  const auto seed = make_seed(SeedCurve::line(Vec3(2.73419, 7.32986, 5.6956),
                                              Vec3(-2.01563, 3.59467, 1.83745)),
                              35);
  const SurfaceResult r = build_stream_surface<3>(*field, seed, o);
  // How long this folding surface lasts before its fronts are cut away depends on every
  // integration's rounding (932 faces in 81 steps since DOPRI5 stopped growing a step right
  // after a rejection; 13,130 in 357 steps before): the checks hold either way.
  check_no_degenerate(r, 500);
  // No stream line carries a mesh vertex on a large share of the rows (before: 3981 of 4268
  // vertices had one seed parameter).
  std::map<double, std::size_t> per_line;
  for (const double s : r.mesh.s) ++per_line[s];
  std::size_t most = 0;
  for (const auto& [s, count] : per_line) most = std::max(most, count);
  CHECK(most <= static_cast<std::size_t>(r.report.steps) + 1);
}

TEST_CASE("abc: the fold guard leaves no fold, and rips the front only where it folded",
          "[engine][stitch][fold]") {
  // `stream --field abc --seed line:0,0,1:3,3,1 --edge 0.1 --steps 300`: 637 folds without the
  // guard, where the front crosses the flow's separating surfaces.
  const auto field = make_analytic_field("abc");
  StreamSurfaceOptions o;
  o.edge = 0.1;
  o.max_steps = 300;
  const auto seed = make_seed(SeedCurve::line(Vec3(0, 0, 1), Vec3(3, 3, 1)), 20);
  o.fold_guard = false;
  const SurfaceResult unguarded = build_stream_surface<3>(*field, seed, o);
  o.fold_guard = true;
  const SurfaceResult r = build_stream_surface<3>(*field, seed, o);
  REQUIRE(unguarded.report.quality.folds > 100);
  check_no_degenerate(r);
  CHECK(measure_quality(r.mesh).folds == 0);
  CHECK(r.report.fold_rips > 0);
  CHECK(r.report.folds_left == 0);
  // A local repair: the surface keeps nearly all of its extent.
  CHECK(r.mesh.vertex_count() > 0.9 * static_cast<double>(unguarded.mesh.vertex_count()));
  // Every vertex is used by a face (vertices the guard took out are removed from the mesh).
  std::vector<char> used(r.mesh.vertex_count(), 0);
  for (const Face& f : r.mesh.faces)
    for (int k = 0; k < f.size; ++k) used[static_cast<std::size_t>(f.v[static_cast<std::size_t>(k)])] = 1;
  CHECK(std::count(used.begin(), used.end(), 0) == 0);
}
