#include "orthofront/io/readable_file.h"

#include <unistd.h>

#include <cerrno>
#include <system_error>

namespace orthofront::io {

std::string why_unreadable(const std::filesystem::path& path) {
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (ec) {
    if (ec == std::errc::too_many_symbolic_link_levels) return "a loop of symbolic links";
    if (ec == std::errc::permission_denied) return "permission denied";
    if (ec != std::errc::no_such_file_or_directory) return ec.message();
  }
  if (!std::filesystem::exists(status)) {
    const auto link = std::filesystem::symlink_status(path, ec);
    return !ec && std::filesystem::is_symlink(link) ? "a dangling symbolic link" : "no such file";
  }
  if (std::filesystem::is_directory(status)) return "it is a directory";
  if (!std::filesystem::is_regular_file(status))
    return "not a regular file (a device, a FIFO or a socket)";
  if (::access(path.c_str(), R_OK) != 0) return errno == EACCES ? "permission denied" : "";
  return "";
}

}  // namespace orthofront::io
