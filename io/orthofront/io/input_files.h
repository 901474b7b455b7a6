#pragma once
/// The files a job reads its data from, so that no output of the job replaces one: while an
/// InputScope is open (a command, a Python call), every reader notes the files it opens and the
/// output writers refuse a path that names one of them. Outside any scope nothing is noted (a
/// program may read a file and later write it anew).
#include <filesystem>
#include <optional>
#include <vector>

namespace orthofront::io {

/// The extent of one job: inputs noted while any scope is open are forgotten when the last one
/// closes.
class InputScope {
 public:
  InputScope();
  ~InputScope();
  InputScope(const InputScope&) = delete;
  InputScope& operator=(const InputScope&) = delete;
};

/// Notes `path` (an existing file being read) as an input of the open job, if there is one.
void note_input(const std::filesystem::path& path);

/// Every input noted in the open job so far, by the name it was first read under (empty outside
/// any scope).
std::vector<std::filesystem::path> noted_inputs();

/// The noted input that `path` names (the same file, by any name or link), or nothing.
std::optional<std::filesystem::path> input_named_by(const std::filesystem::path& path);

}  // namespace orthofront::io
