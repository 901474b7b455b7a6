#include "orthofront/spacetime/spacetime_streak.h"

#include <cmath>
#include <cstdio>
#include <set>

#include "orthofront/error.h"
#include "orthofront/spacetime/lifted_field.h"

namespace orthofront::spacetime {

namespace {

std::string number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", value);
  return text;
}

}  // namespace

SpacetimeStreakResult build_spacetime_streak_surface(const UnsteadyField& flow, const Vec3& x0,
                                                     const SpacetimeStreakOptions& o) {
  if (flow.dimension() != 2)
    throw InvalidArgument("the space-time streak surface needs a 2D flow; '" + flow.describe() +
                          "' is " + std::to_string(flow.dimension()) + "D");
  if (!(o.release_end > o.release_begin && o.t_end > o.release_begin &&
        std::isfinite(o.release_begin) && std::isfinite(o.t_end) && std::isfinite(o.release_end)))
    throw InvalidArgument("release " + number(o.release_begin) + ":" + number(o.release_end) +
                          " and end time " + number(o.t_end) + " must be finite and increasing");
  if (o.seed_count < 2)
    throw InvalidArgument("seed count must be at least 2, got " + std::to_string(o.seed_count));
  double c = o.time_scale;
  if (c <= 0) {
    double sum = 0;
    int n = 0;
    for (int i = 0; i <= 16; ++i) {
      Vec3 v;
      const double t = o.release_begin + (o.release_end - o.release_begin) * i / 16.0;
      if (flow.velocity(x0, t, v) != FieldStatus::inside)
        throw InvalidArgument("seed point (" + number(x0.x()) + ", " + number(x0.y()) +
                              ") lies outside the domain of " + flow.describe() + " at t = " +
                              number(t));
      v.z() = 0;
      sum += v.norm();
      ++n;
    }
    c = sum / n;
    if (!(c > 0))
      throw InvalidArgument("the flow is zero at the seed point (" + number(x0.x()) + ", " +
                            number(x0.y()) + ") over the release interval: nothing leaves it");
  }
  const LiftedField<3> lifted(flow, c, TimeRange{o.release_begin, o.t_end});
  const double t_lo = o.release_begin, t_hi = std::min(o.release_end, o.t_end);
  Seed<3> seed;
  seed.point = [&](double s) {
    return Vec3(x0.x(), x0.y(), c * (t_lo + s * (t_hi - t_lo)));
  };
  for (int i = 0; i < o.seed_count; ++i) seed.parameters.push_back(static_cast<double>(i) / (o.seed_count - 1));
  SpacetimeStreakResult out;
  out.time_scale = c;
  SurfaceResult sr = build_stream_surface<3>(lifted, seed, o.engine);
  out.mesh = std::move(sr.mesh);
  out.report = sr.report;
  // Report positions in (x, y, t) and each vertex's physical time.
  out.mesh.time.resize(out.mesh.vertex_count());
  for (std::size_t i = 0; i < out.mesh.vertex_count(); ++i) {
    out.mesh.positions[i].z() /= c;
    out.mesh.time[i] = out.mesh.positions[i].z();
  }
  return out;
}

std::vector<Vec3> slice_at_time(const Mesh& mesh, double t_f) {
  std::set<std::pair<std::int32_t, std::int32_t>> seen;
  std::vector<Vec3> points;
  for (const Face& f : mesh.faces)
    for (int k = 0; k < f.size; ++k) {
      std::int32_t a = f.v[k], b = f.v[(k + 1) % f.size];
      if (a > b) std::swap(a, b);
      if (!seen.insert({a, b}).second) continue;
      const Vec3& p = mesh.positions[static_cast<std::size_t>(a)];
      const Vec3& q = mesh.positions[static_cast<std::size_t>(b)];
      if ((p.z() - t_f) * (q.z() - t_f) > 0 || p.z() == q.z()) continue;
      const double w = (t_f - p.z()) / (q.z() - p.z());
      points.push_back(p + w * (q - p));
    }
  return points;
}

}  // namespace orthofront::spacetime
