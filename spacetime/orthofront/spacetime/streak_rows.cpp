#include "orthofront/spacetime/streak_rows.h"

#include <tbb/parallel_invoke.h>

#include <cmath>

namespace orthofront::spacetime {

namespace {

// Resizes a frame's array to n elements. One that must grow is first emptied (nothing of it is
// kept: every element is written anew) and reserved anew, so that a frame several times larger
// than the last is not copied over (the mesh's arrays take their huge pages from their
// allocator).
template <class T, class Allocator>
void grow(std::vector<T, Allocator>& values, std::size_t n) {
  if (values.capacity() < n) {
    std::vector<T, Allocator>().swap(values);
    values.reserve(n + n / 4);  // room for the next frame to grow a little
  }
  values.resize(n);
}

}  // namespace

std::size_t particle_count(const std::vector<StreakRow>& rows) {
  std::size_t n = 0;
  for (const StreakRow& r : rows) n += r.p.size();
  return n;
}

double row_distance(const StreakRow& a, const StreakRow& b, const LengthLimit& stop) {
  // A merge by s without branches on it (rows drift apart in s, so they would be mispredicted).
  const double beyond = stop.above_squared();
  double d = 0;
  std::size_t i = 0, k = 0;
  const std::size_t na = a.p.size(), nb = b.p.size();
  while (i < na && k < nb) {
    const StreakParticle& pa = a.p[i];
    const StreakParticle& pb = b.p[k];
    const double q = (pa.x - pb.x).squaredNorm();
    const bool pair = pa.s == pb.s && pa.alive() && pb.alive();
    d = pair && q > d ? q : d;
    if (d > beyond) break;
    i += pa.s <= pb.s;
    k += pb.s <= pa.s;
  }
  return std::sqrt(d);  // the largest root is the root of the largest square, bit for bit
}

std::size_t mesh_rows(const std::vector<StreakRow>& rows, bool closed, double t,
                      const UnsteadyField& flow, Mesh& mesh) {
  // Vertices and faces are counted first (a row's live particles numbered from 0, and the faces
  // of the strips, which need only which particles live), so that every array is sized at once,
  // side by side, and the rows and strips then fill them in parallel at offsets counted before.
  const std::size_t nr = rows.size();
  const std::size_t strips = nr > 0 ? nr - 1 : 0;
  // [r][i]: particle i's vertex, -1 where it stopped (its number within the row until the vertex
  // pass below adds the row's first vertex).
  std::vector<std::vector<std::int32_t>> vertex(nr);
  std::vector<std::size_t> first(nr + 1, 0);
  for_each_row(nr, [&](std::size_t r) {
    const std::vector<StreakParticle>& p = rows[r].p;
    vertex[r].resize(p.size());
    std::int32_t v = 0;
    for (std::size_t i = 0; i < p.size(); ++i) vertex[r][i] = p[i].alive() ? v++ : -1;
    first[r + 1] = static_cast<std::size_t>(v);
  });
  std::vector<std::size_t> first_face(strips + 1, 0);
  for_each_row(strips, [&](std::size_t r) {
    std::size_t n = 0;
    for_each_strip_face(rows[r], rows[r + 1], closed, vertex[r], vertex[r + 1], [&n](const Face&) { ++n; });
    first_face[r + 1] = n;
  });
  std::size_t dead = 0;
  for (std::size_t r = 0; r < nr; ++r) {
    dead += rows[r].p.size() - first[r + 1];
    first[r + 1] += first[r];
  }
  for (std::size_t r = 0; r < strips; ++r) first_face[r + 1] += first_face[r];
  const std::size_t nv = first[nr];
  // Side by side: an array that must grow is zero-filled anew (see grow()), one thread each.
  tbb::parallel_invoke([&] { grow(mesh.positions, nv); }, [&] { grow(mesh.s, nv); },
                       [&] { grow(mesh.release_time, nv); }, [&] { grow(mesh.age, nv); },
                       [&] { grow(mesh.speed, nv); }, [&] { grow(mesh.particle_id, nv); },
                       [&] { grow(mesh.faces, first_face.back()); });
  const bool planar = flow.dimension() == 2;
  for_each_row(nr, [&](std::size_t r) {
    const StreakRow& row = rows[r];
    const auto offset = static_cast<std::int32_t>(first[r]);
    for (std::size_t i = 0; i < row.p.size(); ++i) {
      const StreakParticle& p = row.p[i];
      if (!p.alive()) continue;
      const auto v = static_cast<std::size_t>(vertex[r][i] += offset);
      mesh.positions[v] = p.x;
      mesh.s[v] = p.s;
      mesh.release_time[v] = row.tau;
      mesh.age[v] = t - row.tau;
      Vec3 u = Vec3::Zero();
      if (flow.velocity(p.x, t, u) != FieldStatus::inside) u.setZero();
      if (planar) u.z() = 0;
      mesh.speed[v] = u.norm();
      mesh.particle_id[v] = p.id;
    }
  });
  for_each_row(strips, [&](std::size_t r) {
    Face* out = mesh.faces.data() + first_face[r];
    for_each_strip_face(rows[r], rows[r + 1], closed, vertex[r], vertex[r + 1],
                        [&out](const Face& f) { *out++ = f; });
  });
  return dead;
}

}  // namespace orthofront::spacetime
