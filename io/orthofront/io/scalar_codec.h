#pragma once
/// Binary scalar types shared by the PLY and VTK XML codecs: sizes, and loads and stores that do
/// not depend on the host's byte order (internal to the mesh codecs).
#include <algorithm>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>

namespace orthofront::io::detail {

enum class ScalarType {
  kInt8,
  kUInt8,
  kInt16,
  kUInt16,
  kInt32,
  kUInt32,
  kInt64,
  kUInt64,
  kFloat32,
  kFloat64
};

constexpr std::size_t scalar_size(ScalarType type) {
  switch (type) {
    case ScalarType::kInt8:
    case ScalarType::kUInt8:
      return 1;
    case ScalarType::kInt16:
    case ScalarType::kUInt16:
      return 2;
    case ScalarType::kInt32:
    case ScalarType::kUInt32:
    case ScalarType::kFloat32:
      return 4;
    case ScalarType::kInt64:
    case ScalarType::kUInt64:
    case ScalarType::kFloat64:
      return 8;
  }
  return 0;
}

constexpr bool is_integer(ScalarType type) {
  return type != ScalarType::kFloat32 && type != ScalarType::kFloat64;
}

/// Reads a T stored at `bytes` in the given byte order.
template <typename T>
T load(const unsigned char* bytes, bool little_endian) {
  unsigned char buffer[sizeof(T)];
  std::memcpy(buffer, bytes, sizeof(T));
  if ((std::endian::native == std::endian::little) != little_endian) {
    std::reverse(buffer, buffer + sizeof(T));
  }
  T value;
  std::memcpy(&value, buffer, sizeof(T));
  return value;
}

/// Appends `value` to `out` in little-endian byte order.
template <typename T>
void store_le(std::string& out, T value) {
  unsigned char buffer[sizeof(T)];
  std::memcpy(buffer, &value, sizeof(T));
  if constexpr (std::endian::native != std::endian::little)
    std::reverse(buffer, buffer + sizeof(T));
  out.append(reinterpret_cast<const char*>(buffer), sizeof(T));
}

/// Reads one value of `type` as a double: exact for every type but 64-bit integers above 2^53.
inline double load_real(ScalarType type, const unsigned char* bytes, bool little_endian) {
  switch (type) {
    case ScalarType::kInt8:
      return load<std::int8_t>(bytes, little_endian);
    case ScalarType::kUInt8:
      return load<std::uint8_t>(bytes, little_endian);
    case ScalarType::kInt16:
      return load<std::int16_t>(bytes, little_endian);
    case ScalarType::kUInt16:
      return load<std::uint16_t>(bytes, little_endian);
    case ScalarType::kInt32:
      return load<std::int32_t>(bytes, little_endian);
    case ScalarType::kUInt32:
      return load<std::uint32_t>(bytes, little_endian);
    case ScalarType::kInt64:
      return static_cast<double>(load<std::int64_t>(bytes, little_endian));
    case ScalarType::kUInt64:
      return static_cast<double>(load<std::uint64_t>(bytes, little_endian));
    case ScalarType::kFloat32:
      return load<float>(bytes, little_endian);
    case ScalarType::kFloat64:
      return load<double>(bytes, little_endian);
  }
  return 0.0;
}

/// Reads one value of an integer `type` as int64 (UInt64 above 2^63 wraps).
inline std::int64_t load_integer(ScalarType type, const unsigned char* bytes, bool little_endian) {
  switch (type) {
    case ScalarType::kInt8:
      return load<std::int8_t>(bytes, little_endian);
    case ScalarType::kUInt8:
      return load<std::uint8_t>(bytes, little_endian);
    case ScalarType::kInt16:
      return load<std::int16_t>(bytes, little_endian);
    case ScalarType::kUInt16:
      return load<std::uint16_t>(bytes, little_endian);
    case ScalarType::kInt32:
      return load<std::int32_t>(bytes, little_endian);
    case ScalarType::kUInt32:
      return load<std::uint32_t>(bytes, little_endian);
    case ScalarType::kInt64:
      return load<std::int64_t>(bytes, little_endian);
    case ScalarType::kUInt64:
      return static_cast<std::int64_t>(load<std::uint64_t>(bytes, little_endian));
    case ScalarType::kFloat32:
    case ScalarType::kFloat64:
      break;
  }
  return 0;
}

}  // namespace orthofront::io::detail
