#pragma once
/// Adapt (paper §5): merge short front segments, split long ones with vertices on their true
/// stream lines (insertion), and cut segments that no stream line can fill.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "orthofront/engine/front.h"
#include "orthofront/engine/options.h"
#include "orthofront/engine/report.h"
#include "orthofront/engine/seed_shot_legs.h"
#include "orthofront/field/field.h"
#include "orthofront/integrate/runge_kutta.h"
#include "orthofront/mesh/mesh.h"
#include "orthofront/seed/seed.h"

namespace orthofront {

/// Seed shots missing in a row beside a segment before its insertions start from the previous
/// row (FrontVertex::seed_misses). Lorenz: every shot after the first few misses; abc: isolated
/// misses, where starting from the row after the first gave twice the fallbacks.
inline constexpr std::uint8_t kSeedMissesBeforeRowFirst = 3;

template <int N>
class FrontAdapter {
 public:
  /// Inserted vertices become mesh vertices of `mesh`; counts go to `report`. `stop` is handed
  /// to the insertions' integrations. All are owned by the engine and outlive this.
  FrontAdapter(const Field<N>& field, const Seed<N>& seed, const StreamSurfaceOptions& options,
               const Tolerance& tolerance, const StopRequest& stop, Mesh& mesh,
               SurfaceReport& report);

  /// Merges segments shorter than merge_factor·ℓ into their neighbours (not where that would
  /// stitch faces of old mesh vertices only; see the body).
  void merge_short(Front<N>& f);

  /// Splits segments longer than split_factor·ℓ with vertices on the stream lines of seed
  /// parameters between those of their ends. Where the seed parameter cannot tell those stream
  /// lines apart any more (some of them would start from the seed point of an end or of another
  /// insertion on the segment, or the segment runs along one stream line: along_one_stream_line),
  /// the segment is cut instead: cut[k] != 0 after vertex k of the
  /// returned front (split_front's convention); returns whether any segment was cut.
  ///
  /// Near a separating stream line, neighbouring stream lines diverge exponentially and
  /// insertions halve the seed interval between front vertices every step or so, until it is
  /// below the resolution of a double (abc: about 23 steps). Vertices inserted after that share
  /// the seed parameter and so the stream line of an end: the front runs along that one stream
  /// line, and every vertex inserted there stays on it, moving only along it. The front then
  /// grows a fold of zero width that stitch fills with zero-area faces (with α < 0 kept it settles
  /// into a cycle that emits new mesh vertices exactly on the previous step's), and with a mesh
  /// vertex every few 1e-6 along the stream line (T-junctions). No surface lies between such
  /// ends: the surface tears there, as at a rip.
  bool split_long(Front<N>& f, const Front<N>* old, int step, std::vector<char>& cut);

  /// Starts the first legs of the seed shots that the next step's split_long will likely make
  /// on `f` (linked this step; `old` is the front it advanced from): on segments whose ends
  /// came from neighbours and that grow past split_factor·ℓ at this step's rate. See
  /// seed_shot_legs.h; a guess that does not come true costs an idle thread only.
  void start_likely_shots(const Front<N>& f, const Front<N>& old);

  /// A new front step (for the legs started ahead), and the surface's end (legs not begun are
  /// dropped).
  void begin_step() { legs_.begin_step(); }
  void finish() { legs_.drop_pending(); }

  /// Seed-shot legs started ahead, and those split_long used.
  std::size_t legs_started_ahead() const { return legs_.started(); }
  std::size_t legs_used_ahead() const { return legs_.used(); }

 private:
  /// A vertex to insert at fraction λ of segment i, and where it went.
  struct InsertionJob {
    std::size_t segment = 0;
    double lambda = 0, s = 0, t = 0;
    Vec<N> x = Vec<N>::Zero();
    int evaluations = 0;
    enum class Outcome : unsigned char {
      seed,
      streamline,
      previous_row,
      fallback,
      interpolated
    } outcome{};
    bool left_domain = false;  ///< a fallback whose stream line left the domain or met no data
    bool interrupted = false;  ///< a stop request ended its integration (counted as no fallback)
    bool seed_shot_hit = false;      ///< its stream line from the seed met the front
    bool seed_shot_missed = false;   ///< its stream line from the seed missed the front
    bool seed_shot_skipped = false;  ///< started from the previous row after an earlier miss
    bool over_budget = false;  ///< started from the previous row: a shot would cost too much
    double exhausted_leg = 0;  ///< > 0: its leg of this length ran out of evaluations
  };

  /// Whether segment (i, j) runs along one stream line: its ends' seed parameters (the end's
  /// `s_next` wrapped on a closed front) are a few rounding steps apart and it is not across
  /// the flow. A vertex inserted there, from the seed or from the previous row, lands on the
  /// same line (zero-area faces).
  bool along_one_stream_line(const Front<N>& f, std::size_t i, std::size_t j,
                             double s_next) const;

  /// The α of the mesh vertex a front vertex stands for (0 for none).
  double alpha_or_zero(const FrontVertex<N>& fv) const;

  /// Follows the stream line from `start` for `duration`, then moves it along itself onto the
  /// front: the plane through the cubic guess normal to the flow. On success (inside, within a
  /// quarter segment of the guess) sets job.x and job.t; `status` tells why it failed otherwise.
  bool shoot(const Front<N>& f, std::size_t i, std::size_t j, const Vec<N>& guess,
             const Vec<N>& start, double duration, InsertionJob& job, FieldStatus& status) const;

  /// Fills job.x (and job.t when the point is put on its true stream line). Thread-safe.
  void insertion_point(const Front<N>& f, const Front<N>* old, InsertionJob& job) const;

  const Field<N>& field_;
  const Seed<N>& seed_;
  const StreamSurfaceOptions& opt_;
  const Tolerance& tol_;
  const StopRequest& stop_;
  Mesh& mesh_;
  SurfaceReport& report_;
  SeedShotLegs<N> legs_;
  std::vector<InsertionJob> jobs_;  ///< scratch, reused between fronts and steps
  std::vector<std::pair<double, double>> likely_legs_;  ///< scratch of start_likely_shots
};

extern template class FrontAdapter<3>;
extern template class FrontAdapter<4>;

}  // namespace orthofront
