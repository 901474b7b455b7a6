#include "orthofront/io/obj_codec.h"

#include <cstdint>
#include <limits>
#include <vector>

#include "orthofront/io/error.h"
#include "orthofront/io/number_text.h"

namespace orthofront::io::detail {
namespace {

bool is_space(char c) {
  return c == ' ' || c == '\t' || c == '\r';
}

std::vector<std::string_view> split_words(std::string_view line) {
  std::vector<std::string_view> words;
  std::size_t pos = 0;
  while (pos < line.size()) {
    while (pos < line.size() && is_space(line[pos])) ++pos;
    const std::size_t start = pos;
    while (pos < line.size() && !is_space(line[pos])) ++pos;
    if (pos > start) words.push_back(line.substr(start, pos - start));
  }
  return words;
}

}  // namespace

void write_obj(const Mesh& mesh, std::ostream& out) {
  std::string text = "# orthofront mesh: " + std::to_string(mesh.positions.size()) + " vertices, " +
                     std::to_string(mesh.faces.size()) + " faces\n";
  constexpr std::size_t kChunk = 1 << 20;
  const auto flush = [&](bool force) {
    if (text.size() < kChunk && !force) return;
    out.write(text.data(), static_cast<std::streamsize>(text.size()));
    text.clear();
  };
  for (const Vec3& p : mesh.positions) {
    text += 'v';
    for (int c = 0; c < 3; ++c) {
      text += ' ';
      append_number(text, p[c]);
    }
    text += '\n';
    flush(false);
  }
  for (const Face& face : mesh.faces) {
    text += 'f';
    for (int k = 0; k < face.size; ++k) {
      text += ' ';
      append_number(text, static_cast<std::int64_t>(face.v[k]) + 1);
    }
    text += '\n';
    flush(false);
  }
  flush(true);
}

Mesh read_obj(std::string_view data, const std::string& file) {
  Mesh mesh;
  std::size_t pos = 0;
  for (std::size_t line_number = 1; pos < data.size(); ++line_number) {
    std::size_t eol = data.find('\n', pos);
    if (eol == std::string_view::npos) eol = data.size();
    const std::string_view line = data.substr(pos, eol - pos);
    pos = eol + 1;
    const auto words = split_words(line);
    if (words.empty()) continue;
    const auto error = [&](const std::string& what) {
      return FormatError(file + ": line " + std::to_string(line_number) + ": " + what);
    };
    if (words[0] == "v") {
      // "v x y z [w]" or "v x y z r g b": only x y z are positions.
      Vec3 position;
      if (words.size() < 4) throw error("vertex with fewer than 3 coordinates");
      for (int c = 0; c < 3; ++c) {
        if (!parse_number(words[1 + c], position[c])) {
          throw error("bad vertex coordinate '" + std::string(words[1 + c]) + "'");
        }
      }
      mesh.positions.push_back(position);
    } else if (words[0] == "f") {
      const std::size_t n = words.size() - 1;
      if (n < 3 || n > 4) {
        throw error("face with " + std::to_string(n) +
                    " vertices; only triangles and quads are supported");
      }
      Face face;
      face.size = static_cast<std::uint8_t>(n);
      for (std::size_t k = 0; k < n; ++k) {
        const std::string_view ref = words[1 + k].substr(0, words[1 + k].find('/'));
        std::int64_t index = 0;
        if (!parse_number(ref, index) || index == 0) {
          throw error("bad vertex reference '" + std::string(words[1 + k]) + "'");
        }
        // Negative references count back from the latest vertex.
        index = index < 0 ? static_cast<std::int64_t>(mesh.positions.size()) + index : index - 1;
        if (index < 0 || index > std::numeric_limits<std::int32_t>::max()) {
          throw error("vertex reference '" + std::string(words[1 + k]) + "' is out of range");
        }
        face.v[k] = static_cast<std::int32_t>(index);
      }
      mesh.faces.push_back(face);
    }
  }
  for (std::size_t i = 0; i < mesh.faces.size(); ++i) {
    const Face& face = mesh.faces[i];
    for (int k = 0; k < face.size; ++k) {
      if (static_cast<std::size_t>(face.v[k]) >= mesh.positions.size()) {
        throw FormatError(file + ": face " + std::to_string(i) + " refers to vertex " +
                          std::to_string(face.v[k] + 1) + " but there are " +
                          std::to_string(mesh.positions.size()) + " vertices");
      }
    }
  }
  return mesh;
}

}  // namespace orthofront::io::detail
