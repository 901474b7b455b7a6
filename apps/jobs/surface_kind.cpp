#include "jobs/surface_kind.h"

namespace orthofront::jobs {

const char* to_string(SurfaceKind kind) {
  switch (kind) {
    case SurfaceKind::stream:
      return "stream";
    case SurfaceKind::path:
      return "path";
    case SurfaceKind::streak:
      return "streak";
  }
  return "?";
}

std::optional<SurfaceKind> parse_surface_kind(const std::string& name) {
  for (const SurfaceKind kind : kSurfaceKinds)
    if (name == to_string(kind)) return kind;
  return std::nullopt;
}

KindOptions::KindOptions(SurfaceKind k) : kind(k) {
  switch (kind) {
    case SurfaceKind::stream:
      add_stream_options(set, stream, stream_limits);
      break;
    case SurfaceKind::path:
      add_path_options(set, path);
      break;
    case SurfaceKind::streak:
      add_streak_options(set, streak);
      break;
  }
}

}  // namespace orthofront::jobs
