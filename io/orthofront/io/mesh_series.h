#pragma once
/// A time series of meshes written as a ParaView collection: NAME.pvd beside a folder NAME/ of
/// frames NAME_0000.vtp, NAME_0001.vtp, ... Each frame is written atomically, then the .pvd is
/// replaced (atomically) by one listing exactly the frames written so far, so an interrupted run
/// leaves a collection that ParaView plays up to its last complete frame and no entry without
/// its file.
#include <filesystem>
#include <string>
#include <vector>

#include "orthofront/mesh/mesh.h"

namespace orthofront::io {

class MeshSeriesWriter {
 public:
  /// `pvd` must end in .pvd and its folder must exist and be writable (IoError /
  /// InvalidArgument naming it otherwise). The frame folder is made now and locked for the
  /// writer's life: a second writer of the same collection (another run) is refused with
  /// IoError, so two runs never mix their frames. No frame is written until the first.
  explicit MeshSeriesWriter(std::filesystem::path pvd);
  ~MeshSeriesWriter();
  MeshSeriesWriter(const MeshSeriesWriter&) = delete;
  MeshSeriesWriter& operator=(const MeshSeriesWriter&) = delete;

  /// Writes `mesh` as the next frame at `time` (times must increase), then the .pvd. Returns the
  /// frame's path. Throws IoError naming the file on a failed write (the .pvd then still lists
  /// only the frames before this one).
  std::filesystem::path add_frame(const Mesh& mesh, double time);
  /// Notes every frame carries where its mesh has none of its own (Mesh::notes).
  void set_notes(std::vector<std::pair<std::string, std::string>> notes) { notes_ = std::move(notes); }

  const std::filesystem::path& pvd() const { return pvd_; }
  const std::filesystem::path& frame_folder() const { return folder_; }
  std::size_t frames() const { return entries_.size(); }

 private:
  struct Entry {
    double time;
    std::string file;  // relative to the .pvd's folder
  };
  void write_collection() const;
  std::filesystem::path pvd_, folder_;
  std::string name_;
  std::vector<Entry> entries_;
  std::vector<std::pair<std::string, std::string>> notes_;
  int lock_ = -1;         // the frame folder, flock'ed
  bool made_folder_ = false;  // removed again if no frame was written
};

}  // namespace orthofront::io
