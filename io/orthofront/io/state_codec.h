#pragma once
/// Byte codec of a surface's state between front steps (checkpoints of batch jobs): fixed-width
/// little-endian fields, every length checked against the bytes left before anything is
/// allocated, so a truncated or hostile file is refused with a message naming it.
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "orthofront/engine/surface_builder.h"

namespace orthofront::io {

/// Appends fixed-width values to a byte string.
class ByteWriter {
 public:
  void u8(std::uint8_t v) { bytes_.push_back(static_cast<char>(v)); }
  void u32(std::uint32_t v) { raw(&v, sizeof v); }
  void u64(std::uint64_t v) { raw(&v, sizeof v); }
  void i32(std::int32_t v) { raw(&v, sizeof v); }
  void f64(double v) { raw(&v, sizeof v); }
  void text(std::string_view s) {
    u64(s.size());
    bytes_.append(s);
  }
  template <typename T, typename Allocator>
  void array(const std::vector<T, Allocator>& values) {
    u64(values.size());
    if (!values.empty()) raw(values.data(), values.size() * sizeof(T));
  }
  const std::string& bytes() const { return bytes_; }
  std::string take() { return std::move(bytes_); }

 private:
  void raw(const void* data, std::size_t size) {
    bytes_.append(static_cast<const char*>(data), size);
  }
  std::string bytes_;
};

/// Reads what ByteWriter wrote; throws FormatError naming `source` (a file name) when the bytes
/// run out or a length is impossible.
class ByteReader {
 public:
  ByteReader(std::string_view bytes, std::string source)
      : bytes_(bytes), source_(std::move(source)) {}
  std::uint8_t u8() { return scalar<std::uint8_t>(); }
  std::uint32_t u32() { return scalar<std::uint32_t>(); }
  std::uint64_t u64() { return scalar<std::uint64_t>(); }
  std::int32_t i32() { return scalar<std::int32_t>(); }
  double f64() { return scalar<double>(); }
  std::string text();
  template <typename T>
  std::vector<T> array() {
    const std::uint64_t n = count(sizeof(T));
    std::vector<T> values(n);
    if (n) take(values.data(), n * sizeof(T));
    return values;
  }
  /// array<T>() into `values`, whatever their allocator.
  template <typename T, typename Allocator>
  void array(std::vector<T, Allocator>& values) {
    const std::uint64_t n = count(sizeof(T));
    values.assign(n, T{});
    if (n) take(values.data(), n * sizeof(T));
  }
  /// A count of items of `item_bytes` each that the bytes left can hold (else FormatError).
  std::uint64_t count(std::size_t item_bytes);
  std::size_t left() const { return bytes_.size() - at_; }
  [[noreturn]] void fail(const std::string& what) const;

 private:
  template <typename T>
  T scalar() {
    T value{};
    take(&value, sizeof value);
    return value;
  }
  void take(void* out, std::size_t size);
  std::string_view bytes_;
  std::size_t at_ = 0;
  std::string source_;
};

void write_mesh_state(ByteWriter& out, const Mesh& mesh);
Mesh read_mesh_state(ByteReader& in);

/// The engine's state in R^N (N = 3 or 4). The report's options are not stored: the builder
/// that resumes takes them from its own options.
template <int N>
void write_engine_state(ByteWriter& out, const EngineState<N>& state);
template <int N>
EngineState<N> read_engine_state(ByteReader& in);

}  // namespace orthofront::io
