#include "orthofront/io/atomic_file.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <exception>
#include <string>
#include <system_error>

#include "orthofront/io/error.h"
#include "orthofront/io/input_files.h"

namespace orthofront::io {
namespace {

std::string errno_text(int err) {
  return err != 0 ? std::generic_category().message(err) : std::string("stream error");
}

std::filesystem::path folder_of(const std::filesystem::path& path) {
  std::filesystem::path dir = path.parent_path();
  return dir.empty() ? std::filesystem::path(".") : dir;
}

/// Why writing `temp` failed: the system's error `err` and, when the disk is full, the bytes
/// left there (as the HDF5 writer says it). A stream can lose errno (err = 0): a folder with
/// (almost) nothing free is then still named as the likely cause.
std::string write_cause(const std::filesystem::path& temp, int err) {
  const std::filesystem::path dir = folder_of(temp);
  std::error_code ec;
  const auto space = std::filesystem::space(dir, ec);
  const std::string free_text =
      ec ? std::string() : std::to_string(space.available) + " bytes free in " + dir.string();
  if (err == ENOSPC || err == EDQUOT) {
    std::string text = std::generic_category().message(err);
    if (!free_text.empty()) text += (err == ENOSPC ? " (disk full: " : " (") + free_text + ")";
    return text;
  }
  if (err == 0 && !ec && space.available < (std::uintmax_t{1} << 20))
    return "no system error reported, but the disk is probably full (" + free_text + ")";
  return errno_text(err);
}

[[noreturn]] void fail(const std::filesystem::path& path, const std::string& what) {
  throw IoError("cannot write " + path.string() + ": " + what);
}

/// Outputs replace regular files only, and never an input of this run: renaming onto a device,
/// a pipe or a symbolic link would replace it with a plain file (a device node, a link the user
/// keeps), and onto an input would destroy the data the output came from.
void check_replaceable(const std::filesystem::path& path) {
  std::error_code ec;
  const auto status = std::filesystem::symlink_status(path, ec);
  if (ec || !std::filesystem::exists(status)) return;
  if (std::filesystem::is_symlink(status)) {
    std::error_code ignored;
    fail(path, "it is a symbolic link (to " + std::filesystem::read_symlink(path, ignored).string() +
                   "): outputs replace regular files only; give the path of the file itself");
  }
  if (std::filesystem::is_directory(status)) fail(path, "it is a directory");
  if (!std::filesystem::is_regular_file(status))
    fail(path, "it is not a regular file (a device, pipe or socket): outputs replace regular "
               "files only");
  if (const auto input = input_named_by(path))
    fail(path, input->string() == path.string()
                   ? "it is an input of this run; write the output elsewhere"
                   : "it is an input of this run (" + input->string() +
                         "); write the output elsewhere");
}

/// Forces the file's data to disk, so that after a power loss the renamed file is never empty.
int sync_file(const std::filesystem::path& path, int flags) {
  const int fd = ::open(path.c_str(), flags | O_RDONLY | O_CLOEXEC);
  if (fd < 0) return errno;
  const int err = ::fsync(fd) == 0 ? 0 : errno;
  ::close(fd);
  return err;
}

void discard(std::ofstream& out, const std::filesystem::path& temp) {
  out.exceptions(std::ios::goodbit);  // close() must not throw while cleaning up
  if (out.is_open()) out.close();
  std::error_code ignored;
  std::filesystem::remove(temp, ignored);
}

/// Writes `temp` in full through `write` and forces it to disk; throws IoError naming `path`
/// (the temporary is then removed).
void write_temporary(const std::filesystem::path& path, const std::filesystem::path& temp,
                     const std::function<void(std::ofstream&)>& write) {
  std::ofstream out;
  try {
    errno = 0;
    out.open(temp, std::ios::binary | std::ios::trunc);
    if (!out) fail(path, "cannot create " + temp.string() + ": " + errno_text(errno));
    errno = 0;
    write(out);
    out.exceptions(std::ios::goodbit);
    // The stream's write(2) that failed left its errno: read it before anything else can
    // overwrite it (the buffered rest is written by flush(), its failure likewise).
    int err = out.fail() ? errno : 0;
    if (!out.fail()) {
      errno = 0;
      out.flush();
      if (out.fail()) err = errno;
    }
    const bool failed = out.fail();
    errno = 0;
    out.close();
    if (!failed && out.fail()) err = errno;
    if (out.fail()) fail(path, "writing " + temp.string() + " failed: " + write_cause(temp, err));
    if (const int sync_err = sync_file(temp, 0); sync_err != 0) {
      fail(path, "fsync of " + temp.string() + " failed: " + write_cause(temp, sync_err));
    }
  } catch (const IoError&) {
    discard(out, temp);
    throw;
  } catch (const std::exception& e) {
    discard(out, temp);
    // Keeps the cause reachable through std::rethrow_if_nested.
    std::throw_with_nested(IoError("cannot write " + path.string() + ": " + e.what()));
  } catch (...) {
    // Not an error of ours (e.g. thread cancellation): clean up and let it pass unchanged.
    discard(out, temp);
    throw;
  }
}

/// The rename is durable only once the directory entry is; failures here (file systems that
/// cannot sync directories) leave a complete file behind, so they are not errors.
void sync_folder(const std::filesystem::path& path) { sync_file(folder_of(path), O_DIRECTORY); }

}  // namespace

std::filesystem::path temporary_path(const std::filesystem::path& path) {
  const std::string prefix = path.filename().string() + ".tmp-";
  std::filesystem::path dir = path.parent_path();
  if (dir.empty()) dir = ".";
  std::error_code ec;
  for (std::filesystem::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.size() <= prefix.size() || name.compare(0, prefix.size(), prefix) != 0) continue;
    const std::string digits = name.substr(prefix.size());
    if (digits.size() > 9 || digits.find_first_not_of("0123456789") != std::string::npos) continue;
    const auto pid = static_cast<pid_t>(std::stol(digits));
    if (pid != ::getpid() && ::kill(pid, 0) != 0 && errno == ESRCH) {
      std::error_code ignored;
      std::filesystem::remove(it->path(), ignored);
    }
  }
  std::filesystem::path temp = path;
  temp += ".tmp-" + std::to_string(::getpid());
  return temp;
}

void write_atomically(const std::filesystem::path& path,
                      const std::function<void(std::ofstream&)>& write) {
  check_replaceable(path);
  const std::filesystem::path temp = temporary_path(path);
  write_temporary(path, temp, write);
  std::error_code ec;
  std::filesystem::rename(temp, path, ec);
  if (ec) {
    std::filesystem::remove(temp, ec);
    fail(path, "cannot rename " + temp.string() + ": " + ec.message());
  }
  sync_folder(path);
}

AtomicFileSet::~AtomicFileSet() { discard(); }

void AtomicFileSet::discard() noexcept {
  for (const auto& [file, temp] : staged_) {
    std::error_code ignored;
    std::filesystem::remove(temp, ignored);
  }
  staged_.clear();
}

void AtomicFileSet::add(const std::filesystem::path& path,
                        const std::function<void(std::ofstream&)>& write) {
  try {
    check_replaceable(path);
    std::error_code ec;
    const std::filesystem::path key = std::filesystem::weakly_canonical(path, ec);
    for (const auto& staged : staged_) {
      std::error_code ec2;
      if (!ec && std::filesystem::weakly_canonical(staged.first, ec2) == key && !ec2)
        fail(path, "it is also written as " + staged.first.string() + " in the same run");
    }
    const std::filesystem::path temp = temporary_path(path);
    write_temporary(path, temp, write);
    staged_.emplace_back(path, temp);
  } catch (...) {
    discard();
    throw;
  }
}

void AtomicFileSet::commit() {
  // Everything is written: what is left can only fail on a folder that changed meanwhile.
  for (std::size_t i = 0; i < staged_.size(); ++i) {
    const std::filesystem::path file = staged_[i].first, temp = staged_[i].second;
    std::error_code ec;
    std::filesystem::rename(temp, file, ec);
    if (ec) {
      std::string done;
      for (std::size_t j = 0; j < i; ++j) done += (j ? ", " : "") + staged_[j].first.string();
      const std::string message = "cannot rename " + temp.string() + ": " + ec.message() +
                                  (done.empty() ? "" : " (" + done + " already replaced)");
      staged_.erase(staged_.begin(), staged_.begin() + static_cast<std::ptrdiff_t>(i));
      discard();
      fail(file, message);
    }
  }
  for (const auto& staged : staged_) sync_folder(staged.first);
  staged_.clear();
}

OutputLock::OutputLock(const std::filesystem::path& path) {
  std::filesystem::path dir = path.parent_path();
  if (dir.empty()) dir = ".";
  fd_ = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  // Without a lock (a file system that refuses it) the files are still each written atomically.
  if (fd_ >= 0 && ::flock(fd_, LOCK_EX) != 0) {
    ::close(fd_);
    fd_ = -1;
  }
}

OutputLock::~OutputLock() {
  if (fd_ >= 0) ::close(fd_);  // closing releases the lock
}

void check_writable(const std::filesystem::path& path) {
  std::filesystem::path dir = path.parent_path();
  if (dir.empty()) dir = ".";
  std::error_code ec;
  const auto status = std::filesystem::status(dir, ec);
  if (!std::filesystem::exists(status)) fail(path, "directory " + dir.string() + " does not exist");
  if (!std::filesystem::is_directory(status)) fail(path, dir.string() + " is not a directory");
  if (::access(dir.c_str(), W_OK | X_OK) != 0) {
    fail(path, "directory " + dir.string() + " is not writable: " + errno_text(errno));
  }
  if (std::filesystem::is_directory(path, ec)) fail(path, "it is a directory");
  check_replaceable(path);
}

}  // namespace orthofront::io
