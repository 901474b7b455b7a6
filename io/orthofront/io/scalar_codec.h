#pragma once
/// Binary scalar types shared by the PLY and VTK XML codecs: sizes, and loads and stores that do
/// not depend on the host's byte order (internal to the mesh codecs).
#include <algorithm>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <type_traits>

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

/// Calls f(T{}) with the C++ type T that stores `type`, and returns what it returns.
template <class F>
decltype(auto) with_scalar_type(ScalarType type, F&& f) {
  switch (type) {
    case ScalarType::kInt8:
      return f(std::int8_t{});
    case ScalarType::kUInt8:
      return f(std::uint8_t{});
    case ScalarType::kInt16:
      return f(std::int16_t{});
    case ScalarType::kUInt16:
      return f(std::uint16_t{});
    case ScalarType::kInt32:
      return f(std::int32_t{});
    case ScalarType::kUInt32:
      return f(std::uint32_t{});
    case ScalarType::kInt64:
      return f(std::int64_t{});
    case ScalarType::kUInt64:
      return f(std::uint64_t{});
    case ScalarType::kFloat32:
      return f(float{});
    case ScalarType::kFloat64:
      break;
  }
  return f(double{});  // kFloat64 (the switch lists every type)
}

/// Reads one value of `type` as a double: exact for every type but 64-bit integers above 2^53.
inline double load_real(ScalarType type, const unsigned char* bytes, bool little_endian) {
  return with_scalar_type(type, [&](auto stored) {
    return static_cast<double>(load<decltype(stored)>(bytes, little_endian));
  });
}

/// Reads one value of an integer `type` as int64 (UInt64 above 2^63 wraps); 0 for a real type.
inline std::int64_t load_integer(ScalarType type, const unsigned char* bytes, bool little_endian) {
  return with_scalar_type(type, [&](auto stored) -> std::int64_t {
    using T = decltype(stored);
    if constexpr (std::is_integral_v<T>) {
      return static_cast<std::int64_t>(load<T>(bytes, little_endian));
    } else {
      return 0;
    }
  });
}

}  // namespace orthofront::io::detail
