#pragma once
/// A batch job file (TOML or JSON): the data set, defaults, and the surfaces to build, with
/// generated families (a rake of seed lines, a grid of them, a sweep over t0). See
/// docs/batch.md for the keys.
#include <cstdint>
#include <filesystem>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "jobs/surface_kind.h"
#include "orthofront/types.h"

namespace orthofront::cli {

using jobs::SurfaceKind;
using jobs::to_string;

/// One surface of a job, with every default applied and every family expanded.
struct SurfaceSpec {
  std::string name;                 ///< unique in the job; names the outputs NAME.vtp, NAME.json
  SurfaceKind kind = SurfaceKind::path;
  std::string field;                ///< as --field takes it
  std::string seed;                 ///< as --seed takes it
  Vec3 offset = Vec3::Zero();       ///< families move the seed curve by this
  std::string format = "vtp";       ///< vtp, ply or obj (streak surfaces: a .pvd animation)
  /// The kind's options the job gives (the surface's own keys over [defaults]), by the option's
  /// name ("seed-count"), as the text the option parses. Each was checked against the kind's
  /// schema (jobs/*_job.h) when the file was read; what is not here takes the command's default.
  std::map<std::string, std::string> options;
  int line = 0;                     ///< where the job file defines it (0: unknown)

  bool given(const std::string& option) const { return options.count(option) > 0; }
};

/// The arguments of a stream surface's job: `stream`'s, with the spec's options applied.
jobs::SurfaceJob stream_arguments(const SurfaceSpec& spec);
/// A path surface's: `path`'s (t0 and t1 resolved: job files give them as numbers).
jobs::PathArgs path_arguments(const SurfaceSpec& spec);
/// A streak surface's library options, as `streak` makes them from its flags.
spacetime::StreakOptions streak_arguments(const SurfaceSpec& spec);

struct BatchJob {
  std::filesystem::path file;
  std::string name;
  std::filesystem::path out = "batch-out";  ///< output folder
  std::string cache_budget;         ///< bytes syntax; empty: a quarter of the memory available
  double checkpoint_every = 60;     ///< seconds between checkpoints (0: only on SIGTERM/SIGINT)
  std::vector<SurfaceSpec> surfaces;
  /// A digest of what the job computes (the expanded surfaces and the data), not of its text:
  /// a checkpoint is valid only for the job that wrote it.
  std::uint64_t digest = 0;
};

/// Reads and checks a job file. Throws InvalidArgument naming the file, the line and the key
/// (for example "job.toml:12: surface[2].edge: must be a number > 0, got -1"); io::IoError for
/// a file that cannot be read.
BatchJob read_batch_job(const std::filesystem::path& file);

/// The keys a surface of `kind` takes in a job file, besides a family's own: the kind's options
/// (jobs/*_job.h) with '_' for '-', less those a job sets for all its surfaces (batch_job_level),
/// and the job's own name, kind, field, seed and format. Benchmarks' baselines are accepted but
/// not listed.
std::set<std::string> batch_surface_keys(SurfaceKind kind);

/// Why a kind's option is not a surface key (it belongs to the whole job), or null when it is one.
const char* batch_job_level(SurfaceKind kind, const std::string& option);

}  // namespace orthofront::cli
