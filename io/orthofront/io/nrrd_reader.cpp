#include "orthofront/io/nrrd_reader.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <optional>
#include <vector>

#include "orthofront/io/bzip2_codec.h"
#include "orthofront/io/error.h"
#include "orthofront/io/grid_decode.h"
#include "orthofront/io/number_text.h"
#include "orthofront/io/zlib_codec.h"

namespace orthofront::io {
namespace {

using detail::ScalarType;

std::string trim(std::string_view s) {
  std::size_t a = 0;
  std::size_t b = s.size();
  while (a < b && std::isspace(static_cast<unsigned char>(s[a]))) ++a;
  while (b > a && std::isspace(static_cast<unsigned char>(s[b - 1]))) --b;
  return std::string(s.substr(a, b - a));
}

std::vector<std::string> split_words(std::string_view s) {
  std::vector<std::string> words;
  std::size_t i = 0;
  while (i < s.size()) {
    while (i < s.size() && std::isspace(static_cast<unsigned char>(s[i]))) ++i;
    const std::size_t start = i;
    // A parenthesised vector "(a, b, c)" is one word even with spaces inside.
    if (i < s.size() && s[i] == '(') {
      const std::size_t close = s.find(')', i);
      i = close == std::string_view::npos ? s.size() : close + 1;
    } else {
      while (i < s.size() && !std::isspace(static_cast<unsigned char>(s[i]))) ++i;
    }
    if (i > start) words.emplace_back(s.substr(start, i - start));
  }
  return words;
}

std::optional<ScalarType> nrrd_type(std::string name) {
  for (char& c : name) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  static const std::map<std::string, ScalarType> kTypes = {
      {"signed char", ScalarType::kInt8},   {"int8", ScalarType::kInt8},
      {"int8_t", ScalarType::kInt8},        {"uchar", ScalarType::kUInt8},
      {"unsigned char", ScalarType::kUInt8}, {"uint8", ScalarType::kUInt8},
      {"uint8_t", ScalarType::kUInt8},      {"short", ScalarType::kInt16},
      {"short int", ScalarType::kInt16},    {"signed short", ScalarType::kInt16},
      {"signed short int", ScalarType::kInt16}, {"int16", ScalarType::kInt16},
      {"int16_t", ScalarType::kInt16},      {"ushort", ScalarType::kUInt16},
      {"unsigned short", ScalarType::kUInt16}, {"unsigned short int", ScalarType::kUInt16},
      {"uint16", ScalarType::kUInt16},      {"uint16_t", ScalarType::kUInt16},
      {"int", ScalarType::kInt32},          {"signed int", ScalarType::kInt32},
      {"int32", ScalarType::kInt32},        {"int32_t", ScalarType::kInt32},
      {"uint", ScalarType::kUInt32},        {"unsigned int", ScalarType::kUInt32},
      {"uint32", ScalarType::kUInt32},      {"uint32_t", ScalarType::kUInt32},
      {"longlong", ScalarType::kInt64},     {"long long", ScalarType::kInt64},
      {"long long int", ScalarType::kInt64}, {"signed long long", ScalarType::kInt64},
      {"signed long long int", ScalarType::kInt64}, {"int64", ScalarType::kInt64},
      {"int64_t", ScalarType::kInt64},      {"ulonglong", ScalarType::kUInt64},
      {"unsigned long long", ScalarType::kUInt64}, {"unsigned long long int", ScalarType::kUInt64},
      {"uint64", ScalarType::kUInt64},      {"uint64_t", ScalarType::kUInt64},
      {"float", ScalarType::kFloat32},      {"double", ScalarType::kFloat64},
  };
  const auto it = kTypes.find(name);
  if (it == kTypes.end()) return std::nullopt;
  return it->second;
}

bool is_vector_kind(const std::string& kind) {
  return kind == "vector" || kind == "2-vector" || kind == "3-vector" ||
         kind == "covariant-vector" || kind == "normal" || kind == "3-gradient" ||
         kind == "3-normal" || kind == "list" || kind == "point";
}

bool is_space_kind(const std::string& kind) {
  return kind == "space" || kind == "domain" || kind == "time";
}

class NrrdParser {
 public:
  NrrdParser(std::string_view content, const std::filesystem::path& path)
      : content_(content), path_(path), file_(path.string()) {}

  VectorGrid parse() {
    read_header();
    const int dimension = required_int("dimension");
    if (dimension < 3 || dimension > 4) {
      throw error("dimension " + std::to_string(dimension) +
                  ": a vector field needs one component axis and 2 or 3 spatial axes");
    }
    const auto axes = static_cast<std::size_t>(dimension);
    sizes_ = per_axis_ints("sizes", axes);
    kinds_ = per_axis_words("kinds", axes);
    const std::vector<std::string> directions = per_axis_words("space directions", axes);
    const std::vector<double> spacings = per_axis_doubles("spacings", axes);
    const std::vector<double> mins = per_axis_doubles("axis mins", axes);
    std::vector<std::string> centers = per_axis_words("centers", axes);
    if (centers.empty()) centers = per_axis_words("centerings", axes);

    // The component axis.
    std::optional<std::size_t> component_axis;
    for (std::size_t a = 0; a < axes && !component_axis; ++a) {
      if (!kinds_.empty() && is_vector_kind(kinds_[a])) component_axis = a;
    }
    for (std::size_t a = 0; a < axes && !component_axis; ++a) {
      if (!directions.empty() && directions[a] == "none") component_axis = a;
    }
    if (!component_axis) {
      if (!kinds_.empty() && std::all_of(kinds_.begin(), kinds_.end(), is_space_kind)) {
        throw error("non-vector data: every axis is spatial (kinds: " + field("kinds") +
                    "); need one axis of 2 or 3 vector components");
      }
      component_axis = 0;
    }
    const std::size_t c_axis = *component_axis;
    const std::int64_t components = sizes_[c_axis];
    if (components != 2 && components != 3) {
      throw error("non-vector data: the component axis " + std::to_string(c_axis) + " has size " +
                  std::to_string(components) + " (sizes: " + field("sizes") +
                  "); need 2 or 3 components");
    }
    std::vector<std::size_t> space_axes;
    for (std::size_t a = 0; a < axes; ++a) {
      if (a != c_axis) space_axes.push_back(a);
    }

    VectorGrid grid;
    GridGeometry& g = grid.geometry;
    grid.components = static_cast<int>(components);
    g.dimension = static_cast<int>(space_axes.size());
    for (std::size_t s = 0; s < space_axes.size(); ++s) g.size[s] = sizes_[space_axes[s]];
    if (g.size[2] == 1) g.dimension = 2;  // one z sample: a 2D grid

    // Spacing and origin.
    std::optional<std::vector<double>> origin;
    if (has("space origin")) origin = parse_vector(field("space origin"), "space origin");
    for (std::size_t s = 0; s < space_axes.size(); ++s) {
      const std::size_t a = space_axes[s];
      double spacing = 1.0;
      if (!directions.empty()) {
        const std::vector<double> d = parse_vector(directions[a], "space directions");
        int nonzero = -1;
        for (std::size_t i = 0; i < d.size(); ++i) {
          if (d[i] != 0.0) {
            if (nonzero >= 0) nonzero = -2;
            if (nonzero == -1) nonzero = static_cast<int>(i);
          }
        }
        if (nonzero != static_cast<int>(s)) {
          throw error("space direction " + directions[a] + " of axis " + std::to_string(a) +
                      " is not along world axis " + std::to_string(s) +
                      " (only axis-aligned, unpermuted grids are supported)");
        }
        spacing = d[s];
      } else if (!spacings.empty() && std::isfinite(spacings[a])) {
        spacing = spacings[a];
      }
      if (!(spacing > 0.0)) {
        throw error("spacing " + std::to_string(spacing) + " of axis " + std::to_string(a) +
                    " is not positive (flipped axes are not supported)");
      }
      g.spacing[static_cast<int>(s)] = spacing;
      double o = 0.0;
      if (origin) {
        if (s >= origin->size()) throw error("space origin has too few coordinates");
        o = (*origin)[s];
      } else if (!mins.empty() && std::isfinite(mins[a])) {
        o = mins[a];
        if (!centers.empty() && centers[a] == "cell") o += 0.5 * spacing;
      }
      g.origin[static_cast<int>(s)] = o;
    }

    const std::size_t points =
        detail::checked_point_count(g.size, grid.components, file_, "sizes " + field("sizes"));
    const std::size_t count = points * static_cast<std::size_t>(components);
    // Nothing the size of the grid is allocated before the data proved to hold it.
    std::vector<float> stored;
    read_data(count, stored);
    // Reorder: the stored layout has the component axis at c_axis; ours has it first.
    std::array<std::size_t, 4> stride{};
    std::size_t s = 1;
    for (std::size_t a = 0; a < axes; ++a) {
      stride[a] = s;
      s *= static_cast<std::size_t>(sizes_[a]);
    }
    if (c_axis == 0) {
      grid.values = std::move(stored);
    } else {
      grid.values.resize(count);
      std::array<std::size_t, 3> space_stride{0, 0, 0};
      for (std::size_t i = 0; i < space_axes.size(); ++i) space_stride[i] = stride[space_axes[i]];
      std::size_t out = 0;
      for (std::int64_t k = 0; k < g.size[2]; ++k) {
        for (std::int64_t j = 0; j < g.size[1]; ++j) {
          for (std::int64_t i = 0; i < g.size[0]; ++i) {
            const std::size_t base = static_cast<std::size_t>(i) * space_stride[0] +
                                     static_cast<std::size_t>(j) * space_stride[1] +
                                     static_cast<std::size_t>(k) * space_stride[2];
            for (std::int64_t c = 0; c < components; ++c)
              grid.values[out++] = stored[base + static_cast<std::size_t>(c) * stride[c_axis]];
          }
        }
      }
    }
    detail::validate_grid(grid, file_);
    return grid;
  }

 private:
  FormatError error(const std::string& what) const { return FormatError(file_ + ": " + what); }

  void read_header() {
    if (!content_.starts_with("NRRD000")) throw error("not a NRRD file (no 'NRRD000X' magic)");
    std::size_t pos = 0;
    bool first = true;
    for (;;) {
      const std::size_t end = content_.find('\n', pos);
      if (end == std::string_view::npos) {
        // A detached header (.nhdr) may end without a blank line.
        if (pos < content_.size()) add_line(content_.substr(pos), first);
        data_begin_ = content_.size();
        header_complete_ = false;
        break;
      }
      std::string_view line = content_.substr(pos, end - pos);
      pos = end + 1;
      if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
      if (line.empty()) {
        data_begin_ = pos;
        break;
      }
      add_line(line, first);
      first = false;
    }
  }

  void add_line(std::string_view line, bool first) {
    if (first) {
      magic_ = std::string(line);
      return;
    }
    if (line.starts_with("#")) return;
    if (line.find(":=") != std::string_view::npos) return;  // key/value pairs
    const std::size_t colon = line.find(": ");
    if (colon == std::string_view::npos)
      throw error("bad header line '" + std::string(line) + "' (expected 'field: value')");
    std::string key = trim(line.substr(0, colon));
    for (char& c : key) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (key == "datafile") key = "data file";
    if (key == "lineskip") key = "line skip";
    if (key == "byteskip") key = "byte skip";
    if (key == "centerings") key = "centers";
    fields_[key] = trim(line.substr(colon + 2));
  }

  bool has(const std::string& key) const { return fields_.count(key) != 0; }
  std::string field(const std::string& key) const {
    const auto it = fields_.find(key);
    return it == fields_.end() ? std::string() : it->second;
  }

  int required_int(const std::string& key) const {
    if (!has(key)) throw error("no '" + key + "' field in the header");
    int value = 0;
    if (!detail::parse_number(field(key), value))
      throw error("bad " + key + " '" + field(key) + "'");
    return value;
  }

  std::vector<std::string> per_axis_words(const std::string& key, std::size_t axes) const {
    if (!has(key)) return {};
    std::vector<std::string> words = split_words(field(key));
    if (words.size() != axes) {
      throw error(key + " '" + field(key) + "' has " + std::to_string(words.size()) +
                  " entries for dimension " + std::to_string(axes));
    }
    return words;
  }

  std::vector<std::int64_t> per_axis_ints(const std::string& key, std::size_t axes) const {
    if (!has(key)) throw error("no '" + key + "' field in the header");
    std::vector<std::int64_t> values;
    for (const std::string& word : per_axis_words(key, axes)) {
      std::int64_t v = 0;
      if (!detail::parse_number(word, v) || v < 1)
        throw error("bad " + key + " entry '" + word + "' in '" + field(key) + "'");
      values.push_back(v);
    }
    return values;
  }

  std::vector<double> per_axis_doubles(const std::string& key, std::size_t axes) const {
    std::vector<double> values;
    for (std::string word : per_axis_words(key, axes)) {
      for (char& c : word) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
      double v = 0.0;
      if (word == "nan") {
        v = std::numeric_limits<double>::quiet_NaN();
      } else if (!detail::parse_number(word, v)) {
        throw error("bad " + key + " entry '" + word + "' in '" + field(key) + "'");
      }
      values.push_back(v);
    }
    return values;
  }

  std::vector<double> parse_vector(const std::string& text, const std::string& key) const {
    if (text.size() < 2 || text.front() != '(' || text.back() != ')')
      throw error("bad " + key + " vector '" + text + "' (expected '(a,b,...)')");
    std::vector<double> values;
    std::string_view inside(text);
    inside = inside.substr(1, inside.size() - 2);
    std::size_t pos = 0;
    while (pos <= inside.size()) {
      const std::size_t comma = std::min(inside.find(',', pos), inside.size());
      double v = 0.0;
      if (!detail::parse_number(trim(inside.substr(pos, comma - pos)), v))
        throw error("bad " + key + " vector '" + text + "'");
      values.push_back(v);
      pos = comma + 1;
    }
    return values;
  }

  void read_data(std::size_t count, std::vector<float>& out) const {
    const std::string type_name = field("type");
    if (type_name.empty()) throw error("no 'type' field in the header");
    const auto type = nrrd_type(type_name);
    if (!type) throw error("unsupported type '" + type_name + "'");
    std::string encoding = field("encoding");
    if (encoding.empty()) throw error("no 'encoding' field in the header");
    for (char& c : encoding) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (encoding == "gz") encoding = "gzip";
    if (encoding == "bz2") encoding = "bzip2";
    if (encoding == "txt" || encoding == "text") encoding = "ascii";
    if (encoding != "raw" && encoding != "gzip" && encoding != "bzip2" && encoding != "hex" &&
        encoding != "ascii") {
      throw error("unsupported encoding '" + field("encoding") +
                  "' (raw, gzip, bzip2, hex and ascii are supported)");
    }
    const std::size_t scalar = detail::scalar_size(*type);
    bool little = true;
    if (encoding != "ascii" && scalar > 1) {
      const std::string endian = field("endian");
      if (endian == "little") {
        little = true;
      } else if (endian == "big") {
        little = false;
      } else {
        throw error(endian.empty() ? std::string("no 'endian' field for a multi-byte type")
                                   : "bad endian '" + endian + "'");
      }
    }
    // Where the data is: after the header, or in a detached file.
    std::string detached;
    std::string data_name = file_;
    std::string_view data = content_.substr(std::min(data_begin_, content_.size()));
    if (has("data file")) {
      const std::vector<std::string> words = split_words(field("data file"));
      if (words.size() != 1 || words[0] == "LIST") {
        throw error("unsupported data file '" + field("data file") +
                    "' (a single detached file is supported)");
      }
      std::filesystem::path data_path = words[0];
      if (data_path.is_relative()) data_path = path_.parent_path() / data_path;
      detached = detail::read_file_bytes(data_path);
      data = detached;
      data_name = data_path.string();
    } else if (!header_complete_) {
      throw error("truncated header: no blank line before the data");
    }
    // Skips say that the data file holds other bytes besides the samples: only then may it
    // hold more than the sizes need.
    bool skips = false;
    if (has("line skip")) {
      int lines = 0;
      if (!detail::parse_number(field("line skip"), lines) || lines < 0)
        throw error("bad line skip '" + field("line skip") + "'");
      skips = lines > 0;
      for (int i = 0; i < lines; ++i) {
        const std::size_t nl = data.find('\n');
        if (nl == std::string_view::npos) throw error("truncated: line skip goes past the data");
        data.remove_prefix(nl + 1);
      }
    }
    const std::size_t bytes = count * scalar;
    std::int64_t byte_skip = 0;
    if (has("byte skip")) {
      if (!detail::parse_number(field("byte skip"), byte_skip) || byte_skip < -1)
        throw error("bad byte skip '" + field("byte skip") + "'");
      skips = skips || byte_skip != 0;
    }
    if (encoding == "ascii") {
      // Every value takes a character and a separator: n values need 2n - 1 characters.
      if (count > (data.size() + 1) / 2)
        throw error("truncated: " + data_name + " holds " + std::to_string(data.size()) +
                    " characters, too few for the " + std::to_string(count) +
                    " values of sizes " + field("sizes"));
      out.resize(count);
      std::size_t pos = 0;
      for (std::size_t i = 0; i < count; ++i) {
        while (pos < data.size() &&
               (std::isspace(static_cast<unsigned char>(data[pos])) || data[pos] == ','))
          ++pos;
        const std::size_t start = pos;
        while (pos < data.size() && !std::isspace(static_cast<unsigned char>(data[pos])) &&
               data[pos] != ',')
          ++pos;
        if (start == pos) {
          throw error("truncated: " + data_name + " holds " + std::to_string(i) + " of " +
                      std::to_string(count) + " values");
        }
        double v = 0.0;
        if (!detail::parse_number(data.substr(start, pos - start), v))
          throw error("bad value '" + std::string(data.substr(start, pos - start)) + "'");
        out[i] = static_cast<float>(v);
      }
      return;
    }
    std::string inflated;
    if (encoding == "hex") {
      // Two hex digits a byte, whitespace anywhere between them.
      if (data.size() < 2 * bytes)
        throw error("truncated: " + data_name + " holds " + std::to_string(data.size()) +
                    " characters, too few for the " + std::to_string(bytes) +
                    " hex bytes of sizes " + field("sizes") + " of " + field("type"));
      inflated.reserve(bytes);
      int high = -1;
      for (const char c : data) {
        if (std::isspace(static_cast<unsigned char>(c))) continue;
        int digit = -1;
        if (c >= '0' && c <= '9') digit = c - '0';
        if (c >= 'a' && c <= 'f') digit = c - 'a' + 10;
        if (c >= 'A' && c <= 'F') digit = c - 'A' + 10;
        if (digit < 0) throw error("bad hex character '" + std::string(1, c) + "' in the data");
        if (high < 0) {
          high = digit;
          continue;
        }
        if (inflated.size() == bytes)
          throw error(data_name + " holds more hex bytes than sizes " + field("sizes") + " of " +
                      field("type") + " need (" + std::to_string(bytes) + ")");
        inflated.push_back(static_cast<char>(high * 16 + digit));
        high = -1;
      }
      if (inflated.size() < bytes || high >= 0)
        throw error("truncated: the hex data holds " + std::to_string(inflated.size()) +
                    " bytes; sizes " + field("sizes") + " of " + field("type") + " need " +
                    std::to_string(bytes));
      data = inflated;
    } else if (encoding == "bzip2") {
      if (byte_skip > 0)
        data.remove_prefix(std::min<std::size_t>(data.size(), static_cast<std::size_t>(byte_skip)));
      inflated = detail::bzip2_decompress(data, data_name + ": bzip2 data", bytes);
      data = inflated;
      if (data.size() < bytes)
        throw error("truncated: the bzip2 data holds " + std::to_string(data.size()) +
                    " bytes; sizes " + field("sizes") + " of " + field("type") + " need " +
                    std::to_string(bytes));
    } else if (encoding == "gzip") {
      if (byte_skip > 0) data.remove_prefix(std::min<std::size_t>(data.size(), static_cast<std::size_t>(byte_skip)));
      // Deflate expands at most 1032:1: fewer compressed bytes cannot hold the grid.
      if (static_cast<double>(data.size()) * 1032.0 < static_cast<double>(bytes))
        throw error("truncated: " + data_name + " holds " + std::to_string(data.size()) +
                    " gzip bytes, too few for the " + std::to_string(bytes) + " bytes of sizes " +
                    field("sizes") + " of " + field("type"));
      inflated = detail::gzip_inflate(data, data_name + ": gzip data", bytes);
      data = inflated;
      if (data.size() < bytes) {
        throw error("truncated: the gzip data holds " + std::to_string(data.size()) +
                    " bytes; sizes " + field("sizes") + " of " + field("type") + " need " +
                    std::to_string(bytes));
      }
    } else {
      if (byte_skip == -1) {
        if (data.size() < bytes) {
          throw error("truncated: " + data_name + " holds " + std::to_string(data.size()) +
                      " data bytes; sizes " + field("sizes") + " of " + field("type") + " need " +
                      std::to_string(bytes));
        }
        data.remove_prefix(data.size() - bytes);
      } else {
        data.remove_prefix(std::min<std::size_t>(data.size(), static_cast<std::size_t>(byte_skip)));
      }
      if (data.size() < bytes) {
        throw error("truncated: " + data_name + " holds " + std::to_string(data.size()) +
                    " data bytes; sizes " + field("sizes") + " of " + field("type") + " need " +
                    std::to_string(bytes));
      }
      // Raw data without skips is the samples and nothing else (as teem writes it): more bytes
      // mean sizes or type that do not describe the data, which would be read misaligned.
      if (!skips && data.size() > bytes) {
        throw error(data_name + " holds " + std::to_string(data.size()) + " data bytes but sizes " +
                    field("sizes") + " of " + field("type") + " need " + std::to_string(bytes) +
                    ": the header claims fewer samples than the data holds (do the sizes and "
                    "type match the data? bytes besides the samples need 'byte skip' or "
                    "'line skip')");
      }
    }
    out.resize(count);
    detail::scalars_to_floats(*type, reinterpret_cast<const unsigned char*>(data.data()), count,
                              little, out.data());
  }

  std::string_view content_;
  std::filesystem::path path_;
  std::string file_;
  std::string magic_;
  std::map<std::string, std::string> fields_;
  std::size_t data_begin_ = 0;
  bool header_complete_ = true;
  std::vector<std::int64_t> sizes_;
  std::vector<std::string> kinds_;
};

}  // namespace

VectorGrid parse_nrrd(std::string_view content, const std::filesystem::path& file) {
  return NrrdParser(content, file).parse();
}

VectorGrid read_nrrd(const std::filesystem::path& path) {
  return parse_nrrd(detail::read_file_bytes(path), path);
}

}  // namespace orthofront::io
