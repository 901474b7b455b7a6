#pragma once
/// Where a benchmark writes the series it samples: the --keep path, left there, or else a fresh
/// name in the temporary folder, removed when this goes out of scope (on an error too).
#include <filesystem>
#include <random>
#include <string>
#include <system_error>

namespace orthofront::cli {

class BenchSeriesFile {
 public:
  BenchSeriesFile(const std::string& keep, const std::string& prefix)
      : path_(keep), temporary_(keep.empty()) {
    if (temporary_)
      path_ = std::filesystem::temp_directory_path() /
              (prefix + "-" + std::to_string(std::random_device{}()) + ".h5");
  }
  ~BenchSeriesFile() {
    std::error_code ec;
    if (temporary_) std::filesystem::remove(path_, ec);
  }
  BenchSeriesFile(const BenchSeriesFile&) = delete;
  BenchSeriesFile& operator=(const BenchSeriesFile&) = delete;

  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
  bool temporary_;
};

}  // namespace orthofront::cli
