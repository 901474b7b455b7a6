#pragma once
/// The parts of VTK's XML formats shared by the PolyData (.vtp) and ImageData (.vti) codecs: a
/// minimal XML scanner, the file-wide binary layout (byte order, header type, compressor) and the
/// decoding of binary data blocks, uncompressed or zlib-compressed (internal to the codecs).
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "orthofront/io/error.h"
#include "orthofront/io/scalar_codec.h"

namespace orthofront::io::detail {

// A minimal XML scan, enough for VTK's own structure (no DTDs, no namespaces).

struct XmlTag {
  std::string name;
  std::vector<std::pair<std::string, std::string>> attributes;
  bool end = false;           // </name>
  bool self_closing = false;  // <name ... />

  const std::string* attribute(std::string_view key) const {
    for (const auto& [k, v] : attributes) {
      if (k == key) return &v;
    }
    return nullptr;
  }
};

class XmlScanner {
 public:
  XmlScanner(std::string_view text, std::string file) : text_(text), file_(std::move(file)) {}

  /// Moves to the next start or end tag, skipping declarations, comments and text. False at the
  /// end of the text.
  bool next(XmlTag& tag) {
    for (;;) {
      pos_ = text_.find('<', pos_);
      if (pos_ == std::string_view::npos) {
        pos_ = text_.size();
        return false;
      }
      const std::string_view rest = text_.substr(pos_);
      if (rest.starts_with("<?")) {
        skip_past("?>");
      } else if (rest.starts_with("<!--")) {
        skip_past("-->");
      } else if (rest.starts_with("<![CDATA[")) {
        skip_past("]]>");
      } else if (rest.starts_with("<!")) {
        skip_past(">");
      } else {
        break;
      }
    }
    ++pos_;
    tag = XmlTag{};
    if (peek() == '/') {
      tag.end = true;
      ++pos_;
    }
    tag.name = read_name();
    if (tag.name.empty()) throw error("tag without a name");
    for (;;) {
      skip_spaces();
      if (peek() == '>') {
        ++pos_;
        return true;
      }
      if (text_.substr(pos_).starts_with("/>") && !tag.end) {
        tag.self_closing = true;
        pos_ += 2;
        return true;
      }
      if (tag.end) throw error("unexpected content in </" + tag.name + ">");
      std::string key = read_name();
      if (key.empty()) throw error("bad attribute in <" + tag.name + ">");
      skip_spaces();
      if (peek() != '=') throw error("attribute " + key + " of <" + tag.name + "> has no value");
      ++pos_;
      skip_spaces();
      const char quote = peek();
      if (quote != '"' && quote != '\'') throw error("unquoted value of attribute " + key);
      const std::size_t close = text_.find(quote, pos_ + 1);
      if (close == std::string_view::npos) throw error("unterminated value of attribute " + key);
      tag.attributes.emplace_back(std::move(key),
                                  decode_entities(text_.substr(pos_ + 1, close - pos_ - 1)));
      pos_ = close + 1;
    }
  }

  /// Byte offset of the scan in the text (just past the last tag read).
  std::size_t position() const { return pos_; }

  /// Character data from the current position up to the next tag.
  std::string_view text() {
    const std::size_t start = pos_;
    pos_ = std::min(text_.find('<', pos_), text_.size());
    return text_.substr(start, pos_ - start);
  }

 private:
  FormatError error(const std::string& what) const {
    return FormatError(file_ + ": malformed XML at byte " + std::to_string(pos_) + ": " + what);
  }
  char peek() const { return pos_ < text_.size() ? text_[pos_] : '\0'; }
  static bool is_space(char c) { return c == ' ' || c == '\n' || c == '\r' || c == '\t'; }
  void skip_spaces() {
    while (pos_ < text_.size() && is_space(text_[pos_])) ++pos_;
  }
  void skip_past(std::string_view terminator) {
    const std::size_t end = text_.find(terminator, pos_);
    if (end == std::string_view::npos)
      throw error("unterminated '" + std::string(terminator) + "'");
    pos_ = end + terminator.size();
  }
  std::string read_name() {
    const std::size_t start = pos_;
    while (pos_ < text_.size() && !is_space(text_[pos_]) && text_[pos_] != '=' &&
           text_[pos_] != '>' && text_[pos_] != '/' && text_[pos_] != '<') {
      ++pos_;
    }
    return std::string(text_.substr(start, pos_ - start));
  }
  static std::string decode_entities(std::string_view value) {
    std::string out;
    for (std::size_t i = 0; i < value.size(); ++i) {
      if (value[i] != '&') {
        out += value[i];
        continue;
      }
      const std::size_t semicolon = value.find(';', i);
      const std::string_view entity =
          semicolon == std::string_view::npos ? "" : value.substr(i + 1, semicolon - i - 1);
      char c = '\0';
      if (entity == "lt") c = '<';
      if (entity == "gt") c = '>';
      if (entity == "amp") c = '&';
      if (entity == "quot") c = '"';
      if (entity == "apos") c = '\'';
      if (c == '\0') {
        out += '&';  // not one of the five predefined entities: kept as written
      } else {
        out += c;
        i = semicolon;
      }
    }
    return out;
  }

  std::string_view text_;
  std::string file_;
  std::size_t pos_ = 0;
};

/// How a VTK XML file stores binary data: from the attributes of its <VTKFile> element.
struct VtkLayout {
  bool little_endian = true;
  std::size_t header_size = 4;  ///< UInt32 unless header_type says otherwise
  std::string compressor;       ///< empty, or the compressor's class name
};

/// Reads byte_order, header_type and compressor from the <VTKFile> tag. Throws FormatError naming
/// `file` for a bad value and for a compressor other than vtkZLibDataCompressor.
VtkLayout read_vtk_layout(const XmlTag& root, const std::string& file);

/// The scalar type of a DataArray type name ("Float32", "Int64", ...).
std::optional<ScalarType> vtk_type(std::string_view name);

/// One binary data block as VTK writes it, starting at `bytes`: a byte count (uncompressed) or a
/// block table followed by zlib blocks (compressed). Returns the data bytes, uncompressed, and sets
/// `consumed` to the bytes the block took. Throws FormatError starting with `context` when the
/// block is truncated, damaged or inconsistent.
std::string decode_vtk_block(std::string_view bytes, const VtkLayout& layout,
                             const std::string& context, std::size_t* consumed = nullptr);

/// The same for an inline binary array or an appended base64 array: `text` is its base64 text.
std::string decode_vtk_base64(std::string_view text, const VtkLayout& layout,
                              const std::string& context);

}  // namespace orthofront::io::detail
