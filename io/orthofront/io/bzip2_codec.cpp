#include "orthofront/io/bzip2_codec.h"

#include <bzlib.h>

#include <algorithm>

#include "orthofront/io/error.h"

namespace orthofront::io::detail {

namespace {

/// bz_stream with its cleanup.
struct Decompressor {
  bz_stream stream{};
  Decompressor() {
    if (BZ2_bzDecompressInit(&stream, 0, 0) != BZ_OK)
      throw FormatError("bzip2: cannot start the decompressor");
  }
  Decompressor(const Decompressor&) = delete;
  Decompressor& operator=(const Decompressor&) = delete;
  ~Decompressor() { BZ2_bzDecompressEnd(&stream); }
};

}  // namespace

std::string bzip2_decompress(std::string_view compressed, const std::string& context,
                             std::size_t limit) {
  std::string out;
  std::size_t consumed = 0;
  constexpr std::size_t kChunk = std::size_t{1} << 20;
  // Concatenated streams (as `cat a.bz2 b.bz2` or parallel compressors write them) are joined.
  while (consumed < compressed.size()) {
    Decompressor d;
    d.stream.next_in = const_cast<char*>(compressed.data() + consumed);  // bzlib's API is not const
    const std::size_t available = compressed.size() - consumed;
    d.stream.avail_in = static_cast<unsigned>(std::min<std::size_t>(available, 1u << 30));
    int status = BZ_OK;
    while (status != BZ_STREAM_END) {
      if (out.size() >= limit) {
        // Anything more is past what the header describes.
        char probe = 0;
        d.stream.next_out = &probe;
        d.stream.avail_out = 1;
        status = BZ2_bzDecompress(&d.stream);
        if (d.stream.avail_out == 0)
          throw FormatError(context + ": the bzip2 data holds more than the " +
                            std::to_string(limit) + " bytes the header describes");
        if (status != BZ_STREAM_END && status != BZ_OK)
          throw FormatError(context + ": corrupt bzip2 data (bzlib error " +
                            std::to_string(status) + ")");
        if (status == BZ_OK && d.stream.avail_in == 0)
          throw FormatError(context + ": truncated bzip2 data");
        continue;
      }
      const std::size_t old = out.size();
      const std::size_t grow = std::min(kChunk, limit - old);
      out.resize(old + grow);
      d.stream.next_out = out.data() + old;
      d.stream.avail_out = static_cast<unsigned>(grow);
      status = BZ2_bzDecompress(&d.stream);
      out.resize(old + grow - d.stream.avail_out);
      if (status != BZ_OK && status != BZ_STREAM_END)
        throw FormatError(context + ": corrupt bzip2 data (bzlib error " + std::to_string(status) +
                          ")");
      if (status == BZ_OK && d.stream.avail_in == 0 && d.stream.avail_out > 0)
        throw FormatError(context + ": truncated bzip2 data");
    }
    consumed += available - d.stream.avail_in;
    // Trailing bytes that cannot start another stream (padding) end the data.
    if (compressed.substr(consumed, 3) != "BZh") break;
  }
  return out;
}

std::string bzip2_compress(std::string_view bytes, int block_size_100k) {
  // bzip2's documented bound: 1% more plus 600 bytes.
  unsigned length = static_cast<unsigned>(bytes.size() + bytes.size() / 100 + 601);
  std::string out(length, '\0');
  const int status = BZ2_bzBuffToBuffCompress(out.data(), &length, const_cast<char*>(bytes.data()),
                                              static_cast<unsigned>(bytes.size()),
                                              block_size_100k, 0, 0);
  if (status != BZ_OK) throw FormatError("bzip2: compression failed (" + std::to_string(status) + ")");
  out.resize(length);
  return out;
}

}  // namespace orthofront::io::detail
