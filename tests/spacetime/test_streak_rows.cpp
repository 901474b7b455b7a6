// The rows of a streak surface: the strips between neighbouring rows, the distance of two rows
// and the mesh of a set of rows.
#include <catch2/catch.hpp>

#include <vector>

#include "orthofront/field/unsteady.h"
#include "orthofront/spacetime/streak_rows.h"

using namespace orthofront;
using namespace orthofront::spacetime;

namespace {

// A row at τ of particles at s, placed at (s, τ, 0).
StreakRow row(double tau, const std::vector<double>& s) {
  StreakRow r;
  r.tau = tau;
  for (const double v : s) {
    StreakParticle p;
    p.s = v;
    p.x = Vec3(v, tau, 0);
    r.p.push_back(p);
  }
  return r;
}

std::vector<std::int32_t> numbered(const StreakRow& r, std::int32_t first) {
  std::vector<std::int32_t> v(r.p.size());
  for (std::size_t i = 0; i < v.size(); ++i) v[i] = first + static_cast<std::int32_t>(i);
  return v;
}

std::vector<Face> strip(const StreakRow& a, const StreakRow& b, bool closed,
                        const std::vector<std::int32_t>& va, const std::vector<std::int32_t>& vb) {
  std::vector<Face> faces;
  for_each_strip_face(a, b, closed, va, vb, [&](const Face& f) { faces.push_back(f); });
  return faces;
}

Face quad(std::int32_t a, std::int32_t b, std::int32_t c, std::int32_t d) { return Face{{a, b, c, d}, 4}; }
Face triangle(std::int32_t a, std::int32_t b, std::int32_t c) { return Face{{a, b, c, -1}, 3}; }

}  // namespace

TEST_CASE("streak rows: a particle's slot and status share a word without touching each other",
          "[spacetime][streak]") {
  StreakParticle p;
  CHECK(p.alive());
  CHECK(p.slot() == kNoSlot);
  p.set_slot(12345);
  CHECK(p.slot() == 12345);
  CHECK(p.alive());
  p.set_status(advect::ParticleStatus::no_data);
  CHECK(p.slot() == 12345);
  CHECK(p.status() == advect::ParticleStatus::no_data);
  CHECK_FALSE(p.alive());
  p.set_slot(StreakParticle::kSlots - 1);
  CHECK(p.slot() == StreakParticle::kSlots - 1);
  CHECK(p.status() == advect::ParticleStatus::no_data);
  p.set_slot(kNoSlot);
  CHECK(p.slot() == kNoSlot);
  p.set_status(advect::ParticleStatus::moving);
  CHECK(p.alive());
}

TEST_CASE("streak rows: rows sharing their s give quads, an s of one row only, a triangle",
          "[spacetime][streak]") {
  const StreakRow a = row(0, {0, 0.5, 1});
  const StreakRow b = row(1, {0, 0.25, 0.5, 1});
  const auto va = numbered(a, 0), vb = numbered(b, 3);
  // a: 0 1 2 at s = 0, 0.5, 1; b: 3 4 5 6 at s = 0, 0.25, 0.5, 1.
  CHECK(strip(a, b, false, va, vb) == std::vector<Face>{triangle(0, 4, 3), quad(0, 1, 5, 4), quad(1, 2, 6, 5)});
  CHECK(strip(a, a, false, va, numbered(a, 3)) == std::vector<Face>{quad(0, 1, 4, 3), quad(1, 2, 5, 4)});
  // Closed rows close up: the last particles join the first.
  CHECK(strip(a, a, true, va, numbered(a, 3)) ==
        std::vector<Face>{quad(0, 1, 4, 3), quad(1, 2, 5, 4), quad(2, 0, 3, 5)});
  // A stopped particle (-1) takes its faces with it.
  std::vector<std::int32_t> vb_stopped = vb;
  vb_stopped[1] = -1;
  CHECK(strip(a, b, false, va, vb_stopped) == std::vector<Face>{quad(1, 2, 6, 5)});
}

TEST_CASE("streak rows: the distance of two rows is over the live particles they share in s",
          "[spacetime][streak]") {
  StreakRow a = row(0, {0, 0.5, 1});
  StreakRow b = row(0, {0, 0.25, 0.5, 1});
  b.p[0].x.y() = 2;   // 2 from a's particle at s = 0
  b.p[1].x.y() = 9;   // s = 0.25: a has none
  b.p[2].x.y() = 3;   // 3 from a's at s = 0.5
  const LengthLimit far(100);
  CHECK(row_distance(a, b, far) == 3);
  a.p[1].set_status(advect::ParticleStatus::left_domain);
  CHECK(row_distance(a, b, far) == 2);
  // Once a pair is beyond the limit for certain the search stops there.
  CHECK(row_distance(a, b, LengthLimit(1)) == 2);
}

TEST_CASE("streak rows: the mesh of the rows numbers live particles row after row",
          "[spacetime][streak]") {
  const auto flow = make_unsteady_field("double-gyre");
  std::vector<StreakRow> rows{row(0, {0.1, 0.5, 0.9}), row(0.25, {0.1, 0.3, 0.5, 0.9})};
  for (StreakRow& r : rows)
    for (StreakParticle& p : r.p) p.id = static_cast<std::int32_t>(100 * r.tau + 10 * p.s);
  rows[1].p[3].set_status(advect::ParticleStatus::left_domain);
  Mesh mesh;
  const std::size_t dead = mesh_rows(rows, false, 1.0, *flow, mesh);
  CHECK(dead == 1);
  REQUIRE(mesh.vertex_count() == 6);
  CHECK(mesh.positions[4] == Vec3(0.3, 0.25, 0));
  CHECK(mesh.s[5] == 0.5);
  CHECK(mesh.release_time[3] == 0.25);
  CHECK(mesh.age[3] == 0.75);
  CHECK(mesh.particle_id[4] == static_cast<std::int32_t>(100 * 0.25 + 10 * 0.3));
  Vec3 u;
  REQUIRE(flow->velocity(mesh.positions[1], 1.0, u) == FieldStatus::inside);
  u.z() = 0;
  CHECK(mesh.speed[1] == u.norm());
  // Vertices 0 1 2 | 3 4 5 (the particle at s = 0.9 of the second row stopped).
  CHECK(std::vector<Face>(mesh.faces.begin(), mesh.faces.end()) ==
        std::vector<Face>{triangle(0, 4, 3), quad(0, 1, 5, 4)});
  // Reused for a smaller frame: the arrays shrink to it.
  rows.pop_back();
  CHECK(mesh_rows(rows, false, 1.0, *flow, mesh) == 0);
  CHECK(mesh.vertex_count() == 3);
  CHECK(mesh.face_count() == 0);
  CHECK(particle_count(rows) == 3);
}
