#pragma once
/// Numbers as text, independent of the C locale: shortest exact output and strict parsing
/// (internal to the mesh codecs).
#include <charconv>
#include <cstdint>
#include <string>
#include <string_view>
#include <system_error>

namespace orthofront::io::detail {

/// Appends the shortest text that reads back as exactly `value`.
template <typename T>
void append_number(std::string& out, T value) {
  char buffer[40];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value);
  out.append(buffer, result.ptr);
}

/// Parses all of `text` (a leading '+' allowed) into `value`; false when the text is not a number,
/// is out of range, or has anything left over.
template <typename T>
bool parse_number(std::string_view text, T& value) {
  if (!text.empty() && text.front() == '+') text.remove_prefix(1);
  if (text.empty()) return false;
  const char* end = text.data() + text.size();
  const auto result = std::from_chars(text.data(), end, value);
  return result.ec == std::errc() && result.ptr == end;
}

}  // namespace orthofront::io::detail
