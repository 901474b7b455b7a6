#include "jobs/grid_args.h"

#include <charconv>
#include <cmath>
#include <limits>
#include <vector>

#include "orthofront/error.h"

namespace orthofront::jobs {

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

// "x,y,z", or "x,y" where `z` is given (a 2D point).
Vec3 parse_point(const std::string& text, const std::string& what, const double* z = nullptr) {
  const auto parts = split(text, ',');
  Vec3 p;
  if (parts.size() != 3 && !(z && parts.size() == 2))
    throw InvalidArgument(what + " '" + text + "' must be three numbers x,y,z" +
                          (z ? " or two x,y" : ""));
  for (std::size_t a = 0; a < parts.size(); ++a)
    if (!parse_number(parts[a], p[static_cast<int>(a)]) || !std::isfinite(p[static_cast<int>(a)]))
      throw InvalidArgument(what + " '" + text + "': '" + parts[a] + "' is not a finite number");
  if (parts.size() == 2) p.z() = *z;
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

Box<3> parse_box(const std::string& text, const std::string& option, bool planar) {
  const auto corners = split(text, ':');
  const std::string form =
      std::string("xmin,ymin,zmin:xmax,ymax,zmax") + (planar ? " or xmin,ymin:xmax,ymax" : "");
  if (corners.size() != 2) throw InvalidArgument(option + " '" + text + "' must be " + form);
  const double low = -std::numeric_limits<double>::infinity(), high = -low;
  Box<3> box;
  box.lo = parse_point(corners[0], option + " corner", planar ? &low : nullptr);
  box.hi = parse_point(corners[1], option + " corner", planar ? &high : nullptr);
  for (int a = 0; a < 3; ++a)
    if (!(box.hi[a] >= box.lo[a]))
      throw InvalidArgument(option + " '" + text + "': max below min along " +
                            std::string(1, static_cast<char>('x' + a)));
  return box;
}

Compression parse_compression(const std::string& text) {
  const std::string name = text.substr(0, text.find(':'));
  Compression c;
  if (name == "none" && name == text) return c;
  if (name == "gzip") c = {io::Hdf5Codec::gzip, 4};
  else if (name == "lz4") c = {io::Hdf5Codec::lz4, 5};
  else if (name == "zstd") c = {io::Hdf5Codec::zstd, 1};
  else
    throw InvalidArgument("--compress '" + text +
                          "' must be none, lz4, zstd or gzip, optionally with :LEVEL (1-9)");
  if (name != text) {
    int level = 0;
    if (!parse_number(text.substr(name.size() + 1), level) || level < 1 || level > 9)
      throw InvalidArgument("--compress '" + text + "': the level must be 1 to 9");
    c.level = level;
  }
  return c;
}

void apply_compression(const Compression& c, io::Hdf5WriteOptions& options) {
  options.codec = c.codec;
  options.level = c.level;
  options.gzip_level = c.codec == io::Hdf5Codec::gzip ? c.level : 0;
}

std::string sidecar_text(const io::Hdf5WriteOptions& options, const std::string& file) {
  if (io::xdmf_readable(options)) return " and " + io::xdmf_path(file).string();
  return std::string(" (no .xmf: ParaView's HDF5 cannot decode Blosc ") +
         io::to_string(options.codec) +
         "; --compress gzip or none writes one for ParaView's XDMF reader)";
}

io::Hdf5Storage parse_layout(const std::string& text) {
  if (text == "bricked") return io::Hdf5Storage::bricked;
  if (text == "chunked") return io::Hdf5Storage::chunked;
  if (text == "per-step") return io::Hdf5Storage::per_step;
  throw InvalidArgument("--layout '" + text + "' must be bricked, chunked or per-step");
}

}  // namespace orthofront::jobs
