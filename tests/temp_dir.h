#pragma once
// One temporary folder helper for every test: a fresh directory under the system temp directory,
// removed with its content; and reading a file whole.
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <system_error>
#include <vector>

namespace test_support {

class TempDir {
 public:
  explicit TempDir(const std::string& tag = "test") {
    static int counter = 0;
    path_ = std::filesystem::temp_directory_path() /
            ("orthofront-test-" + tag + "-" + std::to_string(::getpid()) + "-" +
             std::to_string(counter++));
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  ~TempDir() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }
  const std::filesystem::path& path() const { return path_; }
  bool empty() const { return std::filesystem::is_empty(path_); }
  /// Names of the files in the directory, sorted.
  std::vector<std::string> entries() const {
    std::vector<std::string> names;
    for (const auto& entry : std::filesystem::directory_iterator(path_))
      names.push_back(entry.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
  }

 private:
  std::filesystem::path path_;
};

/// The whole content of a file ("" when it cannot be opened).
inline std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

/// A .vtp file's text without its field data (the notes of where it came from): two runs of
/// one surface from different files of the same data give the same rest, byte for byte.
inline std::string vtp_geometry_text(const std::filesystem::path& path) {
  std::string text = read_text(path);
  const std::size_t begin = text.find("<FieldData>");
  const std::size_t end = text.find("</FieldData>");
  if (begin != std::string::npos && end != std::string::npos && end > begin)
    text.erase(begin, end + std::string("</FieldData>").size() - begin);
  return text;
}

}  // namespace test_support
