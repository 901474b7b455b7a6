#include "orthofront/seed/seed_curve.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "orthofront/error.h"

namespace orthofront {

SeedCurve SeedCurve::line(const Vec3& a, const Vec3& b) { return polyline({a, b}, false); }

SeedCurve SeedCurve::circle(const Vec3& center, const Vec3& normal, double radius, bool open) {
  SeedCurve c = arc(center, normal, radius, 0.0, 360.0);
  c.closed_ = !open;
  c.open_circle_ = open;
  return c;
}

SeedCurve SeedCurve::arc(const Vec3& center, const Vec3& normal, double radius, double a0_deg,
                         double a1_deg) {
  if (!(radius > 0) || !std::isfinite(radius))
    throw InvalidArgument("seed radius must be positive and finite, got " + std::to_string(radius));
  const double nn = normal.norm();
  if (!(nn > 0) || !std::isfinite(nn))
    throw InvalidArgument("seed circle normal must be a non-zero vector");
  if (a0_deg == a1_deg) throw InvalidArgument("seed arc has zero angular extent");
  const Vec3 n = normal / nn;
  // First in-plane axis: the coordinate axis least aligned with n, made orthogonal to it.
  Vec3 axis = Vec3::UnitX();
  if (std::abs(n.x()) > 0.9) axis = Vec3::UnitY();
  SeedCurve c;
  c.kind_ = Kind::circle;
  c.center_ = center;
  c.u_ = (axis - axis.dot(n) * n).normalized();
  c.w_ = n.cross(c.u_);
  c.radius_ = radius;
  c.a0_ = a0_deg * std::numbers::pi / 180.0;
  c.a1_ = a1_deg * std::numbers::pi / 180.0;
  c.length_ = radius * std::abs(c.a1_ - c.a0_);
  return c;
}

SeedCurve SeedCurve::polyline(std::vector<Vec3> points, bool closed) {
  if (points.size() < 2) throw InvalidArgument("a seed polyline needs at least two points");
  if (closed) points.push_back(points.front());
  SeedCurve c;
  c.kind_ = Kind::polyline;
  c.closed_ = closed;
  c.cumulative_.assign(points.size(), 0.0);
  for (std::size_t i = 1; i < points.size(); ++i)
    c.cumulative_[i] = c.cumulative_[i - 1] + (points[i] - points[i - 1]).norm();
  c.length_ = c.cumulative_.back();
  if (!(c.length_ > 0)) throw InvalidArgument("seed curve has zero length");
  for (double& v : c.cumulative_) v /= c.length_;
  c.points_ = std::move(points);
  return c;
}

SeedCurve SeedCurve::translated(const Vec3& offset) const {
  SeedCurve moved = *this;
  moved.center_ += offset;
  for (Vec3& p : moved.points_) p += offset;
  return moved;
}

Vec3 SeedCurve::point(double s) const {
  if (closed_ || open_circle_) s -= std::floor(s);
  if (kind_ == Kind::circle) {
    const double a = a0_ + s * (a1_ - a0_);
    return center_ + radius_ * (std::cos(a) * u_ + std::sin(a) * w_);
  }
  s = std::clamp(s, 0.0, 1.0);
  const auto it = std::upper_bound(cumulative_.begin(), cumulative_.end(), s);
  const std::size_t i = std::min<std::size_t>(
      static_cast<std::size_t>(std::max<std::ptrdiff_t>(it - cumulative_.begin(), 1)) - 1,
      points_.size() - 2);
  const double span = cumulative_[i + 1] - cumulative_[i];
  const double f = span > 0 ? (s - cumulative_[i]) / span : 0.0;
  return points_[i] + f * (points_[i + 1] - points_[i]);
}

std::vector<double> SeedCurve::sample(int count) const {
  if (count < 2) throw InvalidArgument("a seed needs at least 2 vertices, got " + std::to_string(count));
  std::vector<double> s(static_cast<std::size_t>(count));
  const bool periodic = closed_ || open_circle_;
  const double denom = periodic ? count : count - 1;
  for (int i = 0; i < count; ++i) s[static_cast<std::size_t>(i)] = i / denom;
  return s;
}

}  // namespace orthofront
