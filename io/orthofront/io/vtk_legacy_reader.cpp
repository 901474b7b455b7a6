#include "orthofront/io/vtk_legacy_reader.h"

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <limits>
#include <optional>
#include <vector>

#include "orthofront/io/error.h"
#include "orthofront/io/grid_decode.h"
#include "orthofront/io/number_text.h"

namespace orthofront::io {
namespace {

using detail::ScalarType;

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::optional<ScalarType> legacy_type(const std::string& name) {
  const std::string n = lower(name);
  if (n == "char") return ScalarType::kInt8;
  if (n == "unsigned_char") return ScalarType::kUInt8;
  if (n == "short") return ScalarType::kInt16;
  if (n == "unsigned_short") return ScalarType::kUInt16;
  if (n == "int") return ScalarType::kInt32;
  if (n == "unsigned_int") return ScalarType::kUInt32;
  if (n == "long" || n == "vtktypeint64") return ScalarType::kInt64;
  if (n == "unsigned_long" || n == "vtktypeuint64") return ScalarType::kUInt64;
  if (n == "float") return ScalarType::kFloat32;
  if (n == "double") return ScalarType::kFloat64;
  return std::nullopt;
}

class LegacyParser {
 public:
  LegacyParser(std::string_view content, std::string file, std::string array)
      : content_(content), file_(std::move(file)), wanted_(std::move(array)) {}

  VectorGrid parse() {
    const std::string first = line();
    if (!first.starts_with("# vtk DataFile"))
      throw error("not a legacy VTK file (the first line is not '# vtk DataFile Version ...')");
    line();  // title
    const std::string mode = lower(trimmed(line()));
    if (mode == "binary") {
      binary_ = true;
    } else if (mode != "ascii") {
      throw error("unsupported encoding '" + mode + "' (ASCII or BINARY)");
    }
    if (lower(token()) != "dataset") throw error("expected DATASET after the encoding line");
    const std::string dataset = token();
    const bool rectilinear = dataset == "RECTILINEAR_GRID";
    if (dataset != "STRUCTURED_POINTS" && !rectilinear) {
      throw error("unsupported DATASET '" + dataset +
                  "' (STRUCTURED_POINTS and RECTILINEAR_GRID are supported)");
    }
    VectorGrid grid;
    GridGeometry& g = grid.geometry;
    bool have_dims = false;
    std::array<std::vector<float>, 3> coordinates;
    std::string word;
    // Geometry keywords up to POINT_DATA.
    for (;;) {
      word = token();
      if (word.empty()) throw error("truncated: no POINT_DATA section");
      const std::string key = lower(word);
      if (key == "dimensions") {
        for (std::size_t a = 0; a < 3; ++a) g.size[a] = integer("DIMENSIONS");
        for (std::size_t a = 0; a < 3; ++a) {
          if (g.size[a] < 1)
            throw error("bad DIMENSIONS " + std::to_string(g.size[0]) + " " + std::to_string(g.size[1]) +
                        " " + std::to_string(g.size[2]));
        }
        have_dims = true;
      } else if (key == "origin") {
        for (int a = 0; a < 3; ++a) g.origin[a] = real("ORIGIN");
      } else if (key == "spacing" || key == "aspect_ratio") {
        for (int a = 0; a < 3; ++a) g.spacing[a] = real("SPACING");
      } else if (rectilinear && (key == "x_coordinates" || key == "y_coordinates" || key == "z_coordinates")) {
        const std::size_t a = static_cast<std::size_t>(key[0] - 'x');
        const std::int64_t n = integer(word);
        const std::string type = token();
        if (!have_dims || n != g.size[a]) {
          throw error(word + " has " + std::to_string(n) + " values but DIMENSIONS say " +
                      (have_dims ? std::to_string(g.size[a]) : std::string("nothing (missing)")));
        }
        read_values(type, static_cast<std::size_t>(n), &coordinates[a], word);
      } else if (key == "field") {
        skip_field();
      } else if (key == "metadata") {
        skip_metadata();
      } else if (key == "point_data") {
        break;
      } else if (key == "cell_data") {
        throw error("CELL_DATA before POINT_DATA: only point data is supported");
      } else {
        throw error("unexpected '" + word + "' in the " + dataset + " header");
      }
    }
    if (!have_dims) throw error("no DIMENSIONS before POINT_DATA");
    const std::size_t points = detail::checked_point_count(g.size, 3, file_, "DIMENSIONS");
    const std::int64_t declared = integer("POINT_DATA");
    if (declared != static_cast<std::int64_t>(points)) {
      throw error("POINT_DATA " + std::to_string(declared) + " does not match DIMENSIONS " +
                  std::to_string(g.size[0]) + " x " + std::to_string(g.size[1]) + " x " +
                  std::to_string(g.size[2]) + " = " + std::to_string(points) + " points");
    }
    if (rectilinear) {
      for (std::size_t a = 0; a < 3; ++a) {
        if (coordinates[a].empty())
          throw error(std::string(1, static_cast<char>('X' + a)) + "_COORDINATES missing");
        g.axes[a].assign(coordinates[a].begin(), coordinates[a].end());
      }
    }
    // Attributes.
    std::vector<std::string> seen;
    bool found = false;
    bool in_point_data = true;
    std::size_t tuples = points;
    for (;;) {
      word = token();
      if (word.empty()) break;
      const std::string key = lower(word);
      if (key == "cell_data") {
        in_point_data = false;
        tuples = nonnegative("CELL_DATA", integer("CELL_DATA"));
        continue;
      }
      if (key == "point_data") {
        in_point_data = true;
        tuples = points;
        integer("POINT_DATA");
        continue;
      }
      if (key == "metadata") {
        skip_metadata();
        continue;
      }
      std::string name;
      std::string type;
      std::size_t components = 1;
      if (key == "vectors" || key == "normals") {
        name = token();
        type = token();
        components = 3;
      } else if (key == "scalars") {
        name = token();
        type = token();
        // Optional component count, then LOOKUP_TABLE (which may be absent in old files).
        std::string next = peek_token();
        std::int64_t n = 0;
        if (detail::parse_number(next, n)) {
          token();
          components = nonnegative("SCALARS " + name + " components", n);
          next = peek_token();
        }
        if (lower(next) == "lookup_table") {
          token();
          token();
        }
      } else if (key == "texture_coordinates") {
        name = token();
        components = nonnegative("TEXTURE_COORDINATES " + name + " components",
                                 integer("TEXTURE_COORDINATES"));
        type = token();
      } else if (key == "tensors" || key == "tensors6") {
        name = token();
        type = token();
        components = key == "tensors" ? 9 : 6;
      } else if (key == "lookup_table") {
        name = token();
        const std::int64_t n = integer("LOOKUP_TABLE");
        skip_values(binary_ ? "unsigned_char" : "float", product(nonnegative(word, n), 4, word),
                    word);
        continue;
      } else if (key == "field") {
        if (read_field(tuples, in_point_data, grid, seen)) found = true;
        if (found) break;
        continue;
      } else if (key == "color_scalars") {
        name = token();
        components = nonnegative("COLOR_SCALARS " + name + " components", integer("COLOR_SCALARS"));
        type = binary_ ? "unsigned_char" : "float";
      } else {
        throw error("unexpected '" + word + "' among the data arrays");
      }
      seen.push_back(word + " " + name + " (" + std::to_string(components) + " components)");
      const bool take = in_point_data && (wanted_.empty() ? key == "vectors" : name == wanted_);
      if (take) {
        if (components != 2 && components != 3) {
          throw error("point data '" + name + "' has " + std::to_string(components) +
                      " components: not vector data");
        }
        grid.components = static_cast<int>(components);
        read_values(type, points * components, &grid.values, word + " " + name);
        found = true;
        break;
      }
      skip_values(type, product(tuples, components, word + " " + name), word + " " + name);
    }
    if (!found) {
      std::string list;
      for (const std::string& s : seen) list += (list.empty() ? "" : ", ") + s;
      throw error((wanted_.empty() ? std::string("no VECTORS in POINT_DATA")
                                   : "no point data named '" + wanted_ + "'") +
                  " (arrays: " + (list.empty() ? "none" : list) + ")");
    }
    g.dimension = g.size[2] == 1 ? 2 : 3;  // one z sample: a 2D grid (of 2- or 3-vectors)
    detail::validate_grid(grid, file_);
    return grid;
  }

 private:
  FormatError error(const std::string& what) const { return FormatError(file_ + ": " + what); }

  static std::string trimmed(std::string s) {
    while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.pop_back();
    std::size_t a = 0;
    while (a < s.size() && std::isspace(static_cast<unsigned char>(s[a]))) ++a;
    return s.substr(a);
  }

  std::string line() {
    if (pos_ >= content_.size()) throw error("truncated header");
    const std::size_t end = std::min(content_.find('\n', pos_), content_.size());
    std::string text(content_.substr(pos_, end - pos_));
    pos_ = std::min(end + 1, content_.size());
    if (!text.empty() && text.back() == '\r') text.pop_back();
    return text;
  }

  void skip_space() {
    while (pos_ < content_.size() && std::isspace(static_cast<unsigned char>(content_[pos_]))) ++pos_;
  }

  std::string token() {
    skip_space();
    const std::size_t start = pos_;
    while (pos_ < content_.size() && !std::isspace(static_cast<unsigned char>(content_[pos_]))) ++pos_;
    return std::string(content_.substr(start, pos_ - start));
  }

  std::string peek_token() {
    const std::size_t saved = pos_;
    std::string t = token();
    pos_ = saved;
    return t;
  }

  std::int64_t integer(const std::string& what) {
    const std::string t = token();
    std::int64_t v = 0;
    if (!detail::parse_number(t, v))
      throw error(t.empty() ? "truncated: " + what + " needs a number" : "bad " + what + " value '" + t + "'");
    return v;
  }

  double real(const std::string& what) {
    const std::string t = token();
    double v = 0.0;
    if (!detail::parse_number(t, v))
      throw error(t.empty() ? "truncated: " + what + " needs a number" : "bad " + what + " value '" + t + "'");
    return v;
  }

  /// Binary data starts after the single newline that ends the keyword line.
  void start_binary_data() {
    while (pos_ < content_.size() && content_[pos_] != '\n') ++pos_;
    if (pos_ < content_.size()) ++pos_;
  }

  /// A count read from the file: negative is an error.
  std::size_t nonnegative(const std::string& what, std::int64_t n) const {
    if (n < 0) throw error("bad " + what + " " + std::to_string(n));
    return static_cast<std::size_t>(n);
  }

  /// The value count of `a` x `b` (tuples and components), refused where it wraps around.
  std::size_t product(std::size_t a, std::size_t b, const std::string& what) const {
    std::size_t n = 0;
    if (__builtin_mul_overflow(a, b, &n)) {
      throw error(what + " declares " + std::to_string(a) + " x " + std::to_string(b) +
                  " values, more than any file holds");
    }
    return n;
  }

  /// Reads `count` values into `out` (resized to them), or skips them when `out` is null. The
  /// count is checked against the bytes left in the file before anything is allocated.
  void read_values(const std::string& type_name, std::size_t count, std::vector<float>* out,
                   const std::string& what) {
    const auto type = legacy_type(type_name);
    if (!type) throw error(what + " has unsupported type '" + type_name + "'");
    if (binary_) {
      start_binary_data();
      const std::size_t scalar = detail::scalar_size(*type);
      const std::size_t rest = content_.size() - pos_;
      if (count > rest / scalar) {
        throw error("truncated: " + what + " needs " +
                    (count > std::numeric_limits<std::size_t>::max() / scalar
                         ? std::to_string(count) + " values of " + std::to_string(scalar)
                         : std::to_string(count * scalar)) +
                    " bytes, the file holds " + std::to_string(rest));
      }
      const std::size_t bytes = count * scalar;
      if (out != nullptr) {
        out->resize(count);
        detail::scalars_to_floats(*type, reinterpret_cast<const unsigned char*>(content_.data() + pos_),
                                  count, false, out->data());
      }
      pos_ += bytes;
      return;
    }
    // Ascii values grow `out` as they are read: every value takes a character and a separator,
    // so the file's length bounds the reservation.
    if (out != nullptr) {
      out->clear();
      out->reserve(std::min(count, (content_.size() - pos_ + 1) / 2));
    }
    for (std::size_t i = 0; i < count; ++i) {
      const std::string t = token();
      double v = 0.0;
      if (t.empty()) {
        throw error("truncated: " + what + " holds " + std::to_string(i) + " of " +
                    std::to_string(count) + " values");
      }
      if (!detail::parse_number(t, v)) throw error(what + " has the bad value '" + t + "'");
      if (out != nullptr) out->push_back(static_cast<float>(v));
    }
  }

  void skip_values(const std::string& type, std::size_t count, const std::string& what) {
    read_values(type, count, nullptr, what);
  }

  void skip_metadata() {
    // Lines up to the first empty one.
    start_binary_data();
    for (;;) {
      if (pos_ >= content_.size()) return;
      const std::string l = trimmed(line());
      if (l.empty()) return;
    }
  }

  void skip_field() {
    token();  // name
    const std::int64_t arrays = integer("FIELD");
    for (std::int64_t a = 0; a < arrays; ++a) {
      const std::string name = token();
      const std::size_t components =
          nonnegative("FIELD array " + name + " components", integer("FIELD array " + name));
      const std::size_t tuples =
          nonnegative("FIELD array " + name + " tuples", integer("FIELD array " + name));
      const std::string type = token();
      skip_values(type, product(components, tuples, "FIELD array " + name), "FIELD array " + name);
    }
  }

  /// A FIELD block among the attributes: takes the wanted array if it is there.
  bool read_field(std::size_t tuples_expected, bool point_data, VectorGrid& grid,
                  std::vector<std::string>& seen) {
    token();  // name
    const std::int64_t arrays = integer("FIELD");
    for (std::int64_t a = 0; a < arrays; ++a) {
      const std::string name = token();
      const std::size_t components =
          nonnegative("FIELD array " + name + " components", integer("FIELD array " + name));
      const std::size_t tuples =
          nonnegative("FIELD array " + name + " tuples", integer("FIELD array " + name));
      const std::string type = token();
      if (lower(name) == "metadata") {
        skip_metadata();
        continue;
      }
      seen.push_back("FIELD array " + name + " (" + std::to_string(components) + " components)");
      const std::size_t values = product(components, tuples, "FIELD array " + name);
      if (point_data && !wanted_.empty() && name == wanted_) {
        if (components != 2 && components != 3)
          throw error("point data '" + name + "' has " + std::to_string(components) +
                      " components: not vector data");
        if (tuples != tuples_expected)
          throw error("FIELD array " + name + " has " + std::to_string(tuples) + " tuples for " +
                      std::to_string(tuples_expected) + " points");
        grid.components = static_cast<int>(components);
        read_values(type, values, &grid.values, "FIELD array " + name);
        return true;
      }
      skip_values(type, values, "FIELD array " + name);
    }
    return false;
  }

  std::string_view content_;
  std::string file_;
  std::string wanted_;
  std::size_t pos_ = 0;
  bool binary_ = false;
};

}  // namespace

VectorGrid parse_vtk_legacy(std::string_view content, const std::string& file,
                            const std::string& array) {
  return LegacyParser(content, file, array).parse();
}

VectorGrid read_vtk_legacy(const std::filesystem::path& path, const std::string& array) {
  return parse_vtk_legacy(detail::read_file_bytes(path), path.string(), array);
}

}  // namespace orthofront::io
