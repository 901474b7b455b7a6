#include "orthofront/solve/alpha_solver.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <stdexcept>

namespace orthofront {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// sqrt(a^2 + b^2). std::hypot is several times slower and sits on the critical path of the
// factorisation, so it is kept for the range where the squares overflow or lose digits to
// underflow.
inline double hypot_fast(double a, double b) {
  const double sum = a * a + b * b;
  if (sum >= 1e-290 && sum <= 1e290) return std::sqrt(sum);
  return std::hypot(a, b);
}

// Admissible μ at speed level t: vertex i allows (-t - a_i s_i) / (k_i s_i) <= μ <=
// (t - a_i s_i) / (k_i s_i) (bounds swapped for k_i < 0), so the set is [max_i lo_i, min_i hi_i].
// Each bound moves with t at the rate w_i = 1 / |k_i s_i|.
struct Envelope {
  double lo = -kInf;
  double hi = kInf;
  double lo_w = 0;  // w of the line bounding lo (its slope in t is -lo_w)
  double hi_w = 0;  // w of the line bounding hi (its slope in t is +hi_w)
};

Envelope envelope_at(double t, std::span<const double> a, std::span<const double> k,
                     std::span<const double> s) {
  Envelope e;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const double ks = k[i] * s[i];
    if (!(s[i] > 0) || ks == 0) continue;
    const double inv = 1 / ks;
    const double as = a[i] * s[i];
    const double b1 = (-t - as) * inv;
    const double b2 = (t - as) * inv;
    const double lo = std::min(b1, b2);
    const double hi = std::max(b1, b2);
    const double w = std::abs(inv);
    // On ties keep the flatter line: it gives the right-hand derivative in t.
    if (lo > e.lo || (lo == e.lo && w < e.lo_w)) {
      e.lo = lo;
      e.lo_w = w;
    }
    if (hi < e.hi || (hi == e.hi && w < e.hi_w)) {
      e.hi = hi;
      e.hi_w = w;
    }
  }
  return e;
}

// Speed no μ can remove: vertices that move (s > 0) but on which the kernel vanishes.
double speed_floor(std::span<const double> a, std::span<const double> k,
                   std::span<const double> s) {
  double floor = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (s[i] > 0 && k[i] * s[i] == 0) floor = std::max(floor, std::abs(a[i]) * s[i]);
  }
  return floor;
}

double max_speed_at(double mu, std::span<const double> a, std::span<const double> k,
                    std::span<const double> s) {
  double speed = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (!(s[i] > 0)) continue;
    // k_i == 0 keeps μ = ±inf from producing inf * 0.
    const double alpha = k[i] == 0 ? a[i] : a[i] + mu * k[i];
    speed = std::max(speed, std::abs(alpha) * s[i]);
  }
  return speed;
}

// Root t* of φ(t) = e.lo - e.hi (convex, decreasing, piecewise linear: the minimax speed) and
// the largest μ admissible there, starting from a level t with φ(t) > 0. A Newton step from the
// left never overshoots a convex decreasing function; it lands where the two active lines meet,
// which is exact once they are the optimal pair. The active lines only move forward along their
// envelopes, so there are at most 2n steps; random data needs about ten.
double minimax_mu(double t, Envelope e, std::span<const double> a, std::span<const double> k,
                  std::span<const double> s) {
  const std::size_t max_steps = 2 * a.size() + 8;
  double mu = e.hi;
  for (std::size_t step = 0; step < max_steps; ++step) {
    const double dt = (e.lo - e.hi) / (e.lo_w + e.hi_w);
    mu = e.hi + e.hi_w * dt;  // where the two active lines meet
    const double t_next = t + dt;
    if (!(t_next > t)) break;  // converged to rounding
    const Envelope next = envelope_at(t_next, a, k, s);
    if (next.lo <= next.hi) return next.hi;  // t_next is t* up to rounding
    t = t_next;
    e = next;
  }
  return mu;
}

// The forward pass of AlphaSolver::solve: rotations c, s and y (in alpha_ln), for m equations.
struct Forward {
  bool in_range = true;  // false: a square left the range where the squared pass is exact
  bool full_rank = true;
  double min_pivot = 0;
};

// The recurrence d_{j+1} = c_j p_{j+1} with c_j = d_j / sqrt(d_j^2 + q_j^2) waits for a square
// root and a division per row. Here rho_j comes from D = d^2, whose recurrence
// D_{j+1} = p_{j+1}^2 D_j / (D_j + q_j^2) has one division on its path, and the square root of
// 1/rho_j^2 and the products c_j = d_j / rho_j, d_{j+1} = c_j p_{j+1} come off it. The two
// recurrences drift apart by rounding (like sqrt(n) ulps), so D restarts from d every 64 rows.
// Gives in_range = false where a square or a product of squares leaves the normal range while
// what it stands for is not zero, for forward_direct to do the work instead.
Forward forward_squared(std::span<const double> p, std::span<const double> q,
                        std::span<const double> r, std::span<double> y, double* c, double* s,
                        std::size_t m) {
  constexpr double kLow = 1e-290, kHigh = 1e290;
  Forward out;
  double inv_max = 0, inv_min = kInf;  // of 1/rho^2: at the smallest and the largest pivot
  bool zero_pivot = false;
  double d = p[0];
  double dd = d * d;
  double super = 0;  // R_{j-1,j}
  double y_prev = 0;
  for (std::size_t j = 0; j < m; ++j) {
    const double qj = q[j];
    const double next_p = j + 1 < m ? p[j + 1] : 0.0;
    const double rho2 = dd + qj * qj;
    // rho2 = 0 is a zero column only where d and q_j are zero (not a square underflowing).
    if (!(d == 0 || dd >= kLow) || !(rho2 <= kHigh) || (rho2 < kLow && (d != 0 || qj != 0))) {
      out.in_range = false;
      return out;
    }
    double cj = 1, sj = 0, yj = 0;
    if (rho2 > 0) {
      const double ahead = next_p * next_p * dd;  // beside the division: not on the path
      if (ahead < kLow && ahead != 0) {  // digits lost that the division would not give back
        out.in_range = false;
        return out;
      }
      const double inv = 1 / rho2;
      const double inv_rho = std::sqrt(inv);
      cj = d * inv_rho;
      sj = qj * inv_rho;
      yj = (-r[j] - super * y_prev) * inv_rho;
      dd = ahead * inv;
      inv_min = std::min(inv_min, inv);
      inv_max = std::max(inv_max, inv);
    } else {
      // Zero column: as in forward_direct.
      zero_pivot = true;
      dd = next_p * next_p;
    }
    d = cj * next_p;
    if ((j & 63) == 63) dd = d * d;
    c[j] = cj;
    s[j] = sj;
    y[j] = yj;
    y_prev = yj;
    super = sj * next_p;
  }
  out.full_rank = !zero_pivot;
  // rho_min / rho_max = sqrt(1/rho_max^2) / sqrt(1/rho_min^2) (the quotient of the squares
  // could underflow).
  out.min_pivot = zero_pivot || !(inv_max > 0) ? 0 : std::sqrt(inv_min) / std::sqrt(inv_max);
  return out;
}

// The forward pass with d itself: exact over the whole range of magnitudes.
Forward forward_direct(std::span<const double> p, std::span<const double> q,
                       std::span<const double> r, std::span<double> y, double* c, double* s,
                       std::size_t m) {
  Forward out;
  double rho_min = kInf;
  double rho_max = 0;
  double d = p[0];
  double super = 0;  // R_{j-1,j}
  double y_prev = 0;
  for (std::size_t j = 0; j < m; ++j) {
    const double rho = hypot_fast(d, q[j]);
    double cj = 1;
    double sj = 0;
    double yj = 0;
    if (rho > 0) {
      cj = d / rho;
      sj = q[j] / rho;
      yj = (-r[j] - super * y_prev) / rho;
    } else {
      // Zero column: the identity keeps Q orthogonal and M Q e_n = 0; y_j = 0 leaves equation j
      // unsatisfied and all others exact.
      out.full_rank = false;
    }
    if (rho < rho_min) rho_min = rho;
    if (rho > rho_max) rho_max = rho;
    c[j] = cj;
    s[j] = sj;
    y[j] = yj;
    y_prev = yj;
    if (j + 1 < m) {
      super = sj * p[j + 1];
      d = cj * p[j + 1];
    }
  }
  out.min_pivot = rho_max > 0 ? rho_min / rho_max : 0;
  return out;
}

}  // namespace

AlphaSolver::Result AlphaSolver::solve(std::span<const double> p, std::span<const double> q,
                                       std::span<const double> r, std::span<double> alpha_ln,
                                       std::span<double> kernel) {
  const std::size_t n = kernel.size();
  const std::size_t m = n > 0 ? n - 1 : 0;  // number of equations
  if (alpha_ln.size() != n || p.size() != m || q.size() != m || r.size() != m) {
    throw std::invalid_argument(
        "AlphaSolver::solve: p, q, r need n-1 entries and alpha_ln, kernel n entries");
  }
  Result result;
  if (n < 2) {
    if (n == 1) {  // M is empty: the kernel is all of R^1
      alpha_ln[0] = 0;
      kernel[0] = 1;
    }
    return result;
  }
  if (c_.size() < m) {
    c_.resize(m);
    s_.resize(m);
  }
  double* const c = c_.data();
  double* const s = s_.data();

  // Rotation j acts on rows j, j+1 of M^T and zeroes q_j against the running diagonal d. It leaves
  // rho_j on the diagonal of R, s_j p_{j+1} on its superdiagonal and c_j p_{j+1} as the next d.
  // The forward substitution R^T y = -r needs only these, so it runs in the same pass; y is kept
  // in alpha_ln until the rotations are applied.
  const Forward squared = forward_squared(p, q, r, alpha_ln, c, s, m);
  const Forward used = squared.in_range ? squared : forward_direct(p, q, r, alpha_ln, c, s, m);

  // Q = G_0^T ... G_{m-1}^T applied to [y; 0] and to e_n; entry j+1 is final once rotation j has
  // been applied, so the orientation counts are taken on the way.
  // Entry j of both vectors is carried to the next rotation in a register (a1, k1): read back
  // from memory, each rotation waited for the store before it.
  double a1 = 0, k1 = 1;  // entries m of [y; 0] and of e_n
  std::size_t positive = 0;
  std::size_t negative = 0;
  double sum = 0;
  for (std::size_t j = m; j-- > 0;) {
    const double cj = c[j];
    const double sj = s[j];
    const double a0 = alpha_ln[j];
    alpha_ln[j + 1] = sj * a0 + cj * a1;
    a1 = cj * a0 - sj * a1;
    const double k_final = cj * k1;
    kernel[j + 1] = k_final;
    k1 = -sj * k1;
    positive += k_final > 0;
    negative += k_final < 0;
    sum += k_final;
  }
  alpha_ln[0] = a1;
  kernel[0] = k1;
  positive += k1 > 0;
  negative += k1 < 0;
  sum += k1;
  // More positive than negative entries (without zero entries: at least half positive); a tie
  // goes to the orientation with positive sum.
  if (negative > positive || (negative == positive && sum < 0)) {
    for (std::size_t i = 0; i < n; ++i) kernel[i] = -kernel[i];
  }

  result.ok = used.full_rank;
  result.min_pivot = used.min_pivot;
  return result;
}

DampingChoice choose_damping_mu(std::span<const double> alpha_ln, std::span<const double> kernel,
                                std::span<const double> speed, double speed_limit) {
  if (kernel.size() != alpha_ln.size() || speed.size() != alpha_ln.size()) {
    throw std::invalid_argument("choose_damping_mu: alpha_ln, kernel and speed differ in size");
  }
  if (!(speed_limit > 0)) {
    throw std::invalid_argument("choose_damping_mu: speed_limit must be positive");
  }
  const double floor = speed_floor(alpha_ln, kernel, speed);
  const double level = std::max(speed_limit, floor);
  const Envelope e = envelope_at(level, alpha_ln, kernel, speed);
  DampingChoice choice;
  if (e.lo <= e.hi) {
    choice.mu = e.hi;
    choice.feasible = floor <= speed_limit;
  } else {
    choice.mu = minimax_mu(level, e, alpha_ln, kernel, speed);
  }
  choice.max_speed = max_speed_at(choice.mu, alpha_ln, kernel, speed);
  return choice;
}

}  // namespace orthofront
