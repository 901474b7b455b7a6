#pragma once
/// zlib (deflate) as VTK XML, NRRD and AmiraMesh use it (internal to the readers and writers).
#include <cstddef>
#include <string>
#include <string_view>

namespace orthofront::io::detail {

/// Inflates one zlib stream that must give exactly `expected` bytes. Throws FormatError whose
/// message starts with `context` (the file and the array) when the stream is damaged, ends early
/// or is longer than expected, and before allocating anything when `expected` exceeds what
/// `compressed` can inflate to (1032:1).
std::string zlib_inflate(std::string_view compressed, std::size_t expected,
                         const std::string& context);

/// Inflates a gzip or zlib stream (the header says which; concatenated gzip members are joined)
/// of unknown length. Throws FormatError starting with `context` on damaged data, or when the
/// result exceeds `limit` bytes.
std::string gzip_inflate(std::string_view compressed, const std::string& context,
                         std::size_t limit = static_cast<std::size_t>(-1));

/// Deflates `bytes` as one zlib stream (level 0..9, -1 = zlib's default).
std::string zlib_deflate(std::string_view bytes, int level = -1);

/// Deflates `bytes` as one gzip member.
std::string gzip_deflate(std::string_view bytes, int level = -1);

}  // namespace orthofront::io::detail
