#include "cli/grid_args.h"

#include <charconv>
#include <cmath>
#include <vector>

#include "orthofront/error.h"

namespace orthofront::cli {

namespace {

std::vector<std::string> split(const std::string& text, char separator) {
  std::vector<std::string> parts;
  std::size_t start = 0;
  for (std::size_t p = text.find(separator); p != std::string::npos;
       start = p + 1, p = text.find(separator, start))
    parts.push_back(text.substr(start, p - start));
  parts.push_back(text.substr(start));
  return parts;
}

template <class T>
bool parse_number(const std::string& text, T& value) {
  const char* end = text.data() + text.size();
  const auto result = std::from_chars(text.data(), end, value);
  return result.ec == std::errc() && result.ptr == end;
}

Vec3 parse_point(const std::string& text, const std::string& what) {
  const auto parts = split(text, ',');
  Vec3 p;
  if (parts.size() != 3)
    throw InvalidArgument(what + " '" + text + "' must be three numbers x,y,z");
  for (int a = 0; a < 3; ++a)
    if (!parse_number(parts[static_cast<std::size_t>(a)], p[a]) || !std::isfinite(p[a]))
      throw InvalidArgument(what + " '" + text + "': '" + parts[static_cast<std::size_t>(a)] +
                            "' is not a finite number");
  return p;
}

}  // namespace

std::array<std::int64_t, 3> parse_resolution(const std::string& text) {
  const auto parts = split(text, ',');
  if (parts.size() != 2 && parts.size() != 3)
    throw InvalidArgument("--resolution '" + text + "' must be NX,NY,NZ or NX,NY");
  std::array<std::int64_t, 3> n{1, 1, 1};
  for (std::size_t a = 0; a < parts.size(); ++a)
    if (!parse_number(parts[a], n[a]) || n[a] < 1)
      throw InvalidArgument("--resolution '" + text + "': '" + parts[a] +
                            "' is not a positive integer");
  return n;
}

Box<3> parse_box(const std::string& text) {
  const auto corners = split(text, ':');
  if (corners.size() != 2)
    throw InvalidArgument("--box '" + text + "' must be xmin,ymin,zmin:xmax,ymax,zmax");
  Box<3> box;
  box.lo = parse_point(corners[0], "--box corner");
  box.hi = parse_point(corners[1], "--box corner");
  for (int a = 0; a < 3; ++a)
    if (!(box.hi[a] >= box.lo[a]))
      throw InvalidArgument("--box '" + text + "': max below min along " +
                            std::string(1, static_cast<char>('x' + a)));
  return box;
}

int parse_compression(const std::string& text) {
  if (text == "none") return 0;
  if (text == "gzip") return 4;
  int level = 0;
  if (text.rfind("gzip:", 0) == 0 && parse_number(text.substr(5), level) && level >= 1 &&
      level <= 9)
    return level;
  throw InvalidArgument("--compress '" + text + "' must be none, gzip or gzip:LEVEL (1-9)");
}

io::Hdf5Storage parse_layout(const std::string& text) {
  if (text == "chunked") return io::Hdf5Storage::chunked;
  if (text == "per-step") return io::Hdf5Storage::per_step;
  throw InvalidArgument("--layout '" + text + "' must be chunked or per-step");
}

}  // namespace orthofront::cli
