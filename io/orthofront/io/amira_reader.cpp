#include "orthofront/io/amira_reader.h"

#include <algorithm>
#include <cstdint>
#include <limits>
#include <map>
#include <optional>
#include <regex>
#include <sstream>
#include <vector>

#include "orthofront/io/error.h"
#include "orthofront/io/grid_decode.h"
#include "orthofront/io/number_text.h"
#include "orthofront/io/zlib_codec.h"

namespace orthofront::io {
namespace {

using detail::ScalarType;

enum class Encoding { kBinaryBig, kBinaryLittle, kAscii };

/// `LOCATION { TYPE[N] NAME } @K` with an optional `(HxZip,SIZE)` encoding.
struct Declaration {
  std::string location;
  std::string type_name;
  ScalarType type = ScalarType::kFloat32;
  bool type_known = false;
  int components = 1;
  std::string name;
  int section = 0;
  std::string encoding;  // empty (raw), "HxZip", "HxByteRLE", ...
  std::size_t encoded_size = 0;

  std::string text() const {
    return location + " { " + type_name + (components != 1 ? "[" + std::to_string(components) + "]" : "") +
           " " + name + " } @" + std::to_string(section);
  }
};

std::optional<ScalarType> amira_type(const std::string& name) {
  if (name == "byte") return ScalarType::kUInt8;
  if (name == "short") return ScalarType::kInt16;
  if (name == "ushort") return ScalarType::kUInt16;
  if (name == "int") return ScalarType::kInt32;
  if (name == "float") return ScalarType::kFloat32;
  if (name == "double") return ScalarType::kFloat64;
  return std::nullopt;
}

/// `text` with every byte outside printable ASCII shown as '?', for messages.
std::string printable(std::string_view text) {
  std::string out(text);
  for (char& c : out) {
    if (c < 32 || c > 126) c = '?';
  }
  return out;
}

std::vector<std::string> split_words(std::string_view line) {
  std::vector<std::string> words;
  std::istringstream in{std::string(line)};
  std::string word;
  while (in >> word) words.push_back(word);
  return words;
}

class AmiraParser {
 public:
  AmiraParser(std::string_view content, std::string file, std::string field)
      : content_(content), file_(std::move(file)), field_(std::move(field)) {}

  VectorGrid parse() {
    read_header();
    const Declaration& vector = choose_vector();
    const std::vector<std::int64_t>& dims = location_dims(vector.location);
    VectorGrid grid;
    GridGeometry& g = grid.geometry;
    for (std::size_t a = 0; a < 3; ++a) g.size[a] = a < dims.size() ? dims[a] : 1;
    grid.components = vector.components;
    g.dimension = g.size[2] == 1 ? 2 : 3;  // one z sample: a 2D grid (of 2- or 3-vectors)
    // Checks the sizes only: the values are allocated once their data section proved to hold them.
    (void)detail::checked_point_count(g.size, grid.components, file_, "lattice size");

    const Declaration* coordinates = nullptr;
    if (coord_type_ == "rectilinear") {
      for (const Declaration& d : declarations_) {
        if (d.location == "Coordinates") coordinates = &d;
      }
      if (coordinates == nullptr)
        throw error("CoordType \"rectilinear\" but no Coordinates { float xyz } section");
    } else if (coord_type_ != "uniform") {
      throw error("unsupported CoordType \"" + coord_type_ +
                  "\" (uniform and rectilinear lattices are supported)");
    }
    std::vector<float> coordinate_values;
    read_sections(vector, grid.values, coordinates, coordinate_values);

    if (coordinates != nullptr) {
      const std::size_t needed = static_cast<std::size_t>(g.size[0] + g.size[1] + g.size[2]);
      if (coordinate_values.size() != needed) {
        throw error("Coordinates hold " + std::to_string(coordinate_values.size()) +
                    " values; a rectilinear lattice " + detail::size_text(g) + " needs " +
                    std::to_string(needed));
      }
      std::size_t at = 0;
      for (std::size_t a = 0; a < 3; ++a) {
        for (std::int64_t i = 0; i < g.size[a]; ++i) g.axes[a].push_back(coordinate_values[at++]);
      }
    } else if (bounding_box_) {
      const auto& box = *bounding_box_;
      for (int a = 0; a < 3; ++a) {
        const double lo = box[static_cast<std::size_t>(2 * a)];
        const double hi = box[static_cast<std::size_t>(2 * a + 1)];
        const std::int64_t n = g.size[static_cast<std::size_t>(a)];
        g.origin[a] = lo;
        if (n > 1) {
          if (!(hi > lo)) {
            throw error("BoundingBox " + std::to_string(lo) + " .. " + std::to_string(hi) +
                        " on axis " + std::to_string(a) + " is empty or reversed for " +
                        std::to_string(n) + " samples");
          }
          g.spacing[a] = (hi - lo) / static_cast<double>(n - 1);
        } else {
          g.spacing[a] = 1.0;
        }
      }
    }
    detail::validate_grid(grid, file_);
    return grid;
  }

 private:
  FormatError error(const std::string& what) const { return FormatError(file_ + ": " + what); }

  void read_header() {
    const std::size_t first_end = content_.find('\n');
    const std::string_view first =
        content_.substr(0, first_end == std::string_view::npos ? content_.size() : first_end);
    const std::vector<std::string> words = split_words(first);
    if (words.size() < 3 || words[0] != "#" || (words[1] != "AmiraMesh" && words[1] != "Avizo")) {
      throw error("not an AmiraMesh file (the first line is not '# AmiraMesh ...')");
    }
    std::size_t w = 2;
    if (w < words.size() && words[w] == "3D") ++w;
    const std::string encoding = w < words.size() ? words[w] : std::string();
    if (encoding == "BINARY-LITTLE-ENDIAN") {
      encoding_ = Encoding::kBinaryLittle;
    } else if (encoding == "BINARY") {
      encoding_ = Encoding::kBinaryBig;
    } else if (encoding == "ASCII") {
      encoding_ = Encoding::kAscii;
    } else {
      throw error("unsupported AmiraMesh encoding '" + encoding +
                  "' (BINARY, BINARY-LITTLE-ENDIAN and ASCII are supported)");
    }
    constexpr std::string_view kMarker = "# Data section follows";
    const std::size_t marker = content_.find(kMarker);
    if (marker == std::string_view::npos)
      throw error("truncated header: no '# Data section follows' line");
    const std::size_t marker_end = content_.find('\n', marker);
    data_begin_ = marker_end == std::string_view::npos ? content_.size() : marker_end + 1;
    const std::string header(content_.substr(0, marker));

    static const std::regex kDeclaration(
        R"(^\s*(\w+)\s*\{\s*(\w+)(?:\[\s*(\d+)\s*\])?\s+(\w+)\s*\}\s*(?:=\s*)?@(\d+)\s*(?:\(\s*(\w+)\s*,\s*(\d+)\s*\))?)");
    std::istringstream lines(header);
    std::string line;
    std::getline(lines, line);  // the first line
    while (std::getline(lines, line)) {
      if (!line.empty() && line.back() == '\r') line.pop_back();
      const std::vector<std::string> tokens = split_words(line);
      if (tokens.empty() || tokens[0].starts_with("#")) continue;
      if (tokens[0] == "define") {
        if (tokens.size() < 3)
          throw error("bad line '" + line + "': define needs a name and a size");
        std::vector<std::int64_t> dims;
        for (std::size_t i = 2; i < tokens.size(); ++i) {
          std::int64_t n = 0;
          if (!detail::parse_number(tokens[i], n) || n < 1) {
            throw error("bad size '" + tokens[i] + "' of " + tokens[1] + " in '" + line + "'");
          }
          dims.push_back(n);
        }
        if (dims.size() > 3) throw error("'" + line + "' has more than 3 sizes");
        defines_[tokens[1]] = dims;
        continue;
      }
      for (std::size_t t = 0; t < tokens.size(); ++t) {
        if (tokens[t] == "BoundingBox") read_bounding_box(tokens, t, line);
        if (tokens[t] == "CoordType" && t + 1 < tokens.size()) {
          std::string value = tokens[t + 1];
          while (!value.empty() && (value.back() == ',' || value.back() == '"')) value.pop_back();
          if (!value.empty() && value.front() == '"') value.erase(0, 1);
          coord_type_ = value;
        }
      }
      std::smatch m;
      if (std::regex_search(line, m, kDeclaration)) {
        Declaration d;
        d.location = m[1];
        d.type_name = m[2];
        d.name = m[4];
        // The regex admits any run of digits: one beyond the type's range is an error, not a
        // std::out_of_range escaping the reader.
        if (m[3].matched && !detail::parse_number(m[3].str(), d.components))
          throw error("bad component count '" + m[3].str() + "' of " + d.name + " in '" + line + "'");
        if (!detail::parse_number(m[5].str(), d.section))
          throw error("bad data section number '" + m[5].str() + "' in '" + line + "'");
        if (m[6].matched) {
          d.encoding = m[6];
          if (!detail::parse_number(m[7].str(), d.encoded_size))
            throw error("bad encoded size '" + m[7].str() + "' in '" + line + "'");
        }
        if (const auto type = amira_type(d.type_name)) {
          d.type = *type;
          d.type_known = true;
        }
        declarations_.push_back(d);
      }
    }
    if (declarations_.empty())
      throw error("no data declaration (like 'Lattice { float[3] Data } @1') in the header");
  }

  void read_bounding_box(const std::vector<std::string>& tokens, std::size_t at,
                         const std::string& line) {
    std::array<double, 6> box{};
    for (std::size_t i = 0; i < 6; ++i) {
      std::string value = at + 1 + i < tokens.size() ? tokens[at + 1 + i] : std::string();
      while (!value.empty() && value.back() == ',') value.pop_back();
      if (!detail::parse_number(value, box[i])) {
        throw error("bad BoundingBox value '" + value + "' in '" + line +
                    "' (need xmin xmax ymin ymax zmin zmax)");
      }
    }
    bounding_box_ = box;
  }

  const std::vector<std::int64_t>& location_dims(const std::string& location) const {
    const auto it = defines_.find(location);
    if (it == defines_.end())
      throw error("data is declared on '" + location + "' but there is no 'define " + location + "'");
    return it->second;
  }

  const Declaration& choose_vector() const {
    if (!field_.empty()) {
      for (const Declaration& d : declarations_) {
        if (d.name != field_) continue;
        check_vector(d);
        return d;
      }
      std::string names;
      for (const Declaration& d : declarations_) names += (names.empty() ? "" : ", ") + d.name;
      throw error("no data named '" + field_ + "' (the file holds: " + names + ")");
    }
    for (const Declaration& d : declarations_) {
      const auto it = defines_.find(d.location);
      if (it != defines_.end() && it->second.size() >= 2 && (d.components == 2 || d.components == 3))
        return d;
    }
    std::string what;
    for (const Declaration& d : declarations_) what += (what.empty() ? "" : "; ") + d.text();
    throw error("no vector data on a lattice (need float[3] or float[2]); the file holds: " +
                what);
  }

  void check_vector(const Declaration& d) const {
    if (d.components != 2 && d.components != 3) {
      throw error("'" + d.text() + "' has " + std::to_string(d.components) +
                  " component(s): not vector data (need [2] or [3])");
    }
    if (location_dims(d.location).size() < 2)
      throw error("'" + d.text() + "' is not on a 2D or 3D lattice");
  }

  /// The values a section holds per its declaration (components x lattice points), refused
  /// beyond 2^40 so that byte counts computed from it cannot overflow.
  std::size_t value_count(const Declaration& d) const {
    double n = d.components;
    for (const std::int64_t s : location_dims(d.location)) n *= static_cast<double>(s);
    if (n > 1099511627776.0)
      throw error("data section @" + std::to_string(d.section) + " (" + d.text() +
                  ") declares an implausible " + std::to_string(n) + " values");
    std::size_t count = static_cast<std::size_t>(d.components);
    for (const std::int64_t s : location_dims(d.location)) count *= static_cast<std::size_t>(s);
    return count;
  }

  /// Walks the data sections in file order; decodes `vector` into `values` and, when asked, the
  /// rectilinear coordinates.
  void read_sections(const Declaration& vector, std::vector<float>& values,
                     const Declaration* coordinates, std::vector<float>& coordinate_values) {
    std::size_t pos = data_begin_;
    bool have_vector = false;
    bool have_coordinates = coordinates == nullptr;
    while (!(have_vector && have_coordinates)) {
      while (pos < content_.size() && std::isspace(static_cast<unsigned char>(content_[pos]))) ++pos;
      if (pos >= content_.size()) {
        throw error("truncated: the data section @" +
                    std::to_string(have_vector ? coordinates->section : vector.section) +
                    " is missing");
      }
      if (content_[pos] != '@') {
        throw error("expected a data section marker '@N' at byte " + std::to_string(pos) +
                    " (do the sizes in the header match the data?)");
      }
      const std::size_t line_end = content_.find('\n', pos);
      if (line_end == std::string_view::npos)
        throw error("truncated: nothing follows the marker at byte " + std::to_string(pos));
      std::string_view marker = content_.substr(pos + 1, line_end - pos - 1);
      if (!marker.empty() && marker.back() == '\r') marker.remove_suffix(1);
      int section = 0;
      if (!detail::parse_number(marker, section))
        throw error("bad data section marker '@" + printable(marker.substr(0, 20)) +
                    "' at byte " + std::to_string(pos) +
                    " (do the sizes in the header match the data?)");
      const Declaration* d = nullptr;
      for (const Declaration& candidate : declarations_) {
        if (candidate.section == section) d = &candidate;
      }
      if (d == nullptr) throw error("data section @" + std::to_string(section) + " is not declared");
      pos = line_end + 1;
      const bool wanted = d == &vector || d == coordinates;
      std::vector<float>* target = d == &vector ? &values : &coordinate_values;
      pos = read_section(*d, pos, wanted ? target : nullptr);
      if (d == &vector) have_vector = true;
      if (d == coordinates) have_coordinates = true;
    }
    // What follows must be another section (or nothing): bytes left over mean the header's type
    // or sizes do not describe the data (e.g. float[2] declared over float[3] data).
    while (pos < content_.size() && std::isspace(static_cast<unsigned char>(content_[pos]))) ++pos;
    if (pos < content_.size()) {
      const std::size_t line_end = content_.find('\n', pos);
      std::string_view marker = content_.substr(pos + 1, line_end == std::string_view::npos
                                                             ? std::string_view::npos
                                                             : line_end - pos - 1);
      if (!marker.empty() && marker.back() == '\r') marker.remove_suffix(1);
      int section = 0;
      const bool declared =
          content_[pos] == '@' && line_end != std::string_view::npos &&
          detail::parse_number(marker, section) &&
          std::any_of(declarations_.begin(), declarations_.end(),
                      [&](const Declaration& d) { return d.section == section; });
      if (!declared)
        throw error("data section @" + std::to_string(vector.section) + " (" + vector.text() +
                    ") is followed by " + std::to_string(content_.size() - pos) +
                    " bytes that belong to no section: do the type and sizes in the header match "
                    "the data?");
    }
  }

  /// Reads (or skips, when `out` is null) one section starting at `pos` into `out`, which is
  /// sized only once the file proved to hold the declared count; returns the position after it.
  std::size_t read_section(const Declaration& d, std::size_t pos, std::vector<float>* out) const {
    const std::size_t count = value_count(d);
    const std::string what = "data section @" + std::to_string(d.section) + " (" + d.text() + ")";
    const std::size_t rest = content_.size() - pos;
    if (encoding_ == Encoding::kAscii) {
      if (out != nullptr && !d.type_known)
        throw error(what + " has the unsupported type '" + d.type_name + "'");
      // Values grow `out` as they are read: every value takes a character and a separator, so
      // the bytes after the marker bound the reservation.
      if (out != nullptr) {
        out->clear();
        out->reserve(std::min(count, (rest + 1) / 2));
      }
      for (std::size_t i = 0; i < count; ++i) {
        while (pos < content_.size() && std::isspace(static_cast<unsigned char>(content_[pos]))) ++pos;
        const std::size_t start = pos;
        while (pos < content_.size() && !std::isspace(static_cast<unsigned char>(content_[pos]))) ++pos;
        if (start == pos) {
          throw error("truncated: " + what + " holds " + std::to_string(i) + " of " +
                      std::to_string(count) + " values");
        }
        double value = 0.0;
        const std::string_view token = content_.substr(start, pos - start);
        if (!detail::parse_number(token, value))
          throw error(what + " has the bad value '" + std::string(token) + "'");
        if (out != nullptr) out->push_back(static_cast<float>(value));
      }
      return pos;
    }
    if (!d.type_known) {
      throw error(what + " has the unsupported type '" + d.type_name + "'");
    }
    const std::size_t bytes = count * detail::scalar_size(d.type);
    const bool little = encoding_ == Encoding::kBinaryLittle;
    if (!d.encoding.empty()) {
      if (d.encoded_size > rest) {
        throw error("truncated: " + what + " needs " + std::to_string(d.encoded_size) +
                    " compressed bytes, the file holds " + std::to_string(rest));
      }
      if (out != nullptr) {
        if (d.encoding != "HxZip") {
          throw error(what + " uses the unsupported encoding '" + d.encoding +
                      "' (raw and HxZip are supported)");
        }
        // Refuses `bytes` beyond deflate's 1032:1 of encoded_size before allocating.
        const std::string raw =
            detail::zlib_inflate(content_.substr(pos, d.encoded_size), bytes, file_ + ": " + what);
        out->resize(count);
        detail::scalars_to_floats(d.type, reinterpret_cast<const unsigned char*>(raw.data()),
                                  count, little, out->data());
      }
      return pos + d.encoded_size;
    }
    if (bytes > rest) {
      throw error("truncated: " + what + " needs " + std::to_string(bytes) +
                  " bytes, the file holds " + std::to_string(rest));
    }
    if (out != nullptr) {
      out->resize(count);
      detail::scalars_to_floats(d.type, reinterpret_cast<const unsigned char*>(content_.data() + pos),
                                count, little, out->data());
    }
    return pos + bytes;
  }

  std::string_view content_;
  std::string file_;
  std::string field_;
  Encoding encoding_ = Encoding::kBinaryBig;
  std::size_t data_begin_ = 0;
  std::map<std::string, std::vector<std::int64_t>> defines_;
  std::vector<Declaration> declarations_;
  std::optional<std::array<double, 6>> bounding_box_;
  std::string coord_type_ = "uniform";
};

}  // namespace

VectorGrid parse_amira(std::string_view content, const std::string& file, const std::string& field) {
  return AmiraParser(content, file, field).parse();
}

VectorGrid read_amira(const std::filesystem::path& path, const std::string& field) {
  return parse_amira(detail::read_file_bytes(path), path.string(), field);
}

}  // namespace orthofront::io
