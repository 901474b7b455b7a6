// Uses each installed library once: a stream surface (lib), written and read back (io), and a
// streak surface (spacetime). Prints "stream V F, read V, streak V" and exits 0 when they agree.
#include <cstdio>
#include <filesystem>

#include "orthofront/engine/stream_surface.h"
#include "orthofront/field/analytic.h"
#include "orthofront/field/unsteady.h"
#include "orthofront/io/mesh_io.h"
#include "orthofront/seed/seed.h"
#include "orthofront/spacetime/streak_surface.h"

int main(int argc, char** argv) {
  using namespace orthofront;
  if (argc != 2) return 2;
  const auto field = make_analytic_field("sinus");
  StreamSurfaceOptions options;
  options.edge = 0.1;
  options.max_steps = 20;
  const SeedCurve line = SeedCurve::line(Vec3(-1, 0, 0), Vec3(1, 0, 0));
  const SurfaceResult surface = build_stream_surface<3>(*field, make_seed(line, 20), options);
  const std::filesystem::path out = std::filesystem::path(argv[1]) / "sinus.vtp";
  io::write_mesh(surface.mesh, out);
  const Mesh back = io::read_mesh(out);

  const auto gyre = make_unsteady_field("double-gyre");
  spacetime::StreakOptions streak;
  streak.mesh = spacetime::StreakMesh::remeshed;
  streak.release_end = 1;
  streak.frames = {1};
  streak.edge = 0.02;
  std::size_t streak_vertices = 0;
  spacetime::build_streak_surface(
      *gyre, SeedCurve::line(Vec3(0.3, 0.3, 0), Vec3(0.3, 0.45, 0)), streak,
      [&](const spacetime::StreakFrame& f) { streak_vertices = f.mesh.vertex_count(); });
  std::printf("stream %zu %zu, read %zu, streak %zu\n", surface.mesh.vertex_count(),
              surface.mesh.face_count(), back.vertex_count(), streak_vertices);
  const bool ok = surface.mesh.face_count() > 0 && back.vertex_count() == surface.mesh.vertex_count() &&
                  streak_vertices > 0;
  return ok ? 0 : 1;
}
