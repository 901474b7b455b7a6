#include "jobs/seed_spec.h"

#include <charconv>
#include <fstream>
#include <sstream>
#include <vector>

#include "orthofront/error.h"
#include "orthofront/io/error.h"

namespace orthofront::jobs {

namespace {

std::vector<std::string> split(const std::string& text, char sep) {
  std::vector<std::string> parts;
  std::string part;
  std::istringstream in(text);
  while (std::getline(in, part, sep)) parts.push_back(part);
  if (!text.empty() && text.back() == sep) parts.emplace_back();
  return parts;
}

double number(const std::string& text, const std::string& spec) {
  double value = 0;
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, value);
  if (text.empty() || ec != std::errc() || ptr != end || !std::isfinite(value))
    throw InvalidArgument("seed '" + spec + "': '" + text + "' is not a finite number");
  return value;
}

Vec3 point(const std::string& text, const std::string& spec) {
  const auto c = split(text, ',');
  if (c.size() != 3)
    throw InvalidArgument("seed '" + spec + "': '" + text + "' is not a point x,y,z");
  return {number(c[0], spec), number(c[1], spec), number(c[2], spec)};
}

SeedCurve read_csv(const std::string& path, bool closed, const std::string& spec) {
  std::ifstream in(path);
  if (!in) throw io::IoError("seed file '" + path + "' cannot be opened");
  std::vector<Vec3> points;
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty() || line[0] == '#') continue;
    std::string cleaned;
    for (char ch : line) cleaned += (ch == ' ' || ch == '\t' || ch == ';') ? ',' : ch;
    std::vector<std::string> fields;
    for (auto& f : split(cleaned, ','))
      if (!f.empty()) fields.push_back(f);
    if (fields.size() != 3)
      throw InvalidArgument("seed file '" + path + "' line " + std::to_string(line_no) +
                            ": expected 3 numbers, got '" + line + "'");
    try {
      points.emplace_back(number(fields[0], spec), number(fields[1], spec),
                          number(fields[2], spec));
    } catch (const InvalidArgument&) {
      throw InvalidArgument("seed file '" + path + "' line " + std::to_string(line_no) +
                            ": '" + line + "' is not three finite numbers");
    }
  }
  if (points.size() < 2)
    throw InvalidArgument("seed file '" + path + "' holds " + std::to_string(points.size()) +
                          " points; at least 2 are needed");
  return SeedCurve::polyline(std::move(points), closed);
}

}  // namespace

SeedCurve parse_seed(const std::string& spec) {
  const auto colon = spec.find(':');
  const std::string kind = spec.substr(0, colon);
  const std::string rest = colon == std::string::npos ? "" : spec.substr(colon + 1);
  if (kind == "file") {
    bool closed = false;
    std::string path = rest;
    if (path.size() > 7 && path.ends_with(":closed")) {
      closed = true;
      path.resize(path.size() - 7);
    }
    if (path.empty()) throw InvalidArgument("seed '" + spec + "': no file name after 'file:'");
    return read_csv(path, closed, spec);
  }
  const auto parts = split(rest, ':');
  if (kind == "line") {
    if (parts.size() != 2)
      throw InvalidArgument("seed '" + spec + "': expected line:x0,y0,z0:x1,y1,z1");
    const Vec3 a = point(parts[0], spec), b = point(parts[1], spec);
    if ((a - b).norm() == 0) throw InvalidArgument("seed '" + spec + "': the two ends coincide");
    return SeedCurve::line(a, b);
  }
  if (kind == "circle") {
    if (parts.size() != 3 && !(parts.size() == 4 && parts[3] == "open"))
      throw InvalidArgument("seed '" + spec + "': expected circle:cx,cy,cz:nx,ny,nz:r[:open]");
    const double r = number(parts[2], spec);
    if (!(r > 0)) throw InvalidArgument("seed '" + spec + "': radius " + parts[2] + " is not positive");
    return SeedCurve::circle(point(parts[0], spec), point(parts[1], spec), r, parts.size() == 4);
  }
  if (kind == "arc") {
    if (parts.size() != 4)
      throw InvalidArgument("seed '" + spec + "': expected arc:cx,cy,cz:nx,ny,nz:r:a0,a1");
    const auto angles = split(parts[3], ',');
    if (angles.size() != 2)
      throw InvalidArgument("seed '" + spec + "': '" + parts[3] + "' is not two angles a0,a1");
    const double r = number(parts[2], spec);
    if (!(r > 0)) throw InvalidArgument("seed '" + spec + "': radius " + parts[2] + " is not positive");
    return SeedCurve::arc(point(parts[0], spec), point(parts[1], spec), r,
                          number(angles[0], spec), number(angles[1], spec));
  }
  throw InvalidArgument("seed '" + spec + "': unknown kind '" + kind +
                        "' (expected line, circle, arc or file)");
}

}  // namespace orthofront::jobs
