#include "orthofront/io/vtp_codec.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <utility>
#include <vector>

#include "orthofront/io/base64.h"
#include "orthofront/io/vtk_xml.h"
#include "orthofront/io/xml_text.h"
#include "orthofront/io/error.h"
#include "orthofront/io/mesh_attributes.h"
#include "orthofront/io/number_text.h"
#include "orthofront/io/scalar_codec.h"

namespace orthofront::io::detail {
namespace {

// ---------------------------------------------------------------------------------------------
// Writing

/// Base64-encodes little-endian values straight into the stream, in chunks, so that a large
/// array is never held twice in memory.
class Base64Stream {
 public:
  explicit Base64Stream(std::ostream& out) : out_(out) { pending_.reserve(kChunk + 16); }

  template <typename T>
  void put(T value) {
    store_le<T>(pending_, value);
    if (pending_.size() >= kChunk) drain(false);
  }
  void finish() { drain(true); }

 private:
  // A multiple of 3 bytes, so that chunks concatenate to one unbroken base64 text.
  static constexpr std::size_t kChunk = 3 << 20;

  void drain(bool all) {
    const std::size_t n = all ? pending_.size() : pending_.size() / 3 * 3;
    base64_encode(std::string_view(pending_).substr(0, n), text_);
    out_.write(text_.data(), static_cast<std::streamsize>(text_.size()));
    pending_.erase(0, n);
  }

  std::ostream& out_;
  std::string pending_;
  std::string text_;  ///< a chunk's base64, its storage kept from chunk to chunk
};

void write_text(std::ostream& out, const std::string& text) {
  out.write(text.data(), static_cast<std::streamsize>(text.size()));
}

/// Writes one inline binary DataArray: a UInt64 byte count, then `count` values from `value(i)`.
template <typename T, typename ValueAt>
void write_array(std::ostream& out, const char* type, const std::string& name, int components,
                 std::size_t count, ValueAt value) {
  std::string open = std::string("        <DataArray type=\"") + type + "\" Name=\"" + name + "\"";
  if (components != 1) open += " NumberOfComponents=\"" + std::to_string(components) + "\"";
  write_text(out, open + " format=\"binary\">\n          ");
  Base64Stream stream(out);
  stream.put<std::uint64_t>(count * sizeof(T));
  for (std::size_t i = 0; i < count; ++i) stream.put<T>(value(i));
  stream.finish();
  write_text(out, "\n        </DataArray>\n");
}

// ---------------------------------------------------------------------------------------------
// Reading: VTK structure

/// A decoded DataArray: integer types in `integer`, floating-point types in `real`.
struct ArrayData {
  ScalarType type = ScalarType::kFloat64;
  std::size_t components = 1;
  std::vector<double> real;
  std::vector<std::int64_t> integer;

  std::size_t values() const { return is_integer(type) ? integer.size() : real.size(); }
  std::size_t tuples() const { return values() / components; }
  double real_at(std::size_t i) const {
    return is_integer(type) ? static_cast<double>(integer[i]) : real[i];
  }
};

struct PieceData {
  std::uint64_t points = 0;
  std::uint64_t polys = 0;
  std::uint64_t strips = 0;
  std::optional<ArrayData> positions;
  std::optional<ArrayData> poly_connectivity;
  std::optional<ArrayData> poly_offsets;
  std::optional<ArrayData> strip_connectivity;
  std::optional<ArrayData> strip_offsets;
  std::vector<std::pair<std::string, ArrayData>> point_data;
};

class VtpReader {
 public:
  VtpReader(std::string_view data, const std::string& file) : xml_(data, file), file_(file) {}

  Mesh read() {
    XmlTag tag;
    std::vector<std::string> open;  // enclosing elements
    bool have_root = false;
    while (xml_.next(tag)) {
      if (tag.end) {
        if (open.empty() || open.back() != tag.name) {
          throw error("unexpected </" + tag.name + ">" +
                      (open.empty() ? std::string() : " inside <" + open.back() + ">"));
        }
        open.pop_back();
        if (tag.name == "Piece" && piece_) finish_piece();
        continue;
      }
      const std::string parent = open.empty() ? std::string() : open.back();
      if (tag.name == "VTKFile" && open.empty()) {
        read_root(tag);
        have_root = true;
      } else if (!have_root) {
        throw error("not a VTK XML file (no <VTKFile> element)");
      } else if (tag.name == "AppendedData") {
        // Raw appended data is binary and not XML; every array that used it was rejected already.
        open.clear();
        break;
      } else if (tag.name == "Piece" && parent == "PolyData") {
        start_piece(tag);
      } else if (tag.name == "DataArray") {
        read_data_array(tag, parent);
      } else if (tag.name == "Array" && parent == "FieldData") {
        read_note(tag);
      }
      if (!tag.self_closing) open.push_back(tag.name);
    }
    if (!have_root) throw error("not a VTK XML file (no <VTKFile> element)");
    if (!open.empty()) throw error("file ends inside <" + open.back() + ">");
    if (pieces_ == 0) throw error("no PolyData <Piece> element");
    // An attribute is kept only when every piece carried it.
    for (const RealAttribute& attribute : kRealAttributes) {
      if ((mesh_.*attribute.values).size() != mesh_.positions.size()) {
        (mesh_.*attribute.values).clear();
      }
    }
    for (const IntAttribute& attribute : kIntAttributes) {
      if ((mesh_.*attribute.values).size() != mesh_.positions.size()) {
        (mesh_.*attribute.values).clear();
      }
    }
    return std::move(mesh_);
  }

 private:
  FormatError error(const std::string& what) const { return FormatError(file_ + ": " + what); }

  std::uint64_t count_attribute(const XmlTag& tag, std::string_view key) const {
    const std::string* text = tag.attribute(key);
    std::uint64_t value = 0;
    if (text != nullptr && !parse_number(*text, value)) {
      throw error("bad " + std::string(key) + " '" + *text + "' in <" + tag.name + ">");
    }
    return value;
  }

  void read_root(const XmlTag& tag) {
    const std::string* type = tag.attribute("type");
    if (type == nullptr || *type != "PolyData") {
      throw error("VTK file type is '" + (type ? *type : std::string()) + "', expected PolyData");
    }
    layout_ = read_vtk_layout(tag, file_);
  }

  void start_piece(const XmlTag& tag) {
    piece_.emplace();
    piece_->points = count_attribute(tag, "NumberOfPoints");
    piece_->polys = count_attribute(tag, "NumberOfPolys");
    piece_->strips = count_attribute(tag, "NumberOfStrips");
    if (tag.self_closing) finish_piece();
  }

  void read_data_array(const XmlTag& tag, const std::string& parent) {
    const std::string* name_attribute = tag.attribute("Name");
    const std::string name = name_attribute ? *name_attribute : std::string();
    const std::string what = parent + " DataArray" + (name.empty() ? "" : " '" + name + "'");
    const std::string* format = tag.attribute("format");
    if (format != nullptr && *format == "appended") {
      throw error(what +
                  " uses appended data, which is not supported (save inline ascii or "
                  "binary data, e.g. ParaView's 'Data Mode' ascii or binary)");
    }
    const std::string_view content = tag.self_closing ? std::string_view() : xml_.text();
    if (!piece_) return;
    const bool is_attribute = [&] {
      for (const RealAttribute& a : kRealAttributes) {
        if (name == a.name) return true;
      }
      for (const IntAttribute& a : kIntAttributes) {
        if (name == a.name) return true;
      }
      return false;
    }();
    if (parent == "Points") {
      piece_->positions = decode(tag, content, what);
    } else if ((parent == "Polys" || parent == "Strips") &&
               (name == "connectivity" || name == "offsets")) {
      const bool polys = parent == "Polys";
      auto& slot = name == "connectivity"
                       ? (polys ? piece_->poly_connectivity : piece_->strip_connectivity)
                       : (polys ? piece_->poly_offsets : piece_->strip_offsets);
      slot = decode(tag, content, what);
    } else if (parent == "PointData" && is_attribute) {
      piece_->point_data.emplace_back(name, decode(tag, content, what));
    }
  }

  // A field-data string array in ascii: byte values, each string ended by a 0 (the first kept).
  void read_note(const XmlTag& tag) {
    const std::string* type = tag.attribute("type");
    const std::string* format = tag.attribute("format");
    const std::string* name = tag.attribute("Name");
    const std::string_view content = tag.self_closing ? std::string_view() : xml_.text();
    if (type == nullptr || *type != "String" || format == nullptr || *format != "ascii" ||
        name == nullptr)
      return;  // other field data: not a note
    std::string text;
    std::size_t at = 0;
    while (at < content.size()) {
      while (at < content.size() && std::isspace(static_cast<unsigned char>(content[at]))) ++at;
      if (at >= content.size()) break;
      unsigned value = 0;
      const auto [end, ec] = std::from_chars(content.data() + at, content.data() + content.size(), value);
      if (ec != std::errc() || value > 255)
        throw error("field data '" + *name + "' is not a string array of byte values");
      at = static_cast<std::size_t>(end - content.data());
      if (value == 0) break;
      text += static_cast<char>(value);
    }
    mesh_.notes.emplace_back(*name, std::move(text));
  }

  ArrayData decode(const XmlTag& tag, std::string_view content, const std::string& what) const {
    ArrayData array;
    const std::string* type_name = tag.attribute("type");
    const auto type = type_name ? vtk_type(*type_name) : std::nullopt;
    if (!type) throw error(what + " has unsupported type '" + (type_name ? *type_name : "") + "'");
    array.type = *type;
    if (const std::string* components = tag.attribute("NumberOfComponents")) {
      if (!parse_number(*components, array.components) || array.components == 0) {
        throw error(what + " has bad NumberOfComponents '" + *components + "'");
      }
    }
    const std::string* format = tag.attribute("format");
    if (format != nullptr && *format == "ascii") {
      decode_ascii(content, what, array);
    } else if (format != nullptr && *format == "binary") {
      decode_binary(content, what, array);
    } else {
      throw error(what + " has unsupported format '" + (format ? *format : "") + "'");
    }
    if (array.values() % array.components != 0) {
      throw error(what + " has " + std::to_string(array.values()) + " values, not a multiple of " +
                  std::to_string(array.components) + " components");
    }
    return array;
  }

  void decode_ascii(std::string_view content, const std::string& what, ArrayData& array) const {
    std::size_t pos = 0;
    const auto is_space = [](char c) { return c == ' ' || c == '\n' || c == '\r' || c == '\t'; };
    for (;;) {
      while (pos < content.size() && is_space(content[pos])) ++pos;
      if (pos == content.size()) break;
      const std::size_t start = pos;
      while (pos < content.size() && !is_space(content[pos])) ++pos;
      const std::string_view token = content.substr(start, pos - start);
      bool ok = false;
      if (is_integer(array.type)) {
        ok = parse_number(token, array.integer.emplace_back());
      } else {
        ok = parse_number(token, array.real.emplace_back());
      }
      if (!ok) throw error(what + " has the bad value '" + std::string(token) + "'");
    }
  }

  void decode_binary(std::string_view content, const std::string& what, ArrayData& array) const {
    const std::string bytes = decode_vtk_base64(content, layout_, file_ + ": " + what);
    const auto* data = reinterpret_cast<const unsigned char*>(bytes.data());
    const std::size_t size = bytes.size();
    const std::size_t scalar = scalar_size(array.type);
    if (size % scalar != 0) {
      throw error(what + " holds " + std::to_string(size) + " bytes, not a multiple of " +
                  std::to_string(scalar));
    }
    const std::size_t count = static_cast<std::size_t>(size) / scalar;
    if (is_integer(array.type)) {
      array.integer.resize(count);
      for (std::size_t i = 0; i < count; ++i) {
        array.integer[i] = load_integer(array.type, data + i * scalar, layout_.little_endian);
      }
    } else {
      array.real.resize(count);
      for (std::size_t i = 0; i < count; ++i) {
        array.real[i] = load_real(array.type, data + i * scalar, layout_.little_endian);
      }
    }
  }

  /// Index-like values as integers; floating-point arrays must hold whole numbers.
  std::vector<std::int64_t> integers(const ArrayData& array, const std::string& what) const {
    if (is_integer(array.type)) return array.integer;
    std::vector<std::int64_t> result(array.real.size());
    for (std::size_t i = 0; i < array.real.size(); ++i) {
      const double v = array.real[i];
      if (!(std::abs(v) < 9.0e18) || v != std::floor(v)) {
        throw error(what + " value " + std::to_string(v) + " is not an integer");
      }
      result[i] = static_cast<std::int64_t>(v);
    }
    return result;
  }

  /// Cells given as connectivity plus end offsets; calls add(first, size) per cell.
  template <typename Add>
  void for_each_cell(const std::optional<ArrayData>& connectivity,
                     const std::optional<ArrayData>& offsets, std::uint64_t cells,
                     const std::string& kind, std::vector<std::int64_t>& indices, Add add) const {
    if (cells == 0) return;
    if (!connectivity || !offsets) {
      throw error(piece_name() + " has " + std::to_string(cells) + " " + kind +
                  " but no connectivity/offsets arrays");
    }
    indices = integers(*connectivity, kind + " connectivity");
    const std::vector<std::int64_t> ends = integers(*offsets, kind + " offsets");
    if (ends.size() != cells) {
      throw error(piece_name() + ": NumberOf" + kind + " is " + std::to_string(cells) +
                  " but there are " + std::to_string(ends.size()) + " offsets");
    }
    std::int64_t begin = 0;
    for (std::size_t c = 0; c < ends.size(); ++c) {
      if (ends[c] < begin || ends[c] > static_cast<std::int64_t>(indices.size())) {
        throw error(piece_name() + ": " + kind + " offset " + std::to_string(ends[c]) +
                    " of cell " + std::to_string(c) +
                    " is out of order or beyond the connectivity");
      }
      add(c, static_cast<std::size_t>(begin), static_cast<std::size_t>(ends[c] - begin));
      begin = ends[c];
    }
  }

  std::string piece_name() const { return "piece " + std::to_string(pieces_); }

  void finish_piece() {
    PieceData& piece = *piece_;
    const std::size_t base = mesh_.positions.size();
    const std::uint64_t n = piece.points;
    if (base + n > static_cast<std::uint64_t>(std::numeric_limits<std::int32_t>::max())) {
      throw error("point count " + std::to_string(base + n) + " exceeds the supported 2^31 - 1");
    }
    if (n > 0) {
      if (!piece.positions) throw error(piece_name() + " has no Points array");
      if (piece.positions->components != 3) {
        throw error(piece_name() + ": Points have " + std::to_string(piece.positions->components) +
                    " components, expected 3");
      }
      if (piece.positions->tuples() != n) {
        throw error(piece_name() + ": NumberOfPoints is " + std::to_string(n) +
                    " but Points holds " + std::to_string(piece.positions->tuples()));
      }
      for (std::size_t i = 0; i < n; ++i) {
        mesh_.positions.emplace_back(piece.positions->real_at(3 * i),
                                     piece.positions->real_at(3 * i + 1),
                                     piece.positions->real_at(3 * i + 2));
      }
    }
    const auto vertex = [&](std::int64_t index, const std::string& kind, std::size_t cell) {
      if (index < 0 || static_cast<std::uint64_t>(index) >= n) {
        throw error(piece_name() + ": " + kind + " cell " + std::to_string(cell) +
                    " refers to point " + std::to_string(index) + " but there are " +
                    std::to_string(n) + " points");
      }
      return static_cast<std::int32_t>(base + static_cast<std::size_t>(index));
    };
    std::vector<std::int64_t> indices;
    for_each_cell(piece.poly_connectivity, piece.poly_offsets, piece.polys, "Polys", indices,
                  [&](std::size_t cell, std::size_t first, std::size_t size) {
                    if (size < 3 || size > 4) {
                      throw error(piece_name() + ": polygon " + std::to_string(cell) + " has " +
                                  std::to_string(size) +
                                  " vertices; only triangles and quads are supported");
                    }
                    Face face;
                    face.size = static_cast<std::uint8_t>(size);
                    for (std::size_t k = 0; k < size; ++k) {
                      face.v[k] = vertex(indices[first + k], "Polys", cell);
                    }
                    mesh_.faces.push_back(face);
                  });
    // Strips become triangles, every other one flipped to keep the orientation.
    for_each_cell(piece.strip_connectivity, piece.strip_offsets, piece.strips, "Strips", indices,
                  [&](std::size_t cell, std::size_t first, std::size_t size) {
                    for (std::size_t k = 0; k + 2 < size; ++k) {
                      const std::size_t a = first + k + (k % 2 == 0 ? 0 : 1);
                      const std::size_t b = first + k + (k % 2 == 0 ? 1 : 0);
                      mesh_.add_triangle(vertex(indices[a], "Strips", cell),
                                         vertex(indices[b], "Strips", cell),
                                         vertex(indices[first + k + 2], "Strips", cell));
                    }
                  });
    for (const auto& [name, array] : piece.point_data) {
      if (array.components != 1) continue;  // not one of ours, whatever its name
      if (array.tuples() != n) {
        throw error(piece_name() + ": point data '" + name + "' has " +
                    std::to_string(array.tuples()) + " values for " + std::to_string(n) +
                    " points");
      }
      for (const RealAttribute& attribute : kRealAttributes) {
        if (name != attribute.name) continue;
        Mesh::Array<double>& values = mesh_.*attribute.values;
        for (std::size_t i = 0; i < n; ++i) values.push_back(array.real_at(i));
      }
      for (const IntAttribute& attribute : kIntAttributes) {
        if (name != attribute.name) continue;
        Mesh::Array<std::int32_t>& values = mesh_.*attribute.values;
        for (const std::int64_t v : integers(array, "point data '" + name + "'")) {
          if (v < std::numeric_limits<std::int32_t>::min() ||
              v > std::numeric_limits<std::int32_t>::max()) {
            throw error(piece_name() + ": point data '" + name + "' value " + std::to_string(v) +
                        " does not fit a 32-bit integer");
          }
          values.push_back(static_cast<std::int32_t>(v));
        }
      }
    }
    piece_.reset();
    ++pieces_;
  }

  XmlScanner xml_;
  const std::string& file_;
  VtkLayout layout_;
  std::optional<PieceData> piece_;
  std::size_t pieces_ = 0;
  Mesh mesh_;
};

}  // namespace

void write_vtp(const Mesh& mesh, std::ostream& out) {
  const std::size_t n = mesh.positions.size();
  write_text(out,
             "<?xml version=\"1.0\"?>\n"
             "<VTKFile type=\"PolyData\" version=\"0.1\" byte_order=\"LittleEndian\" "
             "header_type=\"UInt64\">\n"
             "  <PolyData>\n");
  if (!mesh.notes.empty()) {
    // String arrays as VTK writes them: each string's bytes as numbers, then a 0.
    write_text(out, "    <FieldData>\n");
    for (const auto& [name, text] : mesh.notes) {
      std::string codes;
      for (const unsigned char c : text) codes += std::to_string(static_cast<int>(c)) + " ";
      write_text(out, "      <Array type=\"String\" Name=\"" + xml_escaped(name) +
                          "\" NumberOfTuples=\"1\" format=\"ascii\">\n        " + codes +
                          "0\n      </Array>\n");
    }
    write_text(out, "    </FieldData>\n");
  }
  write_text(out,
             "    <Piece NumberOfPoints=\"" +
                 std::to_string(n) +
                 "\" NumberOfVerts=\"0\" NumberOfLines=\"0\" NumberOfStrips=\"0\" "
                 "NumberOfPolys=\"" +
                 std::to_string(mesh.faces.size()) + "\">\n      <PointData>\n");
  for (const RealAttribute& attribute : kRealAttributes) {
    const Mesh::Array<double>& values = mesh.*attribute.values;
    if (!is_recorded(mesh, values)) continue;
    write_array<double>(out, "Float64", attribute.name, 1, n,
                        [&](std::size_t i) { return values[i]; });
  }
  for (const IntAttribute& attribute : kIntAttributes) {
    const Mesh::Array<std::int32_t>& values = mesh.*attribute.values;
    if (!is_recorded(mesh, values)) continue;
    write_array<std::int32_t>(out, "Int32", attribute.name, 1, n,
                              [&](std::size_t i) { return values[i]; });
  }
  write_text(out, "      </PointData>\n      <Points>\n");
  write_array<double>(out, "Float64", "Points", 3, 3 * n, [&](std::size_t i) {
    return mesh.positions[i / 3][static_cast<int>(i % 3)];
  });
  write_text(out, "      </Points>\n      <Polys>\n");
  std::vector<std::int64_t> connectivity;
  std::vector<std::int64_t> offsets;
  offsets.reserve(mesh.faces.size());
  for (const Face& face : mesh.faces) {
    for (int k = 0; k < face.size; ++k) connectivity.push_back(face.v[k]);
    offsets.push_back(static_cast<std::int64_t>(connectivity.size()));
  }
  write_array<std::int64_t>(out, "Int64", "connectivity", 1, connectivity.size(),
                            [&](std::size_t i) { return connectivity[i]; });
  write_array<std::int64_t>(out, "Int64", "offsets", 1, offsets.size(),
                            [&](std::size_t i) { return offsets[i]; });
  write_text(out, "      </Polys>\n    </Piece>\n  </PolyData>\n</VTKFile>\n");
}

Mesh read_vtp(std::string_view data, const std::string& file) {
  return VtpReader(data, file).read();
}

}  // namespace orthofront::io::detail
