#pragma once
/// The surface kinds and each one's option schema bound to arguments of its own: where a front
/// end that takes options by name (job files, Python keywords) meets the kinds. A new kind adds
/// its enumerator and its case in surface_kind.cpp.
#include <optional>
#include <string>

#include "jobs/engine_options.h"
#include "jobs/option_set.h"
#include "jobs/path_job.h"
#include "jobs/streak_job.h"
#include "jobs/stream_job.h"

namespace orthofront::jobs {

enum class SurfaceKind { stream, path, streak };

/// Every kind, in the order help pages list them.
inline constexpr SurfaceKind kSurfaceKinds[] = {SurfaceKind::stream, SurfaceKind::path,
                                                SurfaceKind::streak};

/// "stream", "path" or "streak".
const char* to_string(SurfaceKind kind);
/// The kind `name` names, or none.
std::optional<SurfaceKind> parse_surface_kind(const std::string& name);

/// A kind's options (its command's flags) bound to that kind's arguments, which only the kind's
/// own member holds; the set refers to them, so the binding is neither copied nor moved.
class KindOptions {
 public:
  explicit KindOptions(SurfaceKind kind);
  KindOptions(const KindOptions&) = delete;
  KindOptions& operator=(const KindOptions&) = delete;

  SurfaceKind kind;
  OptionSet set;
  SurfaceJob stream;           ///< kind stream
  MemoryLimits stream_limits;  ///< kind stream
  PathArgs path;               ///< kind path
  StreakArgs streak;           ///< kind streak
};

}  // namespace orthofront::jobs
