#include "orthofront/io/ply_codec.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <vector>

#include "orthofront/io/error.h"
#include "orthofront/io/mesh_attributes.h"
#include "orthofront/io/number_text.h"
#include "orthofront/io/scalar_codec.h"

namespace orthofront::io::detail {
namespace {

struct PlyProperty {
  std::string name;
  ScalarType type = ScalarType::kFloat64;
  bool is_list = false;
  ScalarType count_type = ScalarType::kUInt8;
};

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::vector<PlyProperty> properties;
};

enum class PlyEncoding { kAscii, kBinaryLittleEndian, kBinaryBigEndian };

struct PlyHeader {
  PlyEncoding encoding = PlyEncoding::kAscii;
  std::vector<PlyElement> elements;
  std::size_t body_offset = 0;
};

std::optional<ScalarType> ply_type(std::string_view name) {
  if (name == "char" || name == "int8") return ScalarType::kInt8;
  if (name == "uchar" || name == "uint8") return ScalarType::kUInt8;
  if (name == "short" || name == "int16") return ScalarType::kInt16;
  if (name == "ushort" || name == "uint16") return ScalarType::kUInt16;
  if (name == "int" || name == "int32") return ScalarType::kInt32;
  if (name == "uint" || name == "uint32") return ScalarType::kUInt32;
  if (name == "float" || name == "float32") return ScalarType::kFloat32;
  if (name == "double" || name == "float64") return ScalarType::kFloat64;
  return std::nullopt;
}

std::vector<std::string_view> split_words(std::string_view line) {
  std::vector<std::string_view> words;
  std::size_t pos = 0;
  while (pos < line.size()) {
    while (pos < line.size() && (line[pos] == ' ' || line[pos] == '\t')) ++pos;
    const std::size_t start = pos;
    while (pos < line.size() && line[pos] != ' ' && line[pos] != '\t') ++pos;
    if (pos > start) words.push_back(line.substr(start, pos - start));
  }
  return words;
}

PlyHeader parse_header(std::string_view data, const std::string& file) {
  PlyHeader header;
  bool have_format = false;
  std::size_t pos = 0;
  for (int line_number = 1;; ++line_number) {
    const std::size_t eol = data.find('\n', pos);
    if (eol == std::string_view::npos) {
      throw FormatError(file + (line_number == 1 ? ": not a PLY file (empty or no header)"
                                                 : ": PLY header has no end_header line"));
    }
    std::string_view line = data.substr(pos, eol - pos);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    pos = eol + 1;
    const auto words = split_words(line);
    const auto bad_line = [&](const std::string& what) {
      return FormatError(file + ": PLY header line " + std::to_string(line_number) + " '" +
                         std::string(line) + "': " + what);
    };
    if (line_number == 1) {
      if (words.size() != 1 || words[0] != "ply") {
        throw FormatError(file + ": not a PLY file (first line is not 'ply')");
      }
      continue;
    }
    if (words.empty() || words[0] == "comment" || words[0] == "obj_info") continue;
    if (words[0] == "end_header") break;
    if (words[0] == "format") {
      if (words.size() != 3) throw bad_line("expected 'format <encoding> 1.0'");
      if (words[1] == "ascii") {
        header.encoding = PlyEncoding::kAscii;
      } else if (words[1] == "binary_little_endian") {
        header.encoding = PlyEncoding::kBinaryLittleEndian;
      } else if (words[1] == "binary_big_endian") {
        header.encoding = PlyEncoding::kBinaryBigEndian;
      } else {
        throw bad_line("unknown encoding");
      }
      have_format = true;
    } else if (words[0] == "element") {
      PlyElement element;
      if (words.size() != 3 || !parse_number(words[2], element.count)) {
        throw bad_line("expected 'element <name> <count>'");
      }
      element.name = words[1];
      header.elements.push_back(std::move(element));
    } else if (words[0] == "property") {
      if (header.elements.empty()) throw bad_line("property before any element");
      PlyProperty property;
      if (words.size() == 5 && words[1] == "list") {
        const auto count_type = ply_type(words[2]);
        const auto item_type = ply_type(words[3]);
        if (!count_type || !item_type || !is_integer(*count_type)) {
          throw bad_line("unknown or unsuitable list types");
        }
        property.is_list = true;
        property.count_type = *count_type;
        property.type = *item_type;
        property.name = words[4];
      } else if (words.size() == 3) {
        const auto type = ply_type(words[1]);
        if (!type) throw bad_line("unknown property type");
        property.type = *type;
        property.name = words[2];
      } else {
        throw bad_line("expected 'property <type> <name>' or 'property list <type> <type> <name>'");
      }
      header.elements.back().properties.push_back(std::move(property));
    } else {
      throw bad_line("unknown keyword");
    }
  }
  if (!have_format) throw FormatError(file + ": PLY header has no format line");
  header.body_offset = pos;
  return header;
}

enum class ReadStatus { kOk, kEnd, kBad };

/// Values of a binary body, in the file's byte order.
class BinarySource {
 public:
  BinarySource(std::string_view body, bool little_endian)
      : pos_(reinterpret_cast<const unsigned char*>(body.data())),
        end_(pos_ + body.size()),
        little_endian_(little_endian) {}

  ReadStatus read(ScalarType type, double& value) {
    const std::size_t size = scalar_size(type);
    if (static_cast<std::size_t>(end_ - pos_) < size) return ReadStatus::kEnd;
    value = load_real(type, pos_, little_endian_);
    pos_ += size;
    return ReadStatus::kOk;
  }
  std::string_view last_token() const { return {}; }
  /// The fewest bytes a value of `type` takes.
  static std::size_t min_bytes(ScalarType type) { return scalar_size(type); }
  std::size_t remaining() const { return static_cast<std::size_t>(end_ - pos_); }

 private:
  const unsigned char* pos_;
  const unsigned char* end_;
  bool little_endian_;
};

/// Values of an ascii body: whitespace-separated numbers (line breaks carry no meaning).
class AsciiSource {
 public:
  explicit AsciiSource(std::string_view body) : body_(body) {}

  ReadStatus read(ScalarType /*type*/, double& value) {
    while (pos_ < body_.size() && is_space(body_[pos_])) ++pos_;
    if (pos_ == body_.size()) return ReadStatus::kEnd;
    const std::size_t start = pos_;
    while (pos_ < body_.size() && !is_space(body_[pos_])) ++pos_;
    token_ = body_.substr(start, pos_ - start);
    return parse_number(token_, value) ? ReadStatus::kOk : ReadStatus::kBad;
  }
  std::string_view last_token() const { return token_; }
  /// The fewest bytes a value takes: a character and a separator.
  static std::size_t min_bytes(ScalarType /*type*/) { return 2; }
  std::size_t remaining() const { return body_.size() - pos_; }

 private:
  static bool is_space(char c) { return c == ' ' || c == '\n' || c == '\r' || c == '\t'; }
  std::string_view body_;
  std::size_t pos_ = 0;
  std::string_view token_;
};

std::string plural(const std::string& element) {
  if (element == "vertex") return "vertices";
  if (element == "face") return "faces";
  return element + " elements";
}

/// Where a vertex property goes in the mesh.
struct VertexTarget {
  int coordinate = -1;                           // 0..2 for x, y, z
  Mesh::Array<double>* real = nullptr;          // a real attribute
  Mesh::Array<std::int32_t>* integer = nullptr;// an integer attribute
};

template <class Source>
class BodyReader {
 public:
  BodyReader(Source& source, const std::string& file) : source_(source), file_(file) {}

  Mesh read(const PlyHeader& header) {
    Mesh mesh;
    bool have_vertices = false;
    bool have_faces = false;
    for (const PlyElement& element : header.elements) {
      if (element.name == "vertex" && !have_vertices) {
        read_vertices(element, mesh);
        have_vertices = true;
      } else if (element.name == "face" && !have_faces) {
        read_faces(element, mesh);
        have_faces = true;
      } else if (!element.properties.empty()) {  // nothing to read for an element without any
        for (std::uint64_t i = 0; i < element.count; ++i) {
          for (const PlyProperty& property : element.properties) skip(element, i, property);
        }
      }
    }
    // Checked last: the PLY format does not require vertices to precede faces.
    for (std::size_t i = 0; i < mesh.faces.size(); ++i) {
      const Face& face = mesh.faces[i];
      for (int k = 0; k < face.size; ++k) {
        if (static_cast<std::size_t>(face.v[k]) >= mesh.positions.size()) {
          throw FormatError(file_ + ": face " + std::to_string(i) + " refers to vertex " +
                            std::to_string(face.v[k]) + " but there are " +
                            std::to_string(mesh.positions.size()) + " vertices");
        }
      }
    }
    return mesh;
  }

 private:
  double value(ScalarType type, const PlyElement& element, std::uint64_t index,
               const PlyProperty& property) {
    double result = 0.0;
    switch (source_.read(type, result)) {
      case ReadStatus::kOk:
        break;
      case ReadStatus::kEnd:
        throw FormatError(file_ + ": " + element.name + " count " + std::to_string(element.count) +
                          " but file ends after " + std::to_string(index) + " " +
                          plural(element.name));
      case ReadStatus::kBad:
        throw FormatError(file_ + ": bad value '" + std::string(source_.last_token()) +
                          "' for property " + property.name + " of " + element.name + " " +
                          std::to_string(index));
    }
    return result;
  }

  std::uint64_t list_count(const PlyElement& element, std::uint64_t index,
                           const PlyProperty& property) {
    const double count = value(property.count_type, element, index, property);
    if (!(count >= 0.0) || count != std::floor(count)) {
      throw FormatError(file_ + ": bad list length " + std::to_string(count) + " for property " +
                        property.name + " of " + element.name + " " + std::to_string(index));
    }
    return static_cast<std::uint64_t>(count);
  }

  void skip(const PlyElement& element, std::uint64_t index, const PlyProperty& property) {
    const std::uint64_t n = property.is_list ? list_count(element, index, property) : 1;
    for (std::uint64_t k = 0; k < n; ++k) value(property.type, element, index, property);
  }

  // A corrupt count must not make the reader allocate before it finds the file short: the
  // reservation is no more elements than the rest of the body can hold (each takes at least one
  // value per property) and at most 2^20; more grow as they are read.
  std::size_t reserve_hint(const PlyElement& element) const {
    std::size_t min_element = 0;
    for (const PlyProperty& property : element.properties)
      min_element += Source::min_bytes(property.is_list ? property.count_type : property.type);
    const std::uint64_t fit = (source_.remaining() + 1) / std::max<std::size_t>(min_element, 1);
    return static_cast<std::size_t>(std::min<std::uint64_t>({element.count, fit, 1u << 20}));
  }

  void read_vertices(const PlyElement& element, Mesh& mesh) {
    if (element.count > static_cast<std::uint64_t>(std::numeric_limits<std::int32_t>::max())) {
      throw FormatError(file_ + ": vertex count " + std::to_string(element.count) +
                        " exceeds the supported 2^31 - 1");
    }
    std::vector<VertexTarget> targets(element.properties.size());
    bool have_coordinate[3] = {false, false, false};
    for (std::size_t p = 0; p < element.properties.size(); ++p) {
      const PlyProperty& property = element.properties[p];
      bool repeated = property.is_list;  // lists and repeated names are read but not used
      for (std::size_t q = 0; q < p && !repeated; ++q) {
        repeated = element.properties[q].name == property.name;
      }
      if (repeated) continue;
      VertexTarget& target = targets[p];
      if (property.name.size() == 1 && property.name[0] >= 'x' && property.name[0] <= 'z') {
        target.coordinate = property.name[0] - 'x';
        have_coordinate[target.coordinate] = true;
      }
      for (const RealAttribute& attribute : kRealAttributes) {
        if (property.name == attribute.name) target.real = &(mesh.*attribute.values);
      }
      for (const IntAttribute& attribute : kIntAttributes) {
        if (property.name == attribute.name) target.integer = &(mesh.*attribute.values);
      }
      if (target.real != nullptr) target.real->reserve(reserve_hint(element));
      if (target.integer != nullptr) target.integer->reserve(reserve_hint(element));
    }
    if (!have_coordinate[0] || !have_coordinate[1] || !have_coordinate[2]) {
      throw FormatError(file_ + ": vertex element lacks one of the properties x, y, z");
    }
    mesh.positions.reserve(reserve_hint(element));
    for (std::uint64_t i = 0; i < element.count; ++i) {
      Vec3 position = Vec3::Zero();
      for (std::size_t p = 0; p < element.properties.size(); ++p) {
        const PlyProperty& property = element.properties[p];
        if (property.is_list) {
          skip(element, i, property);
          continue;
        }
        const double v = value(property.type, element, i, property);
        const VertexTarget& target = targets[p];
        if (target.coordinate >= 0) {
          position[target.coordinate] = v;
        } else if (target.real != nullptr) {
          target.real->push_back(v);
        } else if (target.integer != nullptr) {
          if (!(v >= std::numeric_limits<std::int32_t>::min() &&
                v <= std::numeric_limits<std::int32_t>::max())) {
            throw FormatError(file_ + ": value " + std::to_string(v) + " of property " +
                              property.name + " of vertex " + std::to_string(i) +
                              " does not fit a 32-bit integer");
          }
          target.integer->push_back(static_cast<std::int32_t>(v));
        }
      }
      mesh.positions.push_back(position);
    }
  }

  void read_faces(const PlyElement& element, Mesh& mesh) {
    std::size_t indices = element.properties.size();
    for (std::size_t p = 0; p < element.properties.size() && indices == element.properties.size();
         ++p) {
      const PlyProperty& property = element.properties[p];
      if (property.is_list &&
          (property.name == "vertex_indices" || property.name == "vertex_index")) {
        indices = p;
      }
    }
    if (indices == element.properties.size()) {
      throw FormatError(file_ + ": face element has no list property vertex_indices");
    }
    mesh.faces.reserve(reserve_hint(element));
    for (std::uint64_t i = 0; i < element.count; ++i) {
      Face face;
      for (std::size_t p = 0; p < element.properties.size(); ++p) {
        const PlyProperty& property = element.properties[p];
        if (p != indices) {
          skip(element, i, property);
          continue;
        }
        const std::uint64_t n = list_count(element, i, property);
        if (n < 3 || n > 4) {
          throw FormatError(file_ + ": face " + std::to_string(i) + " has " + std::to_string(n) +
                            " vertices; only triangles and quads are supported");
        }
        face.size = static_cast<std::uint8_t>(n);
        for (std::uint64_t k = 0; k < n; ++k) {
          const double v = value(property.type, element, i, property);
          if (!(v >= 0.0 && v <= std::numeric_limits<std::int32_t>::max()) || v != std::floor(v)) {
            throw FormatError(file_ + ": face " + std::to_string(i) + " has the bad vertex index " +
                              std::to_string(v));
          }
          face.v[k] = static_cast<std::int32_t>(v);
        }
      }
      mesh.faces.push_back(face);
    }
  }

  Source& source_;
  const std::string& file_;
};

}  // namespace

void write_ply(const Mesh& mesh, std::ostream& out) {
  std::string header =
      "ply\nformat binary_little_endian 1.0\ncomment orthofront mesh\nelement vertex " +
      std::to_string(mesh.positions.size()) +
      "\nproperty double x\nproperty double y\nproperty double z\n";
  std::vector<const Mesh::Array<double>*> reals;
  std::vector<const Mesh::Array<std::int32_t>*> integers;
  for (const RealAttribute& attribute : kRealAttributes) {
    if (!is_recorded(mesh, mesh.*attribute.values)) continue;
    header += std::string("property double ") + attribute.name + "\n";
    reals.push_back(&(mesh.*attribute.values));
  }
  for (const IntAttribute& attribute : kIntAttributes) {
    if (!is_recorded(mesh, mesh.*attribute.values)) continue;
    header += std::string("property int ") + attribute.name + "\n";
    integers.push_back(&(mesh.*attribute.values));
  }
  header += "element face " + std::to_string(mesh.faces.size()) +
            "\nproperty list uchar int vertex_indices\nend_header\n";
  out.write(header.data(), static_cast<std::streamsize>(header.size()));

  // The body goes out in chunks: one buffer of the whole mesh would double its memory.
  constexpr std::size_t kChunk = 1 << 20;
  std::string buffer;
  buffer.reserve(kChunk + 256);
  const auto flush = [&](bool force) {
    if (buffer.size() < kChunk && !force) return;
    out.write(buffer.data(), static_cast<std::streamsize>(buffer.size()));
    buffer.clear();
  };
  for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
    for (int c = 0; c < 3; ++c) store_le<double>(buffer, mesh.positions[i][c]);
    for (const auto* values : reals) store_le<double>(buffer, (*values)[i]);
    for (const auto* values : integers) store_le<std::int32_t>(buffer, (*values)[i]);
    flush(false);
  }
  for (const Face& face : mesh.faces) {
    store_le<std::uint8_t>(buffer, face.size);
    for (int k = 0; k < face.size; ++k) store_le<std::int32_t>(buffer, face.v[k]);
    flush(false);
  }
  flush(true);
}

Mesh read_ply(std::string_view data, const std::string& file) {
  const PlyHeader header = parse_header(data, file);
  const std::string_view body = data.substr(header.body_offset);
  if (header.encoding == PlyEncoding::kAscii) {
    AsciiSource source(body);
    return BodyReader<AsciiSource>(source, file).read(header);
  }
  BinarySource source(body, header.encoding == PlyEncoding::kBinaryLittleEndian);
  return BodyReader<BinarySource>(source, file).read(header);
}

}  // namespace orthofront::io::detail
