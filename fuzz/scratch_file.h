#pragma once
/// Readers that take a path (HDF5, OpenVDB's File, mesh files) get the input in a file of their
/// own in /dev/shm (or the temporary folder), one per process, rewritten for every input.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

namespace orthofront::fuzz {

inline std::filesystem::path scratch_file(const std::string& extension) {
  const std::filesystem::path shm = "/dev/shm";
  const std::filesystem::path folder =
      std::filesystem::is_directory(shm) ? shm : std::filesystem::temp_directory_path();
  return folder / ("orthofront-fuzz-" + std::to_string(::getpid()) + extension);
}

inline const std::filesystem::path& write_scratch(const std::filesystem::path& file,
                                                  const std::uint8_t* data, std::size_t size) {
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  return file;
}

}  // namespace orthofront::fuzz
