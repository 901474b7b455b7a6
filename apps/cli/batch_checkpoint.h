#pragma once
/// Checkpoint files of a batch job, in OUT/.checkpoint/: NAME.state (an unfinished surface's
/// state between front steps) and NAME.done (a finished surface's summary row). Each is written
/// to a temporary and renamed, so a kill at any point leaves the previous file or the new one.
/// Both carry the program version and the job's digest: another version's or another job's
/// checkpoint is refused by name. inputs-RANK.json hold the fingerprints of the data files the job has
/// read: a job is not resumed over data that changed since.
#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "orthofront/engine/surface_builder.h"
#include "orthofront/spacetime/path_surface.h"

namespace orthofront::cli {

/// The version a checkpoint must come from (project version and state format).
std::string checkpoint_version();

using SurfaceState = std::variant<EngineState<3>, spacetime::PathState>;

class CheckpointFolder {
 public:
  CheckpointFolder(std::filesystem::path folder, std::uint64_t job_digest);

  const std::filesystem::path& folder() const { return folder_; }
  bool exists() const;
  /// Creates the folder and records the job it belongs to (job.id).
  void start();
  /// Throws InvalidArgument when the folder belongs to another job or version (naming both).
  void check_owner() const;
  /// Removes every file of the folder (a fresh run over an old checkpoint).
  void clear();

  void save_state(const std::string& surface, const SurfaceState& state) const;
  /// Nothing when the surface has no state file; throws io::FormatError naming the file for a
  /// corrupt one and InvalidArgument for one of another job or version.
  std::optional<SurfaceState> load_state(const std::string& surface) const;
  void remove_state(const std::string& surface) const;

  /// Records the fingerprints (size, modification time, CRC-32 of the first and last 64 KiB)
  /// of `inputs` not yet recorded, in inputs-RANK.json (one file per MPI rank).
  void record_inputs(const std::vector<std::filesystem::path>& inputs, int rank) const;
  /// Throws InvalidArgument naming the first recorded input (of any rank) that is gone or has
  /// changed.
  void check_inputs() const;

  void save_done(const std::string& surface, const nlohmann::json& row) const;
  std::optional<nlohmann::json> load_done(const std::string& surface) const;

 private:
  std::filesystem::path file(const std::string& surface, const char* ext) const;
  void check_inputs(const std::filesystem::path& recorded) const;
  std::filesystem::path folder_;
  std::uint64_t digest_;
};

}  // namespace orthofront::cli
