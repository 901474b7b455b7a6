#include "orthofront/io/atomic_file.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <exception>
#include <string>
#include <system_error>

#include "orthofront/io/error.h"

namespace orthofront::io {
namespace {

std::string errno_text(int err) {
  return err != 0 ? std::generic_category().message(err) : std::string("stream error");
}

[[noreturn]] void fail(const std::filesystem::path& path, const std::string& what) {
  throw IoError("cannot write " + path.string() + ": " + what);
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
  const std::filesystem::path temp = temporary_path(path);
  std::ofstream out;
  try {
    errno = 0;
    out.open(temp, std::ios::binary | std::ios::trunc);
    if (!out) fail(path, "cannot create " + temp.string() + ": " + errno_text(errno));
    write(out);
    out.exceptions(std::ios::goodbit);
    errno = 0;
    out.flush();
    out.close();
    if (out.fail()) fail(path, "writing " + temp.string() + " failed: " + errno_text(errno));
    if (const int err = sync_file(temp, 0); err != 0) {
      fail(path, "fsync of " + temp.string() + " failed: " + errno_text(err));
    }
    std::error_code ec;
    std::filesystem::rename(temp, path, ec);
    if (ec) fail(path, "cannot rename " + temp.string() + ": " + ec.message());
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
  // The rename is durable only once the directory entry is; failures here (file systems that
  // cannot sync directories) leave a complete file behind, so they are not errors.
  std::filesystem::path dir = path.parent_path();
  if (dir.empty()) dir = ".";
  sync_file(dir, O_DIRECTORY);
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
}

}  // namespace orthofront::io
