#pragma once
/// bzip2 as NRRD uses it, through libbz2 (internal to the readers).
#include <cstddef>
#include <string>
#include <string_view>

namespace orthofront::io::detail {

/// Decompresses `compressed` (one or more concatenated bzip2 streams) into at most `limit` bytes,
/// growing the output only as data comes out. Throws FormatError naming `context` for a corrupt
/// stream or more than `limit` bytes.
std::string bzip2_decompress(std::string_view compressed, const std::string& context,
                             std::size_t limit);

/// Compresses `bytes` as one bzip2 stream (for tests and writers).
std::string bzip2_compress(std::string_view bytes, int block_size_100k = 9);

}  // namespace orthofront::io::detail
