#pragma once
/// Seed curves: the curve a stream surface starts from, parametrised by s in [0, 1] with
/// uniform speed (s is proportional to arc length), open or closed.
#include <vector>

#include "orthofront/types.h"

namespace orthofront {

class SeedCurve {
 public:
  /// Segment from a to b (open).
  static SeedCurve line(const Vec3& a, const Vec3& b);
  /// Circle of radius r around `center` in the plane normal to `normal`; closed unless `open`
  /// (an open circle is sampled without repeating its first point and has no closing segment).
  static SeedCurve circle(const Vec3& center, const Vec3& normal, double radius, bool open = false);
  /// Arc of the circle above from angle a0 to a1 (degrees, measured from the plane's first axis).
  static SeedCurve arc(const Vec3& center, const Vec3& normal, double radius, double a0_deg,
                       double a1_deg);
  /// Polyline through `points` (at least two), closed when `closed` is true.
  static SeedCurve polyline(std::vector<Vec3> points, bool closed);

  /// The same curve moved by `offset` (seed rakes and grids of a batch job).
  SeedCurve translated(const Vec3& offset) const;
  /// Point at parameter s; closed curves take s modulo 1.
  Vec3 point(double s) const;
  bool closed() const { return closed_; }
  double length() const { return length_; }
  /// `count` parameters: uniform over [0, 1] for open curves, over [0, 1) for closed ones and for
  /// open circles.
  std::vector<double> sample(int count) const;

 private:
  enum class Kind { polyline, circle };
  Kind kind_ = Kind::polyline;
  bool closed_ = false;
  bool open_circle_ = false;
  double length_ = 0;
  // circle
  Vec3 center_ = Vec3::Zero(), u_ = Vec3::UnitX(), w_ = Vec3::UnitY();
  double radius_ = 0, a0_ = 0, a1_ = 0;  // radians
  // polyline
  std::vector<Vec3> points_;
  std::vector<double> cumulative_;  // arc length at each point, normalised to [0, 1]
};

}  // namespace orthofront
