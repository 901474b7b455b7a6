#include "orthofront/io/vti_reader.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <optional>
#include <vector>

#include "orthofront/io/error.h"
#include "orthofront/io/grid_decode.h"
#include "orthofront/io/number_text.h"
#include "orthofront/io/vtk_xml.h"

namespace orthofront::io {
namespace {

using detail::ScalarType;
using detail::XmlTag;

using Extent = std::array<std::int64_t, 6>;

struct ArrayRef {
  std::string name;
  std::string type_name;
  std::size_t components = 1;
  std::string format;
  std::uint64_t offset = 0;     // appended
  std::string_view inline_text;  // ascii / binary
  std::size_t piece = 0;
};

struct Piece {
  Extent extent{};
  std::string vectors;  // the PointData Vectors attribute
  std::vector<ArrayRef> point_arrays;
  std::vector<std::string> cell_arrays;
};

class VtiParser {
 public:
  VtiParser(std::string_view content, std::string file, std::string array)
      : content_(content), file_(std::move(file)), wanted_(std::move(array)), xml_(content, file_) {}

  VectorGrid parse() {
    scan();
    VectorGrid grid;
    GridGeometry& g = grid.geometry;
    for (std::size_t a = 0; a < 3; ++a) {
      g.size[a] = whole_[2 * a + 1] - whole_[2 * a] + 1;
      g.origin[static_cast<int>(a)] = origin_[a] + static_cast<double>(whole_[2 * a]) * spacing_[a];
      g.spacing[static_cast<int>(a)] = spacing_[a];
      // An axis with one sample has no spacing to speak of: ParaView writes 0 there (a slice
      // saved from ResampleToImage). Any positive value describes the same grid.
      if (g.size[a] == 1 && spacing_[a] == 0.0) g.spacing[static_cast<int>(a)] = 1.0;
    }
    const std::string name = choose_array();
    const ArrayRef* first = find(pieces_.front(), name);
    const std::size_t first_components = first != nullptr ? first->components : 0;
    grid.components = static_cast<int>(first_components);
    if (grid.components != 2 && grid.components != 3) {
      throw error("point data '" + name + "' has " + std::to_string(first_components) +
                  " component(s): not vector data (need 2 or 3)");
    }
    g.dimension = g.size[2] == 1 ? 2 : 3;  // one z sample: a 2D grid (of 2- or 3-vectors)
    const std::size_t points = detail::checked_point_count(g.size, grid.components, file_,
                                                           "WholeExtent size");
    const auto nc = static_cast<std::size_t>(grid.components);
    // The grid is allocated (and filled) before the pieces are decoded: it must not be larger
    // than the file's bytes can hold in the most generous encoding its pieces use.
    double capacity = 0.0;
    for (const Piece& piece : pieces_) {
      if (const ArrayRef* ref = find(piece, name)) capacity = std::max(capacity, value_capacity(*ref));
    }
    if (static_cast<double>(points * nc) > capacity) {
      throw error("truncated: WholeExtent " + detail::size_text(g) + " needs " +
                  std::to_string(points * nc) + " values of point data '" + name +
                  "' but the file's " + std::to_string(content_.size()) + " bytes hold at most " +
                  std::to_string(static_cast<std::uint64_t>(capacity)));
    }
    grid.values.assign(points * nc, std::numeric_limits<float>::quiet_NaN());
    for (std::size_t p = 0; p < pieces_.size(); ++p) {
      const Piece& piece = pieces_[p];
      const ArrayRef* ref = find(piece, name);
      const std::string what = "piece " + std::to_string(p) + " point data '" + name + "'";
      if (ref == nullptr) throw error(what + " is missing");
      if (ref->components != nc) {
        throw error(what + " has " + std::to_string(ref->components) + " components, piece 0 has " +
                    std::to_string(nc));
      }
      std::array<std::int64_t, 3> n{};
      for (std::size_t a = 0; a < 3; ++a) {
        n[a] = piece.extent[2 * a + 1] - piece.extent[2 * a] + 1;
        if (n[a] < 1 || piece.extent[2 * a] < whole_[2 * a] ||
            piece.extent[2 * a + 1] > whole_[2 * a + 1]) {
          throw error("piece " + std::to_string(p) + " Extent lies outside the WholeExtent");
        }
      }
      const std::size_t tuples = static_cast<std::size_t>(n[0] * n[1] * n[2]);
      std::vector<float> values = decode(*ref, what, tuples * nc);
      // ParaView's resampling (ResampleToImage, ResampleWithDataset) marks the points that lie
      // outside the mesh it sampled with vtkValidPointMask = 0, and writes zeros there: no data.
      if (const ArrayRef* mask = find(piece, "vtkValidPointMask"); mask && mask != ref) {
        const std::string mask_what = "piece " + std::to_string(p) + " point data '" + mask->name + "'";
        if (mask->components != 1) throw error(mask_what + " has " + std::to_string(mask->components) + " components, not 1");
        const std::vector<float> valid = decode(*mask, mask_what, tuples);
        for (std::size_t t = 0; t < tuples; ++t)
          if (valid[t] == 0.0f)
            for (std::size_t c = 0; c < nc; ++c)
              values[t * nc + c] = std::numeric_limits<float>::quiet_NaN();
      }
      std::size_t at = 0;
      for (std::int64_t k = 0; k < n[2]; ++k) {
        for (std::int64_t j = 0; j < n[1]; ++j) {
          for (std::int64_t i = 0; i < n[0]; ++i) {
            const std::size_t dst = g.index(i + piece.extent[0] - whole_[0],
                                            j + piece.extent[2] - whole_[2],
                                            k + piece.extent[4] - whole_[4]) * nc;
            for (std::size_t c = 0; c < nc; ++c) grid.values[dst + c] = values[at++];
          }
        }
      }
    }
    detail::validate_grid(grid, file_);
    return grid;
  }

 private:
  FormatError error(const std::string& what) const { return FormatError(file_ + ": " + what); }

  Extent parse_extent(const XmlTag& tag, const char* key) const {
    const std::string* text = tag.attribute(key);
    if (text == nullptr) throw error("<" + tag.name + "> has no " + key);
    Extent e{};
    const std::vector<double> v = numbers(*text, key, 6);
    for (std::size_t i = 0; i < 6; ++i) {
      // Converting a double beyond int64's range is undefined: refuse it first.
      if (!(std::fabs(v[i]) < 0x1p62)) throw error(std::string("bad ") + key + " '" + *text + "'");
      e[i] = static_cast<std::int64_t>(v[i]);
      if (static_cast<double>(e[i]) != v[i]) throw error(std::string("bad ") + key + " '" + *text + "'");
    }
    for (std::size_t a = 0; a < 3; ++a) {
      if (e[2 * a + 1] < e[2 * a])
        throw error(std::string(key) + " '" + *text + "' is empty on axis " + std::to_string(a));
    }
    return e;
  }

  std::vector<double> numbers(const std::string& text, const std::string& key,
                              std::size_t count) const {
    std::vector<double> values;
    std::size_t pos = 0;
    while (pos < text.size()) {
      while (pos < text.size() && std::isspace(static_cast<unsigned char>(text[pos]))) ++pos;
      const std::size_t start = pos;
      while (pos < text.size() && !std::isspace(static_cast<unsigned char>(text[pos]))) ++pos;
      if (start == pos) break;
      double v = 0.0;
      if (!detail::parse_number(std::string_view(text).substr(start, pos - start), v))
        throw error("bad " + key + " '" + text + "'");
      values.push_back(v);
    }
    if (values.size() != count) {
      throw error(key + " '" + text + "' has " + std::to_string(values.size()) + " numbers, expected " +
                  std::to_string(count));
    }
    return values;
  }

  void scan() {
    XmlTag tag;
    std::vector<std::string> open;
    bool have_root = false;
    bool have_image = false;
    while (xml_.next(tag)) {
      if (tag.end) {
        if (!open.empty() && open.back() == tag.name) open.pop_back();
        continue;
      }
      const std::string parent = open.empty() ? std::string() : open.back();
      if (tag.name == "VTKFile" && open.empty()) {
        const std::string* type = tag.attribute("type");
        const std::string type_name = type ? *type : std::string();
        if (type_name != "ImageData") {
          throw error("VTK file type is '" + type_name + "', expected ImageData" +
                      (type_name == "PImageData" ? " (read the .vti pieces of a .pvti instead)" : ""));
        }
        layout_ = detail::read_vtk_layout(tag, file_);
        have_root = true;
      } else if (!have_root) {
        throw error("not a VTK XML file (no <VTKFile> element)");
      } else if (tag.name == "ImageData") {
        whole_ = parse_extent(tag, "WholeExtent");
        if (const std::string* o = tag.attribute("Origin")) {
          const auto v = numbers(*o, "Origin", 3);
          std::copy(v.begin(), v.end(), origin_.begin());
        }
        if (const std::string* s = tag.attribute("Spacing")) {
          const auto v = numbers(*s, "Spacing", 3);
          std::copy(v.begin(), v.end(), spacing_.begin());
        }
        if (const std::string* d = tag.attribute("Direction")) {
          const auto v = numbers(*d, "Direction", 9);
          for (std::size_t i = 0; i < 9; ++i) {
            if (v[i] != (i % 4 == 0 ? 1.0 : 0.0))
              throw error("Direction '" + *d + "' is not the identity (rotated images are not supported)");
          }
        }
        have_image = true;
      } else if (tag.name == "Piece" && parent == "ImageData") {
        Piece piece;
        piece.extent = parse_extent(tag, "Extent");
        pieces_.push_back(piece);
      } else if (tag.name == "PointData" && !pieces_.empty()) {
        if (const std::string* v = tag.attribute("Vectors")) pieces_.back().vectors = *v;
      } else if (tag.name == "DataArray" && !pieces_.empty() &&
                 (parent == "PointData" || parent == "CellData")) {
        read_array_tag(tag, parent == "PointData");
      } else if (tag.name == "AppendedData") {
        read_appended(tag);
        break;  // the rest is binary
      }
      if (!tag.self_closing) open.push_back(tag.name);
    }
    if (!have_root) throw error("not a VTK XML file (no <VTKFile> element)");
    if (!have_image) throw error("no <ImageData> element");
    if (pieces_.empty()) throw error("no <Piece> in <ImageData>");
  }

  void read_array_tag(const XmlTag& tag, bool point_data) {
    ArrayRef ref;
    if (const std::string* name = tag.attribute("Name")) ref.name = *name;
    if (!point_data) {
      pieces_.back().cell_arrays.push_back(ref.name);
      if (!tag.self_closing) xml_.text();
      return;
    }
    if (const std::string* type = tag.attribute("type")) ref.type_name = *type;
    const std::string what = "point data '" + ref.name + "'";
    if (const std::string* c = tag.attribute("NumberOfComponents")) {
      if (!detail::parse_number(*c, ref.components) || ref.components == 0)
        throw error(what + " has bad NumberOfComponents '" + *c + "'");
    }
    if (const std::string* f = tag.attribute("format")) ref.format = *f;
    if (ref.format == "appended") {
      const std::string* offset = tag.attribute("offset");
      if (offset == nullptr || !detail::parse_number(*offset, ref.offset))
        throw error(what + " has a bad or no offset");
    } else if (ref.format != "ascii" && ref.format != "binary") {
      throw error(what + " has unsupported format '" + ref.format + "'");
    }
    if (!tag.self_closing) ref.inline_text = xml_.text();
    ref.piece = pieces_.size() - 1;
    pieces_.back().point_arrays.push_back(ref);
  }

  void read_appended(const XmlTag& tag) {
    const std::string* encoding = tag.attribute("encoding");
    appended_encoding_ = encoding ? *encoding : std::string("raw");
    if (appended_encoding_ != "raw" && appended_encoding_ != "base64")
      throw error("unsupported AppendedData encoding '" + appended_encoding_ + "'");
    const std::size_t underscore = content_.find('_', xml_.position());
    if (underscore == std::string_view::npos)
      throw error("truncated: <AppendedData> has no '_' before its data");
    appended_ = content_.substr(underscore + 1);
    const std::size_t close = appended_.rfind("</AppendedData>");
    if (close != std::string_view::npos) {
      appended_ = appended_.substr(0, close);
    } else if (appended_encoding_ == "base64") {
      throw error("truncated: <AppendedData> is not closed");
    }
    has_appended_ = true;
  }

  const ArrayRef* find(const Piece& piece, const std::string& name) const {
    for (const ArrayRef& ref : piece.point_arrays) {
      if (ref.name == name) return &ref;
    }
    return nullptr;
  }

  std::string choose_array() const {
    const Piece& piece = pieces_.front();
    std::string names;
    for (const ArrayRef& ref : piece.point_arrays) {
      names += (names.empty() ? "" : ", ") + ref.name + " (" + std::to_string(ref.components) +
               " components)";
    }
    if (!wanted_.empty()) {
      if (find(piece, wanted_) == nullptr) {
        throw error("no point data array named '" + wanted_ + "' (point data: " +
                    (names.empty() ? "none" : names) + ")");
      }
      return wanted_;
    }
    if (!piece.vectors.empty() && find(piece, piece.vectors) != nullptr) return piece.vectors;
    for (const std::size_t want : {std::size_t{3}, std::size_t{2}}) {
      for (const ArrayRef& ref : piece.point_arrays) {
        if (ref.components == want) return ref.name;
      }
    }
    std::string message = "no vector point data (2 or 3 components); point data: " +
                          (names.empty() ? std::string("none") : names);
    if (!piece.cell_arrays.empty()) message += "; cell data is not supported";
    throw error(message);
  }

  /// The most values the whole file could give an array stored as `ref`: a character and a
  /// separator per ascii value; the scalar's bytes per binary value, times deflate's 1032:1 at
  /// most when compressed.
  double value_capacity(const ArrayRef& ref) const {
    const auto bytes = static_cast<double>(content_.size());
    if (ref.format == "ascii") return (bytes + 1.0) / 2.0;
    const auto type = detail::vtk_type(ref.type_name);
    const double scalar = type ? static_cast<double>(detail::scalar_size(*type)) : 1.0;
    return bytes * (layout_.compressor.empty() ? 1.0 : 1032.0) / scalar;
  }

  /// The `count` values of `ref`; nothing of that size is allocated before the data proved to
  /// hold it.
  std::vector<float> decode(const ArrayRef& ref, const std::string& what, std::size_t count) const {
    const auto type = detail::vtk_type(ref.type_name);
    if (!type) throw error(what + " has unsupported type '" + ref.type_name + "'");
    std::vector<float> out;
    if (ref.format == "ascii") {
      std::size_t pos = 0;
      const std::string_view text = ref.inline_text;
      out.reserve(std::min(count, (text.size() + 1) / 2));  // a character and a separator each
      std::size_t i = 0;
      for (;;) {
        while (pos < text.size() && std::isspace(static_cast<unsigned char>(text[pos]))) ++pos;
        if (pos == text.size()) break;
        const std::size_t start = pos;
        while (pos < text.size() && !std::isspace(static_cast<unsigned char>(text[pos]))) ++pos;
        double v = 0.0;
        if (!detail::parse_number(text.substr(start, pos - start), v))
          throw error(what + " has the bad value '" + std::string(text.substr(start, pos - start)) + "'");
        if (i < count) out.push_back(static_cast<float>(v));
        ++i;
      }
      check_count(what, i, count);
      return out;
    }
    std::string bytes;
    const std::string context = file_ + ": " + what;
    if (ref.format == "binary") {
      bytes = detail::decode_vtk_base64(ref.inline_text, layout_, context);
    } else {
      if (!has_appended_) throw error(what + " is appended but there is no <AppendedData>");
      if (ref.offset > appended_.size()) {
        throw error("truncated: " + what + " starts at appended offset " +
                    std::to_string(ref.offset) + " but the appended data has " +
                    std::to_string(appended_.size()) + " bytes");
      }
      if (appended_encoding_ == "raw") {
        bytes = detail::decode_vtk_block(appended_.substr(static_cast<std::size_t>(ref.offset)),
                                         layout_, context);
      } else {
        // Up to the next array's offset (base64 offsets count encoded characters).
        std::uint64_t end = appended_.size();
        for (const Piece& piece : pieces_) {
          for (const ArrayRef& other : piece.point_arrays) {
            if (other.format == "appended" && other.offset > ref.offset) end = std::min(end, other.offset);
          }
        }
        bytes = detail::decode_vtk_base64(
            appended_.substr(static_cast<std::size_t>(ref.offset),
                             static_cast<std::size_t>(end - ref.offset)),
            layout_, context);
      }
    }
    const std::size_t scalar = detail::scalar_size(*type);
    if (bytes.size() % scalar != 0) {
      throw error(what + " holds " + std::to_string(bytes.size()) + " bytes, not a multiple of " +
                  std::to_string(scalar));
    }
    check_count(what, bytes.size() / scalar, count);
    out.resize(count);
    detail::scalars_to_floats(*type, reinterpret_cast<const unsigned char*>(bytes.data()), count,
                              layout_.little_endian, out.data());
    return out;
  }

  void check_count(const std::string& what, std::size_t got, std::size_t count) const {
    if (got != count) {
      throw error(what + " holds " + std::to_string(got) + " values; the extent needs " +
                  std::to_string(count) + (got < count ? " (truncated?)" : ""));
    }
  }

  std::string_view content_;
  std::string file_;
  std::string wanted_;
  detail::XmlScanner xml_;
  detail::VtkLayout layout_;
  Extent whole_{};
  std::array<double, 3> origin_{0.0, 0.0, 0.0};
  std::array<double, 3> spacing_{1.0, 1.0, 1.0};
  std::vector<Piece> pieces_;
  bool has_appended_ = false;
  std::string appended_encoding_;
  std::string_view appended_;
};

}  // namespace

VectorGrid parse_vti(std::string_view content, const std::string& file, const std::string& array) {
  return VtiParser(content, file, array).parse();
}

VectorGrid read_vti(const std::filesystem::path& path, const std::string& array) {
  return parse_vti(detail::read_file_bytes(path), path.string(), array);
}

}  // namespace orthofront::io
