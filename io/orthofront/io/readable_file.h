#pragma once
/// Why a path given as an input file cannot be read as one, in the words a message needs.
#include <filesystem>
#include <string>

namespace orthofront::io {

/// "" when `path` is a regular file (after links) that this process may read; otherwise the
/// reason: "no such file", "it is a directory", "a loop of symbolic links", "a dangling symbolic
/// link", "not a regular file (a device, a FIFO or a socket)", "permission denied".
std::string why_unreadable(const std::filesystem::path& path);

}  // namespace orthofront::io
