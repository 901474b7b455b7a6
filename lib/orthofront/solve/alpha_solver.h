#pragma once
/// The α system of a front line: p_i α_i + q_i α_{i+1} = -r_i, i = 0..n-2 (n unknowns).
#include <span>
#include <vector>

namespace orthofront {

/// Least-norm solution and kernel of the (n-1) x n bidiagonal system M α = -r, where row i of M
/// holds p_i at column i and q_i at column i+1.
///
/// Method: n-1 Givens rotations factor M^T = Q R (R bidiagonal, never forming Q); the kernel is
/// k = Q e_n and the least-norm solution α^L = Q [y; 0] with R_[n-1]^T y = -r. O(n) time; the
/// object keeps its workspace, so repeated calls with n not larger than before do not allocate.
class AlphaSolver {
 public:
  struct Result {
    bool ok = false;       ///< false when n < 2 or R has a zero pivot (rank < n-1)
    double min_pivot = 0;  ///< smallest |R_ii| relative to the largest (conditioning hint)
  };

  /// p, q, r: n-1 entries each. alpha_ln, kernel: n entries each (outputs). Throws
  /// std::invalid_argument when the sizes disagree.
  /// kernel has unit length and is oriented towards more positive than negative entries (k^+;
  /// without zero entries: at least half positive), a tie going to a positive sum.
  /// Rank deficiency (a zero pivot, e.g. a row with p_i = q_i = 0) gives ok = false, yet the
  /// outputs stay usable: kernel is still a unit vector with M k = 0 (one of several), and
  /// alpha_ln satisfies every equation except those at zero pivots. n = 1 gives ok = false,
  /// alpha_ln = {0}, kernel = {1}.
  Result solve(std::span<const double> p, std::span<const double> q, std::span<const double> r,
               std::span<double> alpha_ln, std::span<double> kernel);

 private:
  std::vector<double> c_, s_;  // rotation j: cosine and sine; grown, never shrunk
};

/// μ for the unit-invariant damping mode.
struct DampingChoice {
  double mu = 0;          ///< chosen μ
  bool feasible = false;  ///< true when some μ keeps max_i |α_i| |v_i| <= speed_limit
  double max_speed = 0;   ///< max_i |α^L_i + μ k_i| |v_i| at the chosen μ
};

/// Chooses μ in α = α^L + μ k such that max_i |α^L_i + μ k_i| speed_i <= speed_limit.
/// The admissible μ form an interval (intersection of one interval per vertex, found in O(n));
/// the largest admissible μ is returned (most advance along k^+, so the fastest vertex moves by
/// exactly speed_limit * h*). When the interval is empty, returns the μ minimising the maximum
/// speed (convex, piecewise linear; the largest such μ if several), with feasible = false, after
/// a few more O(n) passes (Newton steps on the minimax speed: at most 2n, about ten on random
/// data). Vertices with speed 0 are ignored. mu is +infinity when nothing bounds it from above
/// (k_i = 0 on every vertex with speed > 0). Allocates nothing; throws std::invalid_argument when
/// the sizes disagree or speed_limit <= 0.
DampingChoice choose_damping_mu(std::span<const double> alpha_ln, std::span<const double> kernel,
                                std::span<const double> speed, double speed_limit);

}  // namespace orthofront
