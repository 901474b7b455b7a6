#pragma once
// Helpers of the [realdata] command-line tests: run the binary with its output in a log, read a
// file whole, and a fresh folder per case under the system's temporary folder.
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace realdata_test {

inline int run(const std::string& command_line, const std::filesystem::path& log) {
  const std::string command = command_line + " > '" + log.string() + "' 2>&1 < /dev/null";
  return WEXITSTATUS(std::system(command.c_str()));
}

inline std::string text_of(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

inline std::filesystem::path fresh_dir(const std::string& name) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("orthofront-realdata-" + name);
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

}  // namespace realdata_test
