#pragma once
// Helpers for the vector-grid format tests: temporary folders, byte writers in either byte
// order, synthetic grids with exactly representable values, comparisons and the real-data folder.
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

#include "orthofront/field/grid.h"
#include "temp_dir.h"

namespace grid_test {

namespace fs = std::filesystem;

using test_support::TempDir;

inline void write_file(const fs::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

inline std::string read_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::string bytes(static_cast<std::size_t>(fs::file_size(path)), '\0');
  in.read(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  return bytes;
}

/// Appends `value` in the given byte order.
template <typename T>
void put(std::string& out, T value, bool little_endian) {
  unsigned char b[sizeof(T)];
  std::memcpy(b, &value, sizeof(T));
  if ((std::endian::native == std::endian::little) != little_endian) std::reverse(b, b + sizeof(T));
  out.append(reinterpret_cast<const char*>(b), sizeof(T));
}

/// The floats of `values` in the given byte order.
inline std::string float_bytes(const std::vector<float>& values, bool little_endian) {
  std::string out;
  for (const float v : values) put(out, v, little_endian);
  return out;
}

/// A value that every format stores exactly: distinct per point and component, with fractions
/// and signs (and one NaN to check that missing values survive).
inline float sample_value(std::int64_t i, std::int64_t j, std::int64_t k, int c) {
  return static_cast<float>(i) * 0.5f - static_cast<float>(j) * 1.25f +
         static_cast<float>(k) * 8.0f + static_cast<float>(c) * 0.0625f - 3.0f;
}

/// A uniform grid of the given size filled with sample_value.
inline orthofront::VectorGrid sample_grid(std::int64_t nx, std::int64_t ny, std::int64_t nz,
                                          int components = 3, bool with_nan = false) {
  orthofront::VectorGrid grid;
  grid.geometry.dimension = nz == 1 ? 2 : 3;
  grid.geometry.size = {nx, ny, nz};
  grid.components = components;
  for (std::int64_t k = 0; k < nz; ++k) {
    for (std::int64_t j = 0; j < ny; ++j) {
      for (std::int64_t i = 0; i < nx; ++i) {
        for (int c = 0; c < components; ++c) grid.values.push_back(sample_value(i, j, k, c));
      }
    }
  }
  if (with_nan) grid.values[static_cast<std::size_t>(components)] = NAN;  // point 1, component 0
  return grid;
}

/// Same floats bit for bit (NaN equals NaN).
inline bool same_values(const std::vector<float>& a, const std::vector<float>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (std::isnan(a[i]) && std::isnan(b[i])) continue;
    if (a[i] != b[i]) return false;
  }
  return true;
}

/// The message of the exception of type E that `f` throws ("" when it throws none).
template <typename E>
std::string thrown(const std::function<void()>& f) {
  try {
    f();
  } catch (const E& e) {
    return e.what();
  }
  return "";
}

/// The real data folder, or an empty path (with a visible warning) when it is absent.
inline fs::path datasets_dir(const std::string& sub) {
  const fs::path dir = fs::path(ORTHOFRONT_DATASETS_DIR) / sub;
  if (!fs::is_directory(dir)) {
    WARN("SKIPPED: real data folder " << dir.string() << " is absent");
    return {};
  }
  return dir;
}

}  // namespace grid_test
