#pragma once
/// A batch job file (TOML or JSON): the data set, defaults, and the surfaces to build, with
/// generated families (a rake of seed lines, a grid of them, a sweep over t0). See
/// docs/batch.md for the keys.
#include <cstdint>
#include <filesystem>
#include <set>
#include <string>
#include <vector>

#include "orthofront/engine/options.h"
#include "orthofront/types.h"

namespace orthofront::cli {

enum class SurfaceKind { stream, path, streak };

/// One surface of a job, with every default applied and every family expanded.
struct SurfaceSpec {
  std::string name;                 ///< unique in the job; names the outputs NAME.vtp, NAME.json
  SurfaceKind kind = SurfaceKind::path;
  std::string field;                ///< as --field takes it
  std::string seed;                 ///< as --seed takes it
  Vec3 offset = Vec3::Zero();       ///< families move the seed curve by this
  int seed_count = 20;
  double t0 = 0, t1 = 1;            ///< path
  double time_scale = 0, max_band = 0;
  StreamSurfaceOptions options;
  std::string format = "vtp";       ///< vtp, ply or obj (streak surfaces: a .pvd animation)
  // Streak surfaces, as `streak` takes them.
  std::string release;              ///< "T0:T1"
  std::string frames;               ///< "START:END:COUNT" or "t1,t2,..."
  double split = 1.5, merge = 0.5, release_step = 0;
  int releases_per_break = 1;
  std::string insertion_key = "insertion";  ///< the key it was given under (streak: insert)
  std::string insertion;            ///< as given (stream/path: streamline|cubic|linear; streak: exact|interpolate)
  bool steps_given = false;
  bool seed_count_given = false;    ///< else 20 (stream, path) or derived from ℓ (streak), as the commands
  bool max_vertices_given = false;  ///< else the memory available decides (not part of the digest)         ///< else stream surfaces take `stream`'s 100, path ones run to t1
  int line = 0;                     ///< where the job file defines it (0: unknown)
};

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

const char* to_string(SurfaceKind kind);

/// The keys a surface of a job file takes, besides a family's own: the kinds' option names
/// with '_' for '-' (jobs/*_job.h), and the job's own name, kind, field, seed and format.
const std::set<std::string>& batch_surface_keys();

}  // namespace orthofront::cli
