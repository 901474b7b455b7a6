#include "orthofront/io/vtk_xml.h"

#include <cstdint>

#include "orthofront/io/base64.h"
#include "orthofront/io/zlib_codec.h"

namespace orthofront::io::detail {
namespace {

constexpr std::string_view kZlib = "vtkZLibDataCompressor";

std::uint64_t load_header_value(const unsigned char* p, const VtkLayout& layout) {
  return layout.header_size == 8 ? load<std::uint64_t>(p, layout.little_endian)
                                 : load<std::uint32_t>(p, layout.little_endian);
}

}  // namespace

VtkLayout read_vtk_layout(const XmlTag& root, const std::string& file) {
  VtkLayout layout;
  if (const std::string* order = root.attribute("byte_order")) {
    if (*order != "LittleEndian" && *order != "BigEndian")
      throw FormatError(file + ": bad byte_order '" + *order + "'");
    layout.little_endian = *order == "LittleEndian";
  }
  if (const std::string* header = root.attribute("header_type")) {
    if (*header != "UInt32" && *header != "UInt64")
      throw FormatError(file + ": bad header_type '" + *header + "'");
    layout.header_size = *header == "UInt64" ? 8 : 4;
  }
  if (const std::string* compressor = root.attribute("compressor")) {
    if (!compressor->empty() && *compressor != kZlib) {
      throw FormatError(file + ": unsupported compressor '" + *compressor +
                        "' (only vtkZLibDataCompressor; save with zlib or uncompressed)");
    }
    layout.compressor = *compressor;
  }
  return layout;
}

std::optional<ScalarType> vtk_type(std::string_view name) {
  if (name == "Int8" || name == "Char") return ScalarType::kInt8;
  if (name == "UInt8" || name == "UnsignedChar") return ScalarType::kUInt8;
  if (name == "Int16") return ScalarType::kInt16;
  if (name == "UInt16") return ScalarType::kUInt16;
  if (name == "Int32") return ScalarType::kInt32;
  if (name == "UInt32") return ScalarType::kUInt32;
  if (name == "Int64") return ScalarType::kInt64;
  if (name == "UInt64") return ScalarType::kUInt64;
  if (name == "Float32") return ScalarType::kFloat32;
  if (name == "Float64") return ScalarType::kFloat64;
  return std::nullopt;
}

std::string decode_vtk_block(std::string_view bytes, const VtkLayout& layout,
                             const std::string& context, std::size_t* consumed) {
  const auto* data = reinterpret_cast<const unsigned char*>(bytes.data());
  const std::size_t h = layout.header_size;
  if (layout.compressor.empty()) {
    if (bytes.size() < h) throw FormatError(context + " ends inside its byte count");
    const std::uint64_t size = load_header_value(data, layout);
    if (size > bytes.size() - h) {
      throw FormatError(context + " declares " + std::to_string(size) + " bytes but holds " +
                        std::to_string(bytes.size() - h) + " (truncated)");
    }
    if (consumed != nullptr) *consumed = h + static_cast<std::size_t>(size);
    return std::string(bytes.substr(h, static_cast<std::size_t>(size)));
  }
  // Compressed: [number of blocks, block size, size of the last block (0: full),
  // compressed size of every block], then the blocks.
  if (bytes.size() < 3 * h) throw FormatError(context + " ends inside its compression header");
  const std::uint64_t blocks = load_header_value(data, layout);
  const std::uint64_t block_size = load_header_value(data + h, layout);
  const std::uint64_t last_size = load_header_value(data + 2 * h, layout);
  if (blocks > (bytes.size() - 3 * h) / h) {
    throw FormatError(context + " declares " + std::to_string(blocks) +
                      " compressed blocks but ends inside the block table (truncated)");
  }
  if (blocks > 0 && (block_size == 0 || last_size > block_size)) {
    throw FormatError(context + " has a bad compression header (block size " +
                      std::to_string(block_size) + ", last block " + std::to_string(last_size) +
                      ")");
  }
  std::size_t offset = (3 + static_cast<std::size_t>(blocks)) * h;
  // Block sizes near 2^64 must not wrap around to a total that fits (and then send a block's start
  // past the end of the data).
  std::uint64_t total_compressed = 0;
  bool wrapped = false;
  for (std::uint64_t b = 0; b < blocks; ++b) {
    wrapped = __builtin_add_overflow(total_compressed, load_header_value(data + (3 + b) * h, layout),
                                     &total_compressed) ||
              wrapped;
  }
  if (wrapped || total_compressed > bytes.size() - offset) {
    throw FormatError(context + " declares " +
                      (wrapped ? std::string("more than 2^64") : std::to_string(total_compressed)) +
                      " compressed bytes but holds " + std::to_string(bytes.size() - offset) +
                      " (truncated)");
  }
  std::uint64_t total = 0;
  if (blocks > 0 &&
      (__builtin_mul_overflow(blocks - 1, block_size, &total) ||
       __builtin_add_overflow(total, last_size == 0 ? block_size : last_size, &total))) {
    throw FormatError(context + " declares " + std::to_string(blocks) + " blocks of " +
                      std::to_string(block_size) + " bytes, more than 2^64 (damaged header?)");
  }
  // Deflate expands at most 1032:1: a header claiming more would have us allocate for nothing.
  constexpr double kMaxRatio = 1032.0;
  if (static_cast<double>(total) > static_cast<double>(total_compressed) * kMaxRatio + 64.0)
    throw FormatError(context + " declares " + std::to_string(total) + " bytes from " +
                      std::to_string(total_compressed) +
                      " compressed bytes, more than deflate can expand (damaged header?)");
  std::string out;
  out.reserve(static_cast<std::size_t>(total));
  for (std::uint64_t b = 0; b < blocks; ++b) {
    const auto size = static_cast<std::size_t>(load_header_value(data + (3 + b) * h, layout));
    const std::uint64_t expected = b + 1 == blocks && last_size != 0 ? last_size : block_size;
    if (static_cast<double>(expected) > static_cast<double>(size) * kMaxRatio + 64.0)
      throw FormatError(context + " block " + std::to_string(b) + " declares " +
                        std::to_string(expected) + " bytes from " + std::to_string(size) +
                        " compressed bytes, more than deflate can expand (damaged header?)");
    out += zlib_inflate(bytes.substr(offset, size), static_cast<std::size_t>(expected),
                        context + " block " + std::to_string(b));
    offset += size;
  }
  if (consumed != nullptr) *consumed = offset;
  return out;
}

std::string decode_vtk_base64(std::string_view text, const VtkLayout& layout,
                              const std::string& context) {
  // Writers encode the header and the data separately (padding inside the text) or as one
  // stream; the decoder accepts both and gives the same bytes.
  std::string bytes;
  if (!base64_decode(text, bytes)) throw FormatError(context + " is not valid base64");
  return decode_vtk_block(bytes, layout, context);
}

}  // namespace orthofront::io::detail
