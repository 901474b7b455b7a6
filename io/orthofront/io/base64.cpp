#include "orthofront/io/base64.h"

#include <array>
#include <cstdint>
#include <cstring>

namespace orthofront::io::detail {
namespace {

constexpr char kAlphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

constexpr std::array<std::int8_t, 256> make_decode_table() {
  std::array<std::int8_t, 256> table{};
  table.fill(-1);
  for (int i = 0; i < 64; ++i)
    table[static_cast<unsigned char>(kAlphabet[i])] = static_cast<std::int8_t>(i);
  return table;
}
constexpr std::array<std::int8_t, 256> kDecode = make_decode_table();

/// The two characters of every 12-bit half of a group: two lookups a group instead of four.
constexpr std::array<std::array<char, 2>, 4096> make_pair_table() {
  std::array<std::array<char, 2>, 4096> table{};
  for (std::size_t i = 0; i < 4096; ++i) table[i] = {kAlphabet[i >> 6], kAlphabet[i & 63]};
  return table;
}
constexpr std::array<std::array<char, 2>, 4096> kPairs = make_pair_table();

std::uint32_t byte_at(std::string_view bytes, std::size_t i) {
  return static_cast<unsigned char>(bytes[i]);
}

bool is_space(char c) {
  return c == ' ' || c == '\n' || c == '\r' || c == '\t';
}

}  // namespace

std::string base64_encode(std::string_view bytes) {
  std::string out;
  base64_encode(bytes, out);
  return out;
}

void base64_encode(std::string_view bytes, std::string& out) {
  // Into a buffer sized once: appending a character at a time (a size check and a terminator
  // each) made encoding a visible part of writing a large .vtp.
  out.resize((bytes.size() + 2) / 3 * 4);
  char* o = out.data();
  std::size_t i = 0;
  for (; i + 3 <= bytes.size(); i += 3, o += 4) {
    const std::uint32_t group =
        byte_at(bytes, i) << 16 | byte_at(bytes, i + 1) << 8 | byte_at(bytes, i + 2);
    std::memcpy(o, kPairs[group >> 12].data(), 2);
    std::memcpy(o + 2, kPairs[group & 4095].data(), 2);
  }
  const std::size_t rest = bytes.size() - i;
  if (rest > 0) {
    std::uint32_t group = byte_at(bytes, i) << 16;
    if (rest == 2) group |= byte_at(bytes, i + 1) << 8;
    o[0] = kAlphabet[group >> 18 & 63];
    o[1] = kAlphabet[group >> 12 & 63];
    o[2] = rest == 2 ? kAlphabet[group >> 6 & 63] : '=';
    o[3] = '=';
  }
}

bool base64_decode(std::string_view text, std::string& bytes) {
  // Written through a pointer into room for the most the text can hold, then cut to size:
  // appending a byte at a time made decoding a large part of reading a large .vtp.
  bytes.resize(text.size() / 4 * 3 + 3);
  char* const begin = bytes.data();
  char* out = begin;
  std::uint32_t group = 0;
  int filled = 0;   // characters in the current group, padding included
  int padding = 0;  // '=' in the current group
  // Emits the bytes of a (possibly short) group: n significant characters carry n - 1 bytes.
  const auto flush = [&]() {
    const int significant = filled - padding;
    if (significant < 2) return false;
    group <<= 6 * (4 - filled);
    *out++ = static_cast<char>(group >> 16 & 255);
    if (significant > 2) *out++ = static_cast<char>(group >> 8 & 255);
    if (significant > 3) *out++ = static_cast<char>(group & 255);
    group = 0;
    filled = 0;
    padding = 0;
    return true;
  };
  const auto digit_at = [&](std::size_t i) { return kDecode[static_cast<unsigned char>(text[i])]; };
  for (std::size_t i = 0; i < text.size();) {
    // A whole group of four alphabet characters at once (whitespace and '=' decode to -1 and
    // take the general path below).
    if (filled == 0 && i + 4 <= text.size()) {
      const int a = digit_at(i), b = digit_at(i + 1), c = digit_at(i + 2), d = digit_at(i + 3);
      if ((a | b | c | d) >= 0) {
        const auto whole = static_cast<std::uint32_t>(a << 18 | b << 12 | c << 6 | d);
        out[0] = static_cast<char>(whole >> 16 & 255);
        out[1] = static_cast<char>(whole >> 8 & 255);
        out[2] = static_cast<char>(whole & 255);
        out += 3;
        i += 4;
        continue;
      }
    }
    const char c = text[i++];
    if (is_space(c)) continue;
    if (c == '=') {
      if (filled - padding < 2) return false;
      ++padding;
      group <<= 6;
    } else {
      const int digit = kDecode[static_cast<unsigned char>(c)];
      if (digit < 0 || padding > 0) return false;
      group = group << 6 | static_cast<std::uint32_t>(digit);
    }
    if (++filled == 4 && !flush()) return false;
  }
  if (filled != 0 && !flush()) return false;
  bytes.resize(static_cast<std::size_t>(out - begin));
  return true;
}

}  // namespace orthofront::io::detail
