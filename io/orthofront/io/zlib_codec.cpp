#include "orthofront/io/zlib_codec.h"

#include <zlib.h>

#include <algorithm>
#include <limits>

#include "orthofront/io/error.h"

namespace orthofront::io::detail {
namespace {

// zlib counts in uInt; feed it in pieces so that inputs beyond 4 GiB work.
constexpr std::size_t kPiece = std::size_t{1} << 30;

std::string zlib_message(const z_stream& stream, int code) {
  if (stream.msg != nullptr) return stream.msg;
  switch (code) {
    case Z_DATA_ERROR:
      return "corrupt compressed data";
    case Z_MEM_ERROR:
      return "out of memory";
    case Z_BUF_ERROR:
      return "compressed data ends early";
    default:
      return "zlib error " + std::to_string(code);
  }
}

/// Inflates with the given window bits; stops after `limit` output bytes (more is an error).
std::string inflate_all(std::string_view in, int window_bits, std::size_t reserve,
                        std::size_t limit, bool multiple_members, const std::string& context) {
  z_stream stream{};
  if (inflateInit2(&stream, window_bits) != Z_OK)
    throw FormatError(context + ": cannot initialise zlib");
  std::string out;
  out.reserve(reserve);
  std::size_t consumed = 0;
  char buffer[1 << 16];
  int code = Z_OK;
  for (;;) {
    if (stream.avail_in == 0 && consumed < in.size()) {
      const std::size_t n = std::min(kPiece, in.size() - consumed);
      stream.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(in.data() + consumed));
      stream.avail_in = static_cast<uInt>(n);
      consumed += n;
    }
    stream.next_out = reinterpret_cast<Bytef*>(buffer);
    stream.avail_out = sizeof(buffer);
    code = inflate(&stream, Z_NO_FLUSH);
    const std::size_t produced = sizeof(buffer) - stream.avail_out;
    if (out.size() + produced > limit) {
      inflateEnd(&stream);
      throw FormatError(context + ": compressed data holds more than the expected " +
                        std::to_string(limit) + " bytes");
    }
    out.append(buffer, produced);
    if (code == Z_STREAM_END) {
      // Another gzip member may follow (zero padding after the last one is ignored).
      const std::size_t rest_begin = consumed - stream.avail_in;
      const std::string_view rest = in.substr(rest_begin);
      const bool more = std::any_of(rest.begin(), rest.end(), [](char c) { return c != 0; });
      if (multiple_members && more) {
        if (inflateReset(&stream) != Z_OK) break;
        continue;
      }
      break;
    }
    if (code == Z_BUF_ERROR && stream.avail_in == 0 && consumed == in.size()) break;
    if (code != Z_OK && code != Z_BUF_ERROR) break;
  }
  const std::string message = zlib_message(stream, code);
  inflateEnd(&stream);
  if (code != Z_STREAM_END) {
    throw FormatError(context + ": " +
                      (code == Z_BUF_ERROR || code == Z_OK ? std::string("compressed data ends early")
                                                           : message));
  }
  return out;
}

std::string deflate_all(std::string_view bytes, int level, int window_bits) {
  z_stream stream{};
  if (deflateInit2(&stream, level, Z_DEFLATED, window_bits, 8, Z_DEFAULT_STRATEGY) != Z_OK)
    throw Error("cannot initialise zlib");
  std::string out;
  out.reserve(bytes.size() / 2 + 64);
  std::size_t consumed = 0;
  char buffer[1 << 16];
  int code = Z_OK;
  do {
    if (stream.avail_in == 0 && consumed < bytes.size()) {
      const std::size_t n = std::min(kPiece, bytes.size() - consumed);
      stream.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(bytes.data() + consumed));
      stream.avail_in = static_cast<uInt>(n);
      consumed += n;
    }
    const int flush = consumed == bytes.size() ? Z_FINISH : Z_NO_FLUSH;
    stream.next_out = reinterpret_cast<Bytef*>(buffer);
    stream.avail_out = sizeof(buffer);
    code = deflate(&stream, flush);
    out.append(buffer, sizeof(buffer) - stream.avail_out);
  } while (code == Z_OK || code == Z_BUF_ERROR);
  deflateEnd(&stream);
  if (code != Z_STREAM_END) throw Error("zlib compression failed");
  return out;
}

}  // namespace

std::string zlib_inflate(std::string_view compressed, std::size_t expected,
                         const std::string& context) {
  // Deflate expands at most 1032:1 (plus a few bytes of framing): a larger expected size comes
  // from a damaged or hostile header, and reserving it would allocate for data that is not there.
  if (static_cast<double>(expected) > static_cast<double>(compressed.size()) * 1032.0 + 64.0) {
    throw FormatError(context + ": " + std::to_string(compressed.size()) +
                      " compressed bytes cannot hold the expected " + std::to_string(expected) +
                      " bytes (deflate expands at most 1032:1)");
  }
  std::string out = inflate_all(compressed, 15, expected, expected, false, context);
  if (out.size() != expected) {
    throw FormatError(context + ": compressed data holds " + std::to_string(out.size()) +
                      " bytes, expected " + std::to_string(expected));
  }
  return out;
}

std::string gzip_inflate(std::string_view compressed, const std::string& context,
                         std::size_t limit) {
  // 15 + 32: a zlib or a gzip header, detected automatically.
  return inflate_all(compressed, 15 + 32, std::min<std::size_t>(limit, compressed.size() * 4),
                     limit, true, context);
}

std::string zlib_deflate(std::string_view bytes, int level) {
  return deflate_all(bytes, level, 15);
}

std::string gzip_deflate(std::string_view bytes, int level) {
  return deflate_all(bytes, level, 15 + 16);
}

}  // namespace orthofront::io::detail
