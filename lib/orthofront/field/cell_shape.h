#pragma once
/// The linear cells of unstructured meshes (tetrahedron, pyramid, wedge, hexahedron) in VTK's
/// point order: shape functions, their parametric derivatives, the inverse of the cell map and
/// the faces a point outside the cell leaves through. One body for the CPU and CUDA: plain
/// arrays, no Eigen, no virtual calls, no allocation.
#include <cmath>
#include <cstdint>

#include "orthofront/advect/host_device.h"

namespace orthofront {

/// The value is the number of points (VTK cell types 10, 14, 13, 12).
enum class CellShape : std::uint8_t { tetrahedron = 4, pyramid = 5, wedge = 6, hexahedron = 8 };

namespace cell {

/// Points of a shape.
ORTHOFRONT_HD inline int point_count(CellShape s) { return static_cast<int>(s); }

/// Faces of a shape (4, 5, 5, 6).
ORTHOFRONT_HD inline int face_count(CellShape s) {
  switch (s) {
    case CellShape::tetrahedron: return 4;
    case CellShape::pyramid: return 5;
    case CellShape::wedge: return 5;
    case CellShape::hexahedron: return 6;
  }
  return 0;
}

/// The local points of face `f` of shape `s` (3 or 4 of them, returned as the count; -1 pads).
/// Face f is the face on which the parametric constraint f of `outside_face` is tight, so a walk
/// leaves a cell through the face of its most violated constraint.
ORTHOFRONT_HD inline int face_points(CellShape s, int f, int points[4]) {
  // Tetrahedron: r = 0, s = 0, t = 0, r + s + t = 1.
  constexpr int tet[4][4] = {{0, 2, 3, -1}, {0, 1, 3, -1}, {0, 1, 2, -1}, {1, 2, 3, -1}};
  // Pyramid: r = 0, r = 1, s = 0, s = 1, t = 0.
  constexpr int pyr[5][4] = {{0, 3, 4, -1}, {1, 2, 4, -1}, {0, 1, 4, -1}, {3, 2, 4, -1},
                             {0, 1, 2, 3}};
  // Wedge: r = 0, s = 0, r + s = 1, t = 0, t = 1.
  constexpr int wdg[5][4] = {{0, 2, 5, 3}, {0, 1, 4, 3}, {1, 2, 5, 4}, {0, 1, 2, -1},
                             {3, 4, 5, -1}};
  // Hexahedron: r = 0, r = 1, s = 0, s = 1, t = 0, t = 1.
  constexpr int hex[6][4] = {{0, 3, 7, 4}, {1, 2, 6, 5}, {0, 1, 5, 4},
                             {3, 2, 6, 7}, {0, 1, 2, 3}, {4, 5, 6, 7}};
  const int* row = hex[f];
  switch (s) {
    case CellShape::tetrahedron: row = tet[f]; break;
    case CellShape::pyramid: row = pyr[f]; break;
    case CellShape::wedge: row = wdg[f]; break;
    case CellShape::hexahedron: break;
  }
  int n = 0;
  for (int i = 0; i < 4; ++i) {
    points[i] = row[i];
    if (row[i] >= 0) ++n;
  }
  return n;
}

/// Shape functions N_i(r, s, t) and their derivatives dN[i][a] = ∂N_i/∂ξ_a at ξ = (r, s, t).
ORTHOFRONT_HD inline void shape_functions(CellShape shape, const double xi[3], double N[8],
                                          double dN[8][3]) {
  const double r = xi[0], s = xi[1], t = xi[2];
  switch (shape) {
    case CellShape::tetrahedron: {
      N[0] = 1 - r - s - t, N[1] = r, N[2] = s, N[3] = t;
      const double d[4][3] = {{-1, -1, -1}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
      for (int i = 0; i < 4; ++i)
        for (int a = 0; a < 3; ++a) dN[i][a] = d[i][a];
      return;
    }
    case CellShape::pyramid: {
      // VTK's pyramid: the base bilinear, collapsing linearly to the apex.
      const double u = 1 - t;
      N[0] = (1 - r) * (1 - s) * u, N[1] = r * (1 - s) * u, N[2] = r * s * u,
      N[3] = (1 - r) * s * u, N[4] = t;
      const double d[5][3] = {{-(1 - s) * u, -(1 - r) * u, -(1 - r) * (1 - s)},
                              {(1 - s) * u, -r * u, -r * (1 - s)},
                              {s * u, r * u, -r * s},
                              {-s * u, (1 - r) * u, -(1 - r) * s},
                              {0, 0, 1}};
      for (int i = 0; i < 5; ++i)
        for (int a = 0; a < 3; ++a) dN[i][a] = d[i][a];
      return;
    }
    case CellShape::wedge: {
      const double w = 1 - r - s;
      N[0] = w * (1 - t), N[1] = r * (1 - t), N[2] = s * (1 - t);
      N[3] = w * t, N[4] = r * t, N[5] = s * t;
      const double d[6][3] = {{-(1 - t), -(1 - t), -w}, {1 - t, 0, -r}, {0, 1 - t, -s},
                              {-t, -t, w},               {t, 0, r},      {0, t, s}};
      for (int i = 0; i < 6; ++i)
        for (int a = 0; a < 3; ++a) dN[i][a] = d[i][a];
      return;
    }
    case CellShape::hexahedron: {
      // Points 0-3 on t = 0 at (r, s) = (0,0), (1,0), (1,1), (0,1); 4-7 the same on t = 1.
      constexpr int cr[8] = {0, 1, 1, 0, 0, 1, 1, 0};
      constexpr int cs[8] = {0, 0, 1, 1, 0, 0, 1, 1};
      constexpr int ct[8] = {0, 0, 0, 0, 1, 1, 1, 1};
      for (int i = 0; i < 8; ++i) {
        const double fr = cr[i] ? r : 1 - r, fs = cs[i] ? s : 1 - s, ft = ct[i] ? t : 1 - t;
        const double gr = cr[i] ? 1 : -1, gs = cs[i] ? 1 : -1, gt = ct[i] ? 1 : -1;
        N[i] = fr * fs * ft;
        dN[i][0] = gr * fs * ft, dN[i][1] = fr * gs * ft, dN[i][2] = fr * fs * gt;
      }
      return;
    }
  }
}

/// The parametric centre of a shape (the Newton start of `invert`).
ORTHOFRONT_HD inline void centre(CellShape s, double xi[3]) {
  switch (s) {
    case CellShape::tetrahedron: xi[0] = xi[1] = xi[2] = 0.25; return;
    case CellShape::pyramid: xi[0] = xi[1] = 0.5, xi[2] = 0.2; return;
    case CellShape::wedge: xi[0] = xi[1] = 1.0 / 3, xi[2] = 0.5; return;
    case CellShape::hexahedron: xi[0] = xi[1] = xi[2] = 0.5; return;
  }
}

/// The index of the most violated parametric constraint of ξ (the face to leave through, see
/// face_points) and by how much (≤ 0 when ξ lies in the cell).
ORTHOFRONT_HD inline int outside_face(CellShape shape, const double xi[3], double& violation) {
  const double r = xi[0], s = xi[1], t = xi[2];
  double g[6] = {0, 0, 0, 0, 0, 0};
  int n = 0;
  switch (shape) {
    case CellShape::tetrahedron:
      g[0] = -r, g[1] = -s, g[2] = -t, g[3] = r + s + t - 1, n = 4;
      break;
    case CellShape::pyramid:
      g[0] = -r, g[1] = r - 1, g[2] = -s, g[3] = s - 1, g[4] = -t, n = 5;
      if (t > 1) g[4] = t - 1;  // above the apex: leave through the base's opposite faces
      break;
    case CellShape::wedge:
      g[0] = -r, g[1] = -s, g[2] = r + s - 1, g[3] = -t, g[4] = t - 1, n = 5;
      break;
    case CellShape::hexahedron:
      g[0] = -r, g[1] = r - 1, g[2] = -s, g[3] = s - 1, g[4] = -t, g[5] = t - 1, n = 6;
      break;
  }
  int worst = 0;
  for (int i = 1; i < n; ++i)
    if (g[i] > g[worst]) worst = i;
  violation = g[worst];
  return worst;
}

/// x(ξ) = Σ N_i(ξ) p_i and the map's derivative A(a, b) = ∂x_a/∂ξ_b, for the cell's points
/// `p` (xyz triples).
ORTHOFRONT_HD inline void map_point(CellShape shape, const double (*p)[3], const double xi[3],
                                    double x[3], double A[3][3]) {
  double N[8], dN[8][3];
  shape_functions(shape, xi, N, dN);
  for (int a = 0; a < 3; ++a) {
    x[a] = 0;
    for (int b = 0; b < 3; ++b) A[a][b] = 0;
  }
  for (int i = 0; i < point_count(shape); ++i)
    for (int a = 0; a < 3; ++a) {
      x[a] += N[i] * p[i][a];
      for (int b = 0; b < 3; ++b) A[a][b] += dN[i][b] * p[i][a];
    }
}

ORTHOFRONT_HD inline double determinant(const double A[3][3]) {
  return A[0][0] * (A[1][1] * A[2][2] - A[1][2] * A[2][1]) -
         A[0][1] * (A[1][0] * A[2][2] - A[1][2] * A[2][0]) +
         A[0][2] * (A[1][0] * A[2][1] - A[1][1] * A[2][0]);
}

/// B = A⁻¹; false when A is singular (|det| not above `tiny`).
ORTHOFRONT_HD inline bool invert3(const double A[3][3], double B[3][3], double tiny = 0) {
  const double det = determinant(A);
  if (!(fabs(det) > tiny)) return false;
  const double k = 1 / det;
  B[0][0] = (A[1][1] * A[2][2] - A[1][2] * A[2][1]) * k;
  B[0][1] = (A[0][2] * A[2][1] - A[0][1] * A[2][2]) * k;
  B[0][2] = (A[0][1] * A[1][2] - A[0][2] * A[1][1]) * k;
  B[1][0] = (A[1][2] * A[2][0] - A[1][0] * A[2][2]) * k;
  B[1][1] = (A[0][0] * A[2][2] - A[0][2] * A[2][0]) * k;
  B[1][2] = (A[0][2] * A[1][0] - A[0][0] * A[1][2]) * k;
  B[2][0] = (A[1][0] * A[2][1] - A[1][1] * A[2][0]) * k;
  B[2][1] = (A[0][1] * A[2][0] - A[0][0] * A[2][1]) * k;
  B[2][2] = (A[0][0] * A[1][1] - A[0][1] * A[1][0]) * k;
  return true;
}

/// Solves x(ξ) = x for ξ by Newton's method from the cell's centre (one step is exact for a
/// tetrahedron and for parallelepipeds). Returns false when the map is singular on the way or the
/// iteration does not settle (a point far outside a strongly distorted cell); ξ then holds the
/// last iterate, still useful to pick a face to walk through.
ORTHOFRONT_HD inline bool invert(CellShape shape, const double (*p)[3], const double x[3],
                                 double xi[3]) {
  centre(shape, xi);
  double scale = 0;  // the cell's size, for a relative stopping test
  for (int i = 1; i < point_count(shape); ++i)
    for (int a = 0; a < 3; ++a) scale = fmax(scale, fabs(p[i][a] - p[0][a]));
  const double tol = 1e-13 * scale;
  for (int it = 0; it < 24; ++it) {
    double y[3], A[3][3], B[3][3];
    map_point(shape, p, xi, y, A);
    const double res[3] = {x[0] - y[0], x[1] - y[1], x[2] - y[2]};
    if (fabs(res[0]) <= tol && fabs(res[1]) <= tol && fabs(res[2]) <= tol) return true;
    if (!invert3(A, B)) return false;
    double step_size = 0;
    for (int a = 0; a < 3; ++a) {
      const double d = B[a][0] * res[0] + B[a][1] * res[1] + B[a][2] * res[2];
      xi[a] += d;
      step_size = fmax(step_size, fabs(d));
    }
    if (step_size < 1e-14) return true;
    // A point far away diverges rather than converges; stop early, it is outside anyway.
    if (fabs(xi[0]) > 1e3 || fabs(xi[1]) > 1e3 || fabs(xi[2]) > 1e3) return false;
  }
  return false;
}

}  // namespace cell
}  // namespace orthofront
