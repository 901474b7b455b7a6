#pragma once
/// Writes files under a temporary name and renames them when complete, so a crash or an error
/// never leaves a truncated file that looks finished.
#include <filesystem>
#include <fstream>
#include <functional>
#include <utility>
#include <vector>

namespace orthofront::io {

/// Every writer below refuses (IoError naming `path`) a path that is a symbolic link, a device,
/// a pipe, a socket or a directory, or that names a file this process reads its data from
/// (io/input_files.h): outputs are regular files, and never an input.
///
/// Calls `write(stream)` on a binary stream opened on "<path>.tmp-<pid>", then flushes, checks the
/// stream and renames onto `path`. On any failure (including an exception from `write`) the
/// temporary file is removed and IoError is thrown naming `path` and the cause (the system's
/// error, and on a full disk the bytes left there). The directory must exist.
void write_atomically(const std::filesystem::path& path,
                      const std::function<void(std::ofstream&)>& write);

/// Files that belong together (a mesh and its report), replaced as a set: each is written in
/// full to its temporary by add(); commit() then renames them all. A failure in any add() (or
/// a set destroyed before commit) removes every temporary and replaces no file, so the folder
/// never holds a new file beside an old one of the same set.
class AtomicFileSet {
 public:
  AtomicFileSet() = default;
  ~AtomicFileSet();  ///< removes the temporaries of a set not committed
  AtomicFileSet(const AtomicFileSet&) = delete;
  AtomicFileSet& operator=(const AtomicFileSet&) = delete;

  /// Writes `path`'s content to its temporary, as write_atomically does, without the rename.
  /// Throws IoError naming `path` (and removes every temporary of the set) when the write fails
  /// or `path` is already in the set.
  void add(const std::filesystem::path& path, const std::function<void(std::ofstream&)>& write);

  /// Renames every temporary onto its file, in the order added. A rename that fails (not
  /// expected once the writes succeeded: the folders were writable) throws IoError naming the
  /// file; the files renamed before it stay replaced, the later ones are not.
  void commit();

 private:
  void discard() noexcept;
  std::vector<std::pair<std::filesystem::path, std::filesystem::path>> staged_;  // file, temporary
};

/// "<path>.tmp-<pid>": where a file is written before it is renamed onto `path`. Temporary files
/// of `path` left by processes that no longer run (killed mid-write) are removed first, so a
/// rerun cleans what a SIGKILL left.
std::filesystem::path temporary_path(const std::filesystem::path& path);

/// An exclusive lock on the folder of `path` (flock on the folder itself: nothing is left on
/// disk). A command holds it while it replaces the files that belong together (a mesh and its
/// report), so two runs writing the same outputs leave a matching set: the last one's.
class OutputLock {
 public:
  explicit OutputLock(const std::filesystem::path& path);
  ~OutputLock();
  OutputLock(const OutputLock&) = delete;
  OutputLock& operator=(const OutputLock&) = delete;

 private:
  int fd_ = -1;
};

/// Throws IoError naming `path` when its directory does not exist or is not writable, or when
/// `path` is one no writer replaces (see above).
void check_writable(const std::filesystem::path& path);

}  // namespace orthofront::io
