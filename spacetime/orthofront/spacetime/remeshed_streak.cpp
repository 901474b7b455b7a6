#include "orthofront/spacetime/remeshed_streak.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>
#include <unordered_map>
#include <vector>

#include "orthofront/error.h"
#include "orthofront/field/field_spec.h"
#include "orthofront/mesh/triangle_topology.h"
#include "orthofront/stage_timer.h"

namespace orthofront::spacetime {

namespace {

using Clock = std::chrono::steady_clock;
using Topology = TriangleTopology;
constexpr std::int32_t none = Topology::none;

std::string number(double value) { return format_parameter(value); }

std::size_t idx(std::int32_t i) { return static_cast<std::size_t>(i); }


// Interior angle at p of the triangle (p, q, r).
double angle_at(const Vec3& p, const Vec3& q, const Vec3& r) {
  const Vec3 a = q - p, b = r - p;
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

class RemeshedStreakBuilder {
 public:
  RemeshedStreakBuilder(const StreakFlowAccess& access, const SeedCurve& seed,
                        const StreakOptions& options, const StreakFrameSink& sink)
      : access_(access), flow_(access.flow), seed_(seed), o_(options), sink_(sink),
        integrated_(access.flow, options.tolerance),
        map_(access.map ? *access.map : integrated_), two_d_(access.flow.dimension() == 2) {}

  StreakReport run();

 private:
  struct Split {
    std::int32_t face = none;
    int edge = 0;
    double length = 0;
  };

  std::string field_name() const {
    return o_.field_name.empty() ? flow_.describe() : o_.field_name;
  }
  Vec3 seed_point(double s) const {
    Vec3 p = seed_.point(s);
    if (two_d_) p.z() = 0;
    return p;
  }
  std::int32_t add_particle(const Vec3& x, double s, double tau, ParticleStatus status) {
    const std::int32_t v = topo_.add_vertex();
    x_.push_back(x);
    previous_x_.push_back(x);
    s_.push_back(s);
    tau_.push_back(tau);
    status_.push_back(status);
    id_.push_back(next_id_++);
    on_chain_.push_back(0);
    label_exact_.push_back(1);
    return v;
  }
  bool alive(std::int32_t v) const { return status_[idx(v)] == ParticleStatus::moving; }
  // The target edge length of a part whose youngest particle was released at tau: ℓ, or longer
  // where the part is older than the coarsening age (exactly ℓ while there is none).
  double edge_for(double tau, double coarsen_age) const {
    return o_.edge * std::max(1.0, (t_ - tau) / coarsen_age);
  }
  double edge_for(double tau) const { return edge_for(tau, coarsen_age_); }
  double edge_at(std::int32_t a, std::int32_t b) const {
    return edge_for(std::max(tau_[idx(a)], tau_[idx(b)]));
  }
  double face_edge(std::int32_t f) const {
    const auto& c = topo_.face(f);
    return edge_for(std::max({tau_[idx(c[0])], tau_[idx(c[1])], tau_[idx(c[2])]}));
  }
  double width_at(std::int32_t f) const { return o_.prune * face_edge(f); }
  bool in_region(const Vec3& x) const {
    if (!o_.region) return true;
    const Box<3>& b = *o_.region;
    const bool xy = x.x() >= b.lo.x() && x.x() <= b.hi.x() && x.y() >= b.lo.y() && x.y() <= b.hi.y();
    return xy && (two_d_ || (x.z() >= b.lo.z() && x.z() <= b.hi.z()));
  }
  // A moving particle outside the region of interest stops there (as at the domain's edge).
  void crop(const Vec3& x, ParticleStatus& status, char& cropped) const {
    cropped = status == ParticleStatus::moving && !in_region(x) ? 1 : 0;
    if (cropped) status = ParticleStatus::left_domain;
  }
  std::size_t count_particles() const;
  // Over the vertex budget: lowers the coarsening age so the surface needs about 70 % of it
  // (estimated from its faces' areas and ages), and collapses until it fits.
  void keep_budget(std::size_t particles);
  // An area (of a face) or a length (of a boundary edge), and the release time of its youngest
  // particle.
  struct AgedSize {
    double size, tau;
  };
  double estimate_particles(double coarsen_age, const std::vector<AgedSize>& faces,
                            const std::vector<AgedSize>& boundary) const;
  // Signed double area of (a, b, c) along the surface's orientation (2D) or its normal (3D).
  Vec3 normal(std::int32_t a, std::int32_t b, std::int32_t c) const {
    return (x_[idx(b)] - x_[idx(a)]).cross(x_[idx(c)] - x_[idx(a)]);
  }
  Vec3 normal_with(std::int32_t a, std::int32_t b, std::int32_t c, std::int32_t u,
                   std::int32_t w) const {
    const auto at = [&](std::int32_t v) -> const Vec3& { return x_[idx(v == u ? w : v)]; };
    return (at(b) - at(a)).cross(at(c) - at(a));
  }

  void release(double tau);
  enum class Move { done, retry, failed };
  // Moves every particle from t_ to t_to; retry (nothing changed) where a face would turn over
  // and may_retry; failed on a read error.
  Move advance(double t_to, bool may_retry);
  // Moves to t_to in steps that keep every face on its side, adapting the mesh between them.
  bool advance_to(double t_to);
  bool adapt(bool full = true);
  // Every edge (once) whose length `keep` accepts.
  template <class Keep>
  std::vector<Split> edges_where(const Keep& keep) const;
  // The same list for the edges of the faces around `near` only: in the order edges_where() would
  // give them, each named by the face edges_where() names it by.
  template <class Keep>
  std::vector<Split> edges_near(const std::vector<std::int32_t>& near, const Keep& keep);
  std::vector<std::int32_t> near_faces_;  // edges_near()'s scratch
  std::vector<char> near_mark_;
  // Splits the long edges; near_reshaped: only those around near_ (see there).
  bool split_pass(std::size_t& splits, bool near_reshaped);
  // The last split pass's new particles and the corners of the faces flipped after it.
  std::vector<std::int32_t> near_, flipped_;
  // v's label (s, τ), s taken across s = 0 of a closed seed to lie within ½ of near_s.
  Eigen::Vector2d label_near(std::int32_t v, double near_s) const {
    double sv = s_[idx(v)];
    if (seed_.closed() && sv - near_s > 0.5) sv -= 1;
    if (seed_.closed() && near_s - sv > 0.5) sv += 1;
    return Eigen::Vector2d(sv, tau_[idx(v)]);
  }
  // Signed area of f's labels (s, τ), in its corners' order.
  double label_area(std::int32_t f) const;
  // Whether a face beside the edge has its labels turned against its corners, which an
  // untangled mesh never has (all label triangles turn one way): collapses and flips in a
  // mixing flow join particles whose labels lie far apart, and the path of their label
  // midpoint goes elsewhere. Such an edge's particle is placed by interpolation at once.
  bool labels_tangled(const Split& edge) const;
  // How far the surface is estimated to depart from the chord of edge e of f at its midpoint:
  // k·L² / 8 with k the surface's largest curvature around the edge, and on the dye's boundary
  // also L·turn / 8 from the boundary curve's turn over the edge (a circle of radius R gives
  // L² / 8R either way). Infinity where an end's fan does not hold the edge (a vertex where two
  // sheets touch).
  // On the dye's boundary, also gives the boundary's next vertex past each end in `beyond`
  // (none elsewhere).
  double chord_departure(std::int32_t f, int e, std::vector<Topology::HalfEdge>& ring,
                         std::array<std::int32_t, 2>& beyond) const;
  // Where a boundary edge's new particle goes by the cubic through the edge's ends and the
  // boundary vertices beyond them: in the label that varies along a boundary that is a streak
  // line (one s) or a time line (one τ), which puts the label midpoint where its path goes, and
  // elsewhere (a boundary cut by pruning, a stop, the region) by length along the boundary.
  // False where the cubic departs from either quadratic through three of the points (which
  // bounds its error) by more than `tolerance`: curved boundaries the chord cannot follow are
  // mostly smooth at the scale of ℓ, and these need no integration.
  bool boundary_cubic(std::int32_t a, std::int32_t b, const std::array<std::int32_t, 2>& beyond,
                      double tolerance, Vec3& at) const;
  // Exact particles of a split land where the path of their label midpoint goes, which in a
  // sheared parametrization can lie well off the edge (and fold the faces beside it). One
  // chord step of Gauss-Newton on the label, with the derivative of the faces beside the edge,
  // moves those farther than ℓ/20 from the edge's midpoint toward the particle whose path passes
  // through it (along the edge's labels for a boundary edge, which keeps it on the boundary).
  // Returns whether there was no read error.
  bool steer_to_midpoints(const std::vector<Split>& chosen, const std::vector<std::size_t>& which,
                          std::vector<Vec3>& x, std::vector<ParticleStatus>& status,
                          std::vector<double>& ms, std::vector<double>& mtau);
  void collapse_pass();
  std::size_t flip_pass();  // returns the flips made
  void flip_around_reshaped();
  // The cosine of the smallest angle of (a, b, c) with a at xa: the largest of its corners'
  // cosines, which orders triangles by their smallest angle (reversed) without trigonometry.
  double smallest_angle_cosine(std::int32_t a, std::int32_t b, std::int32_t c,
                               const Vec3& xa) const;
  void smooth_pass();
  // face_flags_[f] = flag(f, scratch ring) for every live face, in parallel.
  template <class Flag>
  void flag_faces(const Flag& flag);
  // How wide the filament is at face f, or infinity where f is not on one: f has a boundary
  // edge, every corner on the boundary and none on the newest row (the youngest strip is thin
  // where the flow is slow).
  double filament_width(std::int32_t f, std::vector<Topology::HalfEdge>& ring) const;
  bool wants_flip(std::int32_t f, int e) const;
  void prune(std::int32_t f);
  void prune_pass();
  bool collapsible(std::int32_t u, std::int32_t w) const;
  void stop_particle(std::int32_t v, bool cropped = false);
  void compact();
  void emit_frame(int index);
  void stop(const std::string& why) {
    report_.complete = false;
    if (report_.message.empty()) report_.message = why;
  }
  bool no_error(const std::string& error) {
    if (error.empty()) return true;
    stop("stopped at t = " + number(t_) + ": " + error);
    return false;
  }

  const StreakFlowAccess& access_;
  const UnsteadyField& flow_;
  const SeedCurve& seed_;
  const StreakOptions& o_;
  const StreakFrameSink& sink_;
  IntegratedFlowMap integrated_;
  const FlowMap& map_;
  const bool two_d_;
  double label_sign_ = 0;   // the sign of every label triangle's area while labels are untangled

  Topology topo_;
  std::vector<Vec3> x_, previous_x_;  // positions now and at the previous break
  std::vector<double> s_, tau_;
  std::vector<ParticleStatus> status_;
  std::vector<std::int32_t> id_;
  std::vector<char> on_chain_;
  std::vector<char> label_exact_;  // the particle lies on its label's path (it was not interpolated)
  std::vector<Topology::HalfEdge> ring_;  // scratch for fans
  mutable std::vector<Topology::HalfEdge> collapse_ring_;  // collapsible()'s
  // Scratch of the sweeps: a per-face-slot flag computed in parallel, and what a sweep changed.
  std::vector<std::uint8_t> face_flags_;
  std::vector<char> changed_faces_, changed_vertices_;
  std::vector<std::int32_t> reshaped_;  // vertices whose fans splits and collapses changed
  // Edges (by their particles' ids) whose collapse was refused, and the pass to try again at.
  std::unordered_map<std::uint64_t, std::size_t> refused_;
  std::size_t collapse_passes_ = 0;
  std::uint64_t edge_key(std::int32_t a, std::int32_t b) const {
    const auto ia = static_cast<std::uint64_t>(id_[idx(a)]), ib = static_cast<std::uint64_t>(id_[idx(b)]);
    return std::min(ia, ib) << 32 | std::max(ia, ib);
  }
  std::vector<std::array<std::int32_t, 3>> removed_;  // scratch: corners of removed faces
  std::vector<std::int32_t> chain_;  // the newest row, by s: the next strip's first side
  std::int32_t next_id_ = 0;
  double t_ = 0, previous_t_ = 0;
  double step_ = 0, step_now_ = 0;  // the release step; the next move's (shortened) step
  double coarsen_age_ = std::numeric_limits<double>::infinity();  // past it ℓ grows with age
  double last_move_ = 0;            // the farthest a particle went in the last move
  StreakReport report_;
  Clock::time_point start_;
};

void RemeshedStreakBuilder::release(double tau) {
  std::vector<double> params;
  if (chain_.empty()) {
    const int n = o_.seed_count > 0
                      ? o_.seed_count
                      : std::max(2, static_cast<int>(std::ceil(seed_.length() / o_.edge)) + 1);
    params = seed_.sample(n);
  } else {
    for (const std::int32_t v : chain_) params.push_back(s_[idx(v)]);
  }
  std::vector<std::int32_t> row;
  row.reserve(params.size());
  for (const double s : params) {
    const Vec3 x = seed_point(s);
    Vec3 v;
    const FieldStatus st = flow_.velocity(x, tau, v);
    ParticleStatus status = st == FieldStatus::inside    ? ParticleStatus::moving
                            : st == FieldStatus::outside ? ParticleStatus::left_domain
                                                         : ParticleStatus::no_data;
    char cropped = 0;
    crop(x, status, cropped);
    row.push_back(add_particle(x, s, tau, status));
    report_.left_region += cropped ? 1 : 0;
  }
  ++report_.rows_released;
  if (!chain_.empty()) {
    const std::size_t n = chain_.size() - (seed_.closed() ? 0 : 1);
    using Corners = std::array<std::int32_t, 3>;
    // In 2D each quad turns the way its own flow crosses the seed: where the flow crosses it
    // both ways, the dye on either side is a sheet of its own, both face up (one orientation
    // for all would lay one of them face down, folded against the other along the streak line
    // from the point where the flow runs along the seed). The two meet only at that line.
    bool reverse = false;
    const auto oriented_face = [&](Corners f) {
      if (reverse) std::swap(f[1], f[2]);
      return f;
    };
    const auto addable = [&](const Corners& f) {
      if (!alive(f[0]) || !alive(f[1]) || !alive(f[2])) return false;
      return topo_.can_add_face(f[0], f[1], f[2]);
    };
    // The quad c0, c1, r1, r0, cut along its shorter diagonal. Its two faces go in the order
    // that joins the mesh along an edge (a face that met the mesh at a corner only would make
    // two fans meet there).
    const auto add_quad = [&](Corners first, Corners second) {
      // A quad twisted across the seed (its flow turns within it): no face turns both ways.
      const Vec3 turn_first = normal(first[0], first[1], first[2]);
      if (!(turn_first.dot(normal(second[0], second[1], second[2])) > 0)) {
        report_.strip_faces_skipped += 2;
        return;
      }
      if (two_d_) reverse = turn_first.z() < 0;
      first = oriented_face(first);
      second = oriented_face(second);
      if (addable(first)) {
        const std::int32_t f = topo_.add_face(first[0], first[1], first[2]);
        if (label_sign_ == 0) label_sign_ = label_area(f) > 0 ? 1 : -1;
        if (addable(second))
          topo_.add_face(second[0], second[1], second[2]);
        else
          ++report_.strip_faces_skipped;
      } else if (addable(second)) {
        topo_.add_face(second[0], second[1], second[2]);
        if (addable(first))
          topo_.add_face(first[0], first[1], first[2]);
        else
          ++report_.strip_faces_skipped;
      } else {
        report_.strip_faces_skipped += 2;
      }
    };
    // In 3D there is no up to turn a quad by: where the flow crosses the seed the other way
    // than beside it (the quad's normal turns over from its neighbour's), the quad is left
    // out, so the dye on either side is a sheet of its own rather than one folded flat.
    Vec3 beside = Vec3::Zero();
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t j = (i + 1) % chain_.size();
      const std::int32_t c0 = chain_[i], c1 = chain_[j], r0 = row[i], r1 = row[j];
      if (!two_d_) {
        const Vec3 across = normal(c0, c1, r1) + normal(c0, r1, r0);
        const bool turned = across.dot(beside) < 0;
        beside = across;
        if (turned) {
          report_.strip_faces_skipped += 2;
          continue;
        }
      }
      if ((x_[idx(c0)] - x_[idx(r1)]).squaredNorm() <= (x_[idx(c1)] - x_[idx(r0)]).squaredNorm())
        add_quad({c0, r1, r0}, {c0, c1, r1});
      else
        add_quad({c0, c1, r0}, {c1, r1, r0});
    }
  }
  for (const std::int32_t v : chain_) on_chain_[idx(v)] = 0;
  chain_ = std::move(row);
  for (const std::int32_t v : chain_) on_chain_[idx(v)] = 1;
}

void RemeshedStreakBuilder::stop_particle(std::int32_t v, bool cropped) {
  if (cropped)
    ++report_.left_region;
  else if (status_[idx(v)] == ParticleStatus::left_domain)
    ++report_.left_domain;
  if (status_[idx(v)] == ParticleStatus::no_data) ++report_.no_data;
  report_.faces_removed_at_stops += topo_.remove_faces_of(v);
}

RemeshedStreakBuilder::Move RemeshedStreakBuilder::advance(double t_to, bool may_retry) {
  const auto start = Clock::now();
  std::vector<std::int32_t> moving;
  for (std::size_t v = 0; v < x_.size(); ++v) {
    const auto i = static_cast<std::int32_t>(v);
    if (alive(i) && (topo_.has_faces(i) || on_chain_[v])) moving.push_back(i);
  }
  std::vector<Vec3> x(moving.size());
  std::vector<double> from(moving.size(), t_);
  std::vector<ParticleStatus> status(moving.size());
  for (std::size_t k = 0; k < moving.size(); ++k) x[k] = x_[idx(moving[k])];
  if (access_.prepare && !no_error(access_.prepare(t_, t_to))) return Move::failed;
  report_.evaluations += map_.advect_all(x, from, t_to, status);
  if (access_.read_error && !no_error(access_.read_error())) return Move::failed;
  std::vector<char> cropped(moving.size(), 0);
  if (o_.region)
    for (std::size_t k = 0; k < moving.size(); ++k) crop(x[k], status[k], cropped[k]);
  report_.particle_steps += moving.size();
  report_.particle_time += static_cast<double>(moving.size()) * (t_to - t_);
  // A face that turns over during the move (its particles crossed) would fold the surface: the
  // move is taken back and made in shorter steps, with the mesh adapted between them.
  std::vector<Vec3> moved = x_;
  for (std::size_t k = 0; k < moving.size(); ++k) moved[idx(moving[k])] = x[k];
  std::vector<char> stopped(x_.size(), 0);
  for (std::size_t k = 0; k < moving.size(); ++k)
    stopped[idx(moving[k])] = status[k] != ParticleStatus::moving ? 1 : 0;
  double largest_move = 0;
  for (std::size_t k = 0; k < moving.size(); ++k)
    if (status[k] == ParticleStatus::moving)
      largest_move = std::max(largest_move, (x[k] - x_[idx(moving[k])]).norm());
  last_move_ = largest_move;
  // Faces of thin filaments that turn over are pruned (they would be anyway); any other face
  // that turns makes the move shorter.
  std::size_t turned = 0;
  std::vector<std::int32_t> turned_filament;
  for (std::size_t f = 0; f < topo_.face_slots(); ++f) {
    const auto fi = static_cast<std::int32_t>(f);
    if (!topo_.face_alive(fi)) continue;
    const auto& c = topo_.face(fi);
    if (stopped[idx(c[0])] || stopped[idx(c[1])] || stopped[idx(c[2])]) continue;
    const Vec3 before = normal(c[0], c[1], c[2]);
    const Vec3 after = (moved[idx(c[1])] - moved[idx(c[0])]).cross(moved[idx(c[2])] - moved[idx(c[0])]);
    if (after.dot(before) > 0) continue;
    if (filament_width(fi, ring_) < width_at(fi))
      turned_filament.push_back(fi);
    else
      ++turned;
  }
  if (turned > 0 && may_retry) {
    report_.advect_seconds += seconds_since(start);
    return Move::retry;
  }
  changed_vertices_.assign(x_.size(), 0);
  for (const std::int32_t f : turned_filament)
    if (topo_.face_alive(f)) prune(f);
  report_.faces_turned += turned;
  for (std::size_t k = 0; k < moving.size(); ++k) {
    const std::size_t v = idx(moving[k]);
    previous_x_[v] = x_[v];
    x_[v] = x[k];
    status_[v] = status[k];
  }
  for (std::size_t k = 0; k < moving.size(); ++k)
    if (status[k] != ParticleStatus::moving) stop_particle(moving[k], cropped[k] != 0);
  ++report_.intervals;
  previous_t_ = t_;
  t_ = t_to;
  report_.advect_seconds += seconds_since(start);
  return Move::done;
}

bool RemeshedStreakBuilder::advance_to(double t_to) {
  // Steps of at most the release step, shortened where particles move further than about ℓ or
  // a face would turn over; at most 1/64 of the release step (then a turned face is counted).
  while (t_ < t_to) {
    double dt = std::min(t_to - t_, step_now_);
    if (t_to - t_ - dt < 1e-9 * step_) dt = t_to - t_;
    const bool may_retry = dt > step_ / 64;
    const Move m = advance(t_ + dt, may_retry);
    if (m == Move::failed) return false;
    if (m == Move::retry) {
      step_now_ = 0.5 * dt;
      ++report_.steps_shortened;
      continue;
    }
    if (t_ < t_to && !adapt(false)) return false;
    // The next step: as long as its particles move about ℓ, never longer than the release step.
    const double grow = last_move_ > 0 ? o_.edge / last_move_ : 2.0;
    step_now_ = std::min(step_, dt * std::clamp(grow, 0.5, 2.0));
  }
  return true;
}

template <class Keep>
std::vector<RemeshedStreakBuilder::Split> RemeshedStreakBuilder::edges_where(const Keep& keep) const {
  // Chunks of faces are measured in parallel and joined in face order: the list (and so every
  // pass that sorts it stably) is the one a single sweep makes.
  constexpr std::size_t chunk = 2048;
  const std::size_t slots = topo_.face_slots();
  std::vector<std::vector<Split>> parts((slots + chunk - 1) / chunk);
  tbb::parallel_for(std::size_t{0}, parts.size(), [&](std::size_t part) {
    for (std::size_t f = part * chunk; f < std::min(slots, (part + 1) * chunk); ++f) {
      const auto fi = static_cast<std::int32_t>(f);
      if (!topo_.face_alive(fi)) continue;
      const auto& c = topo_.face(fi);
      for (int e = 0; e < 3; ++e) {
        const std::int32_t g = topo_.neighbor(fi, e);
        if (g != none && g < fi) continue;  // each edge once
        const std::int32_t a = c[e], b = c[(e + 1) % 3];
        const double length = (x_[idx(a)] - x_[idx(b)]).norm();
        if (keep(length, a, b)) parts[part].push_back({fi, e, length});
      }
    }
  });
  std::vector<Split> edges;
  for (const auto& part : parts) edges.insert(edges.end(), part.begin(), part.end());
  return edges;
}

template <class Keep>
std::vector<RemeshedStreakBuilder::Split> RemeshedStreakBuilder::edges_near(
    const std::vector<std::int32_t>& near, const Keep& keep) {
  near_mark_.resize(topo_.face_slots(), 0);
  near_faces_.clear();
  for (const std::int32_t v : near) {
    topo_.fan(v, ring_);
    for (const Topology::HalfEdge& h : ring_)
      if (!near_mark_[idx(h.face)]) {
        near_mark_[idx(h.face)] = 1;
        near_faces_.push_back(h.face);
      }
  }
  std::vector<Split> edges;
  for (const std::int32_t f : near_faces_) {
    const auto& c = topo_.face(f);
    for (int e = 0; e < 3; ++e) {
      std::int32_t g = topo_.neighbor(f, e);
      if (g != none && g < f && near_mark_[idx(g)]) continue;  // g names it
      const std::int32_t a = c[e], b = c[(e + 1) % 3];
      const double length = (x_[idx(a)] - x_[idx(b)]).norm();
      if (!keep(length, a, b)) continue;
      if (g != none && g < f) {  // named by g, as in a sweep in face order
        int ge = 0;
        while (topo_.neighbor(g, ge) != f) ++ge;
        edges.push_back({g, ge, length});
      } else {
        edges.push_back({f, e, length});
      }
    }
  }
  for (const std::int32_t f : near_faces_) near_mark_[idx(f)] = 0;
  std::sort(edges.begin(), edges.end(), [](const Split& p, const Split& q) {
    return p.face != q.face ? p.face < q.face : p.edge < q.edge;
  });
  return edges;
}

bool RemeshedStreakBuilder::split_pass(std::size_t& splits, bool near_reshaped) {
  // After the first pass, an edge is long only where that pass split (the edges of the faces
  // it split now meet their new particles, or lead to where they landed) or in a face a flip
  // then changed (flips make no long edge, but move edges between faces): around near_.
  const auto is_long = [&](double length, std::int32_t a, std::int32_t b) {
    return length > o_.split * edge_at(a, b);
  };
  std::vector<Split> long_edges =
      near_reshaped ? edges_near(near_, is_long) : edges_where(is_long);
  if (long_edges.empty()) return true;
  std::sort(long_edges.begin(), long_edges.end(),
            [](const Split& a, const Split& b) { return a.length > b.length; });
  // Longest first, no two in one face: each split sees the faces it was chosen from.
  std::vector<char> used(topo_.face_slots(), 0);
  std::vector<Split> chosen;
  for (const Split& sp : long_edges) {
    const std::int32_t g = topo_.neighbor(sp.face, sp.edge);
    if (used[idx(sp.face)] || (g != none && used[idx(g)])) continue;
    used[idx(sp.face)] = 1;
    if (g != none) used[idx(g)] = 1;
    chosen.push_back(sp);
  }
  // The new particles: label midpoints, released there and moved to now; or (interpolated)
  // placed at the edge's midpoint one break ago and moved from there. Particles a few breaks old
  // are released either way (their paths are short).
  const std::size_t n = chosen.size();
  std::vector<Vec3> exact_x, near_x;
  std::vector<double> exact_from, exact_s, exact_tau;
  std::vector<std::size_t> exact_of, near_of, flat_of, curve_of;
  std::vector<Vec3> x(n);
  std::vector<double> ms(n), mtau(n);
  for (std::size_t k = 0; k < n; ++k) {
    const auto& c = topo_.face(chosen[k].face);
    const std::int32_t a = c[chosen[k].edge], b = c[(chosen[k].edge + 1) % 3];
    double sa = s_[idx(a)], sb = s_[idx(b)];
    if (seed_.closed() && std::abs(sa - sb) > 0.5) (sa < sb ? sa : sb) += 1;  // across s = 0
    ms[k] = 0.5 * (sa + sb);
    if (seed_.closed() && ms[k] >= 1) ms[k] -= 1;
    mtau[k] = 0.5 * (tau_[idx(a)] + tau_[idx(b)]);
    const bool young = t_ - mtau[k] <= 4 * (t_ - previous_t_);
    // Where the surface is flat across the edge its midpoint lies on it: no path is needed
    // (young particles are released anyway, their paths are short).
    if (o_.flat_split > 0 && !young) {
      const double tolerance = o_.flat_split * edge_at(a, b);
      std::array<std::int32_t, 2> beyond{};
      if (chord_departure(chosen[k].face, chosen[k].edge, ring_, beyond) <= tolerance) {
        flat_of.push_back(k);
        continue;
      }
      Vec3 on_curve;
      if (boundary_cubic(a, b, beyond, tolerance, on_curve)) {
        curve_of.push_back(k);
        x[k] = on_curve;
        continue;
      }
    }
    // An end placed by interpolation does not lie on its label's path, so the path of the label
    // midpoint has no reason to pass near the edge: it mostly lands off it, and would be
    // integrated from its release only to be replaced by interpolation below. Ends split flat
    // are the exception: their labels are interpolated where the surface is flat, close to
    // true, and across a bend the chord's midpoint (interpolation) would leave the surface.
    const bool ends_trusted =
        o_.flat_split > 0 || (label_exact_[idx(a)] && label_exact_[idx(b)]);
    if (o_.insertion == ParticleInsertion::exact && !ends_trusted && !young) ++report_.inexact_ends;
    const bool exact =
        o_.insertion == ParticleInsertion::exact && ends_trusted && !labels_tangled(chosen[k]);
    if (exact || young || previous_t_ >= t_ || mtau[k] > previous_t_) {
      exact_of.push_back(k);
      exact_x.push_back(seed_point(ms[k]));
      exact_from.push_back(mtau[k]);
    } else {
      near_of.push_back(k);
      near_x.push_back(0.5 * (previous_x_[idx(a)] + previous_x_[idx(b)]));
    }
  }
  if (o_.insertion == ParticleInsertion::exact) report_.diverged_insertions += near_of.size();
  std::vector<ParticleStatus> exact_status(exact_x.size()), near_status(near_x.size());
  {
    const StageTimer timer(report_.insert_seconds);
    if (!exact_x.empty() &&
        !no_error(advect_from_release(access_, map_, exact_x, exact_from, t_, exact_status,
                                      report_.evaluations)))
      return false;
    if (!near_x.empty()) {
      if (access_.prepare && !no_error(access_.prepare(previous_t_, t_))) return false;
      const std::vector<double> from(near_x.size(), previous_t_);
      report_.evaluations += map_.advect_all(near_x, from, t_, near_status);
      if (access_.prepare && !no_error(access_.prepare(t_, t_))) return false;
    }
  }
  std::vector<ParticleStatus> status(n);
  std::vector<Vec3> before(n);
  for (std::size_t k = 0; k < exact_of.size(); ++k) {
    x[exact_of[k]] = exact_x[k];
    status[exact_of[k]] = exact_status[k];
  }
  for (std::size_t k = 0; k < near_of.size(); ++k) {
    x[near_of[k]] = near_x[k];
    status[near_of[k]] = near_status[k];
  }
  for (const std::size_t k : flat_of) {
    const auto& c = topo_.face(chosen[k].face);
    x[k] = 0.5 * (x_[idx(c[chosen[k].edge])] + x_[idx(c[(chosen[k].edge + 1) % 3])]);
    status[k] = ParticleStatus::moving;
  }
  for (const std::size_t k : curve_of) status[k] = ParticleStatus::moving;  // x[k] is set
  for (int round = 0; round < 2; ++round)
    if (!steer_to_midpoints(chosen, exact_of, x, status, ms, mtau)) return false;
  // Where even the steered particle lands far from the edge (its label's path went elsewhere:
  // the edge spans labels whose paths parted), it would bridge to another part of the surface.
  // It is placed as interpolated insertion places it instead: at the edge's midpoint one break
  // ago, moved from there (counted as interpolated).
  std::vector<std::size_t> far;
  for (const std::size_t k : exact_of) {
    const auto& c = topo_.face(chosen[k].face);
    const Vec3& xa = x_[idx(c[chosen[k].edge])];
    const Vec3& xb = x_[idx(c[(chosen[k].edge + 1) % 3])];
    if (status[k] == ParticleStatus::moving && (x[k] - 0.5 * (xa + xb)).norm() > 0.25 * (xb - xa).norm() &&
        previous_t_ < t_)
      far.push_back(k);
  }
  if (!far.empty()) {
    std::vector<Vec3> fx(far.size());
    std::vector<ParticleStatus> fst(far.size());
    for (std::size_t i = 0; i < far.size(); ++i) {
      const auto& c = topo_.face(chosen[far[i]].face);
      fx[i] = 0.5 * (previous_x_[idx(c[chosen[far[i]].edge])] +
                     previous_x_[idx(c[(chosen[far[i]].edge + 1) % 3])]);
    }
    const StageTimer timer(report_.insert_seconds);
    if (access_.prepare && !no_error(access_.prepare(previous_t_, t_))) return false;
    const std::vector<double> from(far.size(), previous_t_);
    report_.evaluations += map_.advect_all(fx, from, t_, fst);
    if (access_.prepare && !no_error(access_.prepare(t_, t_))) return false;
    for (std::size_t i = 0; i < far.size(); ++i) {
      x[far[i]] = fx[i];
      status[far[i]] = fst[i];
    }
    report_.diverged_insertions += far.size();
  }
  // A particle that would turn over one of the faces it makes (it landed beyond a corner across
  // the edge: a thin face beside it) goes to the edge's midpoint instead, which keeps them all
  // on their side; it is counted as placed by interpolation.
  std::size_t folding_exact = 0;
  std::vector<char> exact_placed(n, 0);
  for (const std::size_t k : exact_of) exact_placed[k] = 1;
  for (const std::size_t k : far) exact_placed[k] = 0;
  for (std::size_t k = 0; k < n; ++k) {
    if (status[k] != ParticleStatus::moving) continue;
    const std::int32_t f = chosen[k].face;
    const int e = chosen[k].edge;
    const std::int32_t a = topo_.face(f)[e], b = topo_.face(f)[(e + 1) % 3];
    const Vec3 mid = 0.5 * (x_[idx(a)] + x_[idx(b)]);
    const auto keeps_side = [&](std::int32_t face, std::int32_t p, std::int32_t q) {
      // The face (p, q, o) split at m into (p, m, o) and (m, q, o).
      const std::int32_t o = topo_.opposite(face, topo_.face(face)[0] == p   ? 0
                                                  : topo_.face(face)[1] == p ? 1
                                                                             : 2);
      const Vec3 side = normal(p, q, o);
      const Vec3& xo = x_[idx(o)];
      const Vec3 n1 = (x[k] - x_[idx(p)]).cross(xo - x_[idx(p)]);
      const Vec3 n2 = (x_[idx(q)] - x[k]).cross(xo - x[k]);
      // Within 60° of the face it splits (in 2D exactly its sign): a steeper new face would
      // crease the surface against its neighbours.
      const double flat = 0.5 * side.norm();
      return n1.dot(side) > flat * n1.norm() && n2.dot(side) > flat * n2.norm();
    };
    bool ok = keeps_side(f, a, b);
    const std::int32_t g = topo_.neighbor(f, e);
    if (ok && g != none) ok = keeps_side(g, b, a);
    if (ok) continue;
    x[k] = mid;
    if (exact_placed[k]) {
      exact_placed[k] = 0;
      ++folding_exact;
    }
  }
  report_.diverged_insertions += folding_exact;
  report_.exact_insertions += exact_of.size() - far.size() - folding_exact;
  report_.interpolated_insertions +=
      near_of.size() + far.size() + folding_exact + flat_of.size() + curve_of.size();
  report_.flat_insertions += flat_of.size();
  report_.curve_insertions += curve_of.size();
  std::vector<char> cropped(n, 0);
  if (o_.region)
    for (std::size_t k = 0; k < n; ++k) crop(x[k], status[k], cropped[k]);
  std::vector<std::pair<std::int32_t, bool>> stopped;
  for (std::size_t k = 0; k < n; ++k) {
    const auto& c = topo_.face(chosen[k].face);
    const std::int32_t a = c[chosen[k].edge], b = c[(chosen[k].edge + 1) % 3];
    const Vec3 was = 0.5 * (previous_x_[idx(a)] + previous_x_[idx(b)]);
    const bool chain_edge = on_chain_[idx(a)] && on_chain_[idx(b)] &&
                            topo_.neighbor(chosen[k].face, chosen[k].edge) == none;
    const std::int32_t m = topo_.split(chosen[k].face, chosen[k].edge);
    reshaped_.push_back(m);
    x_.push_back(x[k]);
    previous_x_.push_back(was);
    s_.push_back(ms[k]);
    tau_.push_back(mtau[k]);
    status_.push_back(status[k]);
    id_.push_back(next_id_++);
    on_chain_.push_back(0);
    label_exact_.push_back(exact_placed[k]);
    if (chain_edge) {
      // The newest row gains the particle between a and b.
      const auto ia = std::find(chain_.begin(), chain_.end(), a);
      const auto ib = std::find(chain_.begin(), chain_.end(), b);
      const auto later = std::max(ia, ib);
      const bool wraps = seed_.closed() && std::abs(ia - ib) + 1 ==
                                               static_cast<std::ptrdiff_t>(chain_.size());
      if (ia != chain_.end() && ib != chain_.end() && (std::abs(ia - ib) == 1 || wraps)) {
        chain_.insert(wraps ? chain_.end() : later, m);  // closed seed: after the last
        on_chain_[idx(m)] = 1;
      }
    }
    if (status[k] != ParticleStatus::moving) stopped.emplace_back(m, cropped[k] != 0);
  }
  // Stopped only now: removing a stopped particle's faces can take faces beyond its own split
  // (a fan that would meet another at a point), which a later split of this pass may hold.
  for (const auto& [m, cropped_out] : stopped) stop_particle(m, cropped_out);
  splits += n;
  report_.splits += n;
  return true;
}

double RemeshedStreakBuilder::chord_departure(std::int32_t f, int e,
                                              std::vector<Topology::HalfEdge>& ring,
                                              std::array<std::int32_t, 2>& beyond) const {
  beyond = {none, none};
  const auto& c = topo_.face(f);
  const std::int32_t ends[2] = {c[e], c[(e + 1) % 3]};
  const std::int32_t g = topo_.neighbor(f, e);
  constexpr double unknown = std::numeric_limits<double>::infinity();
  const auto not_known = [&] {
    beyond = {none, none};
    return unknown;
  };
  const Vec3 mid = 0.5 * (x_[idx(ends[0])] + x_[idx(ends[1])]);
  Vec3 n = normal(c[0], c[1], c[2]);
  if (g != none) n += normal(topo_.face(g)[0], topo_.face(g)[1], topo_.face(g)[2]);
  if (!(n.norm() > 0)) return unknown;
  n.normalize();
  // The surface's largest curvature near the edge, from the heights over the plane at the
  // midpoint of the corners around both ends: a curve of curvature k rises k·r²/2 over a
  // distance r. An error in the plane's tilt reads as curvature too, which only errs toward
  // integrating.
  double curvature = 0;
  for (int i = 0; i < 2; ++i) {
    const std::int32_t v = ends[i], other = ends[1 - i];
    const bool fan_on_boundary = topo_.fan(v, ring);
    bool holds = false;
    for (const Topology::HalfEdge& h : ring) {
      const std::int32_t q = topo_.to(h), r = topo_.opposite(h.face, h.edge);
      holds = holds || q == other || r == other;
      for (const std::int32_t corner : {q, r}) {
        const Vec3 d = x_[idx(corner)] - mid;
        const double height = d.dot(n), across = d.squaredNorm() - height * height;
        if (across > 0) curvature = std::max(curvature, 2 * std::abs(height) / across);
      }
    }
    if (!holds) return not_known();
    if (g != none) continue;
    if (!fan_on_boundary) return not_known();
    // The fan runs from the boundary edge leaving v to the one entering it.
    const std::int32_t next = topo_.to(ring.front());
    const std::int32_t previous = topo_.opposite(ring.back().face, ring.back().edge);
    if (next == other)
      beyond[i] = previous;
    else if (previous == other)
      beyond[i] = next;
    else
      return not_known();
  }
  const Vec3 d = x_[idx(ends[1])] - x_[idx(ends[0])];
  double departure = curvature * d.squaredNorm() / 8;
  if (g == none) {
    // The boundary's own turn over the edge (central differences give its tangents at the ends).
    const Vec3 ta = x_[idx(ends[1])] - x_[idx(beyond[0])];
    const Vec3 tb = x_[idx(beyond[1])] - x_[idx(ends[0])];
    if (!(ta.norm() > 0 && tb.norm() > 0)) return unknown;
    departure = std::max(departure, d.norm() * std::atan2(ta.cross(tb).norm(), ta.dot(tb)) / 8);
  }
  return departure;
}

bool RemeshedStreakBuilder::boundary_cubic(std::int32_t a, std::int32_t b,
                                           const std::array<std::int32_t, 2>& beyond,
                                           double tolerance, Vec3& at) const {
  if (beyond[0] == none || beyond[1] == none) return false;
  const std::int32_t v[4] = {beyond[0], a, b, beyond[1]};
  const double near_s = s_[idx(a)];
  Eigen::Vector2d label[4];
  for (int i = 0; i < 4; ++i) label[i] = label_near(v[i], near_s);
  // The label that varies along the boundary: the other one is the same at all four, to
  // 1e-6 of its range (smoothing along a boundary interpolates labels, with rounding).
  const double range[2] = {1.0, std::max(o_.release_end - o_.release_begin, 1e-300)};
  int along = -1;
  for (int l = 0; l < 2 && along < 0; ++l) {
    const int other = 1 - l;
    bool fixed = true;
    for (int i = 1; i < 4; ++i)
      fixed = fixed && std::abs(label[i][other] - label[0][other]) <= 1e-6 * range[other];
    if (fixed) along = l;
  }
  // Elsewhere (a boundary cut by pruning, a stop or the region) the boundary is a curve on
  // the surface with no label of its own: it is parametrized by its length.
  double u[4];
  if (along >= 0) {
    for (int i = 0; i < 4; ++i) u[i] = label[i][along];
  } else {
    u[0] = 0;
    for (int i = 1; i < 4; ++i) u[i] = u[i - 1] + (x_[idx(v[i])] - x_[idx(v[i - 1])]).norm();
  }
  const double sign = u[2] > u[1] ? 1 : -1;
  for (int i = 0; i < 3; ++i)
    if (!(sign * (u[i + 1] - u[i]) > 0)) return false;  // strictly monotone
  const double um = 0.5 * (u[1] + u[2]);
  // Lagrange interpolation at um through the points `from` .. `to` of v.
  const auto lagrange = [&](int from, int to) {
    Vec3 p = Vec3::Zero();
    for (int i = from; i <= to; ++i) {
      double w = 1;
      for (int j = from; j <= to; ++j)
        if (j != i) w *= (um - u[j]) / (u[i] - u[j]);
      p += w * x_[idx(v[i])];
    }
    return p;
  };
  const Vec3 cubic = lagrange(0, 3);
  const double error = std::max((cubic - lagrange(0, 2)).norm(), (cubic - lagrange(1, 3)).norm());
  if (!(error <= tolerance)) return false;
  at = cubic;
  return true;
}

double RemeshedStreakBuilder::label_area(std::int32_t f) const {
  const auto& c = topo_.face(f);
  const double s0 = s_[idx(c[0])];
  const Eigen::Vector2d p = label_near(c[0], s0), q = label_near(c[1], s0) - p,
                        r = label_near(c[2], s0) - p;
  return q.x() * r.y() - q.y() * r.x();
}

bool RemeshedStreakBuilder::labels_tangled(const Split& edge) const {
  if (label_sign_ == 0) return false;
  if (!(label_area(edge.face) * label_sign_ > 0)) return true;
  const std::int32_t g = topo_.neighbor(edge.face, edge.edge);
  return g != none && !(label_area(g) * label_sign_ > 0);
}

bool RemeshedStreakBuilder::steer_to_midpoints(const std::vector<Split>& chosen,
                                               const std::vector<std::size_t>& which,
                                               std::vector<Vec3>& x,
                                               std::vector<ParticleStatus>& status,
                                               std::vector<double>& ms, std::vector<double>& mtau) {
  const double tolerance = 0.05 * o_.edge;
  const double tau_hi = std::min(t_, o_.release_end);
  std::vector<std::size_t> redo;
  std::vector<Vec3> rx;
  std::vector<double> rfrom, rs;
  for (const std::size_t k : which) {
    if (status[k] != ParticleStatus::moving) continue;
    const std::int32_t f = chosen[k].face;
    const int e = chosen[k].edge;
    const auto& c = topo_.face(f);
    const std::int32_t a = c[e], b = c[(e + 1) % 3], o = c[(e + 2) % 3];
    const Vec3 target = 0.5 * (x_[idx(a)] + x_[idx(b)]);
    const Vec3 error = x[k] - target;
    if (error.norm() <= tolerance) continue;
    // A path that ends more than the edge's length away went elsewhere (its label midpoint
    // lies between paths that parted): a chord step does not bring it back, and it is placed
    // by interpolation below.
    if (error.norm() > (x_[idx(b)] - x_[idx(a)]).norm()) continue;
    const Eigen::Vector2d l0(ms[k], mtau[k]);
    const Eigen::Vector2d la = label_near(a, ms[k]), lb = label_near(b, ms[k]), lo = label_near(o, ms[k]);
    Eigen::Vector2d l1;
    const Vec3 d = x_[idx(b)] - x_[idx(a)];
    if (topo_.neighbor(f, e) == none) {
      const double lambda = std::clamp(-d.dot(error) / d.squaredNorm(), -0.4, 0.4);
      l1 = l0 + lambda * (lb - la);
    } else {
      Eigen::Matrix2d dl;
      dl.col(0) = lb - la;
      dl.col(1) = lo - la;
      const double det = dl.determinant();
      if (!(std::abs(det) > 1e-9 * dl.col(0).norm() * dl.col(1).norm())) continue;
      Eigen::Matrix<double, 3, 2> dx;
      dx.col(0) = d;
      dx.col(1) = x_[idx(o)] - x_[idx(a)];
      const Eigen::Matrix<double, 3, 2> jacobian = dx * dl.inverse();
      const Eigen::Matrix2d normal = jacobian.transpose() * jacobian;
      if (!(std::abs(normal.determinant()) > 0)) continue;
      l1 = l0 - normal.ldlt().solve(jacobian.transpose() * error);
      // A chord step is trusted only inside the labels of the two faces beside the edge.
      const auto inside = [&](const Eigen::Vector2d& p, const Eigen::Vector2d& q,
                              const Eigen::Vector2d& r) {
        Eigen::Matrix2d m;
        m.col(0) = q - p;
        m.col(1) = r - p;
        const Eigen::Vector2d w = m.inverse() * (l1 - p);
        return w.x() >= 0 && w.y() >= 0 && w.x() + w.y() <= 1;
      };
      const std::int32_t g = topo_.neighbor(f, e);
      std::int32_t other = none;
      for (const std::int32_t v : topo_.face(g))
        if (v != a && v != b) other = v;
      const Eigen::Vector2d ld = label_near(other, ms[k]);
      if (!(inside(la, lb, lo) || (std::abs((la - ld).x() * (lb - ld).y() - (la - ld).y() * (lb - ld).x()) > 0 &&
                                   inside(lb, la, ld))))
        continue;
    }
    if (!seed_.closed()) l1.x() = std::clamp(l1.x(), 0.0, 1.0);
    l1.x() -= std::floor(l1.x()) * (seed_.closed() ? 1.0 : 0.0);
    l1.y() = std::clamp(l1.y(), o_.release_begin, tau_hi);
    if (!l1.allFinite()) continue;
    redo.push_back(k);
    rx.push_back(seed_point(l1.x()));
    rfrom.push_back(l1.y());
    rs.push_back(l1.x());
  }
  if (redo.empty()) return true;
  std::vector<ParticleStatus> rst(redo.size());
  {
    const StageTimer timer(report_.insert_seconds);
    if (!no_error(advect_from_release(access_, map_, rx, rfrom, t_, rst, report_.evaluations)))
      return false;
  }
  report_.steered_insertions += redo.size();
  for (std::size_t i = 0; i < redo.size(); ++i) {
    const std::size_t k = redo[i];
    const auto& c = topo_.face(chosen[k].face);
    const Vec3 target =
        0.5 * (x_[idx(c[chosen[k].edge])] + x_[idx(c[(chosen[k].edge + 1) % 3])]);
    if (rst[i] != ParticleStatus::moving || (rx[i] - target).norm() >= (x[k] - target).norm())
      continue;
    x[k] = rx[i];
    ms[k] = rs[i];
    mtau[k] = rfrom[i];
  }
  return true;
}

bool RemeshedStreakBuilder::collapsible(std::int32_t u, std::int32_t w) const {
  if (on_chain_[idx(u)]) {
    if (!on_chain_[idx(w)]) return false;
    // Along the newest row only, never its ends.
    const auto iu = std::find(chain_.begin(), chain_.end(), u);
    const auto iw = std::find(chain_.begin(), chain_.end(), w);
    if (std::abs(iu - iw) != 1) return false;
    if (!seed_.closed() && (iu == chain_.begin() || iu + 1 == chain_.end())) return false;
  }
  // The geometric tests first: they refuse most edges, and the link condition costs more.
  std::vector<Topology::HalfEdge>& ring = collapse_ring_;
  const bool boundary = topo_.fan(u, ring);
  if (ring.empty()) return false;
  const Vec3& xu = x_[idx(u)];
  const Vec3& xw = x_[idx(w)];
  if (boundary) {
    // A boundary vertex goes only where its boundary is straight (its shape is kept).
    const std::int32_t p = topo_.to(ring.front());
    const std::int32_t q = topo_.opposite(ring.back().face, ring.back().edge);
    const double straight = angle_at(xu, x_[idx(p)], x_[idx(q)]);
    if (straight < 160.0 * M_PI / 180.0) return false;
  }
  for (const Topology::HalfEdge& h : ring) {
    const auto& c = topo_.face(h.face);
    if (c[0] == w || c[1] == w || c[2] == w) continue;
    const Vec3 before = normal(c[0], c[1], c[2]);
    const Vec3 after = normal_with(c[0], c[1], c[2], u, w);
    // The face keeps its side (within 60°: in 2D exactly its sign, which is the sheet's: where
    // the flow crosses the seed both ways, the dye on either side lies face down) and does not
    // become a sliver.
    if (!(after.dot(before) > 0.5 * after.norm() * before.norm())) return false;
    const std::int32_t other1 = c[(h.edge + 1) % 3], other2 = c[(h.edge + 2) % 3];
    const Vec3& p1 = x_[idx(other1)];
    const Vec3& p2 = x_[idx(other2)];
    if ((p1 - xw).squaredNorm() > std::pow(o_.split * edge_at(w, other1), 2) ||
        (p2 - xw).squaredNorm() > std::pow(o_.split * edge_at(w, other2), 2))
      return false;
    const double area = after.norm();
    const double longest = std::max({(p1 - xw).squaredNorm(), (p2 - xw).squaredNorm(),
                                     (p1 - p2).squaredNorm()});
    if (area < 0.1 * longest) return false;  // smallest angle below about 6°
  }
  return topo_.can_collapse(u, w);
}

void RemeshedStreakBuilder::collapse_pass() {
  const auto start = Clock::now();
  const double base = o_.collapse * o_.edge;
  ++collapse_passes_;
  if (collapse_passes_ % 64 == 0)
    std::erase_if(refused_, [&](const auto& r) { return r.second <= collapse_passes_; });
  std::vector<Split> short_edges = edges_where([&](double length, std::int32_t a, std::int32_t b) {
    // An edge refused lately is left alone for a few passes: most refusals (a neighbour would
    // turn or thin, a new edge would split) outlast one step, and short edges that stay short
    // would be tried again at every step. Boundary edges are tried again sooner (they shape the
    // boundary, and the loose ends of filaments). The pass refuses only edges it has already
    // tried, so they can be left out of the list here.
    if (!(length < o_.collapse * edge_at(a, b))) return false;
    const auto refused = refused_.find(edge_key(a, b));
    return refused == refused_.end() || refused->second <= collapse_passes_;
  });
  if (short_edges.empty()) {
    report_.coarsen_seconds += seconds_since(start);
    return;
  }
  std::sort(short_edges.begin(), short_edges.end(),
            [](const Split& a, const Split& b) { return a.length < b.length; });
  std::vector<char> touched(x_.size(), 0);
  std::vector<Topology::HalfEdge> ring;
  for (const Split& sp : short_edges) {
    if (!topo_.face_alive(sp.face)) continue;
    const auto& c = topo_.face(sp.face);
    const std::int32_t a = c[sp.edge], b = c[(sp.edge + 1) % 3];
    if (touched[idx(a)] || touched[idx(b)]) continue;
    const double length = (x_[idx(a)] - x_[idx(b)]).norm();
    if (length >= o_.collapse * edge_at(a, b)) continue;
    const bool inner = topo_.neighbor(sp.face, sp.edge) != none;
    // An inner edge between two boundary vertices would pinch the surface. (Neither end was
    // touched by this pass's collapses, so their fans are the pass's own.)
    if (inner && topo_.on_boundary(a) && topo_.on_boundary(b)) continue;
    // The younger particle goes first: the older one has travelled further on its label.
    std::int32_t u = tau_[idx(a)] >= tau_[idx(b)] ? a : b, w = u == a ? b : a;
    if (!collapsible(u, w)) {
      std::swap(u, w);
      if (!collapsible(u, w)) {
        refused_[edge_key(a, b)] = collapse_passes_ + (inner ? 8 : 2);
        continue;
      }
    }
    topo_.fan(u, ring);
    for (const Topology::HalfEdge& h : ring)
      for (const std::int32_t v : topo_.face(h.face)) touched[idx(v)] = 1;
    if (on_chain_[idx(u)]) {
      chain_.erase(std::find(chain_.begin(), chain_.end(), u));
      on_chain_[idx(u)] = 0;
    }
    topo_.collapse(u, w);  // u has no face left: it is no longer moved, and compact() drops it
    reshaped_.push_back(w);
    ++report_.collapses;
    if (length >= base) ++report_.coarsened;
  }
  report_.coarsen_seconds += seconds_since(start);
}

bool RemeshedStreakBuilder::wants_flip(std::int32_t fi, int e) const {
  const std::int32_t g = topo_.neighbor(fi, e);
  const auto& c = topo_.face(fi);
  const std::int32_t a = c[e], b = c[(e + 1) % 3], p = c[(e + 2) % 3];
  const auto& gc = topo_.face(g);
  std::int32_t q = none;
  for (const std::int32_t v : gc)
    if (v != a && v != b) q = v;
  const Vec3 &xa = x_[idx(a)], &xb = x_[idx(b)], &xp = x_[idx(p)], &xq = x_[idx(q)];
  // Delaunay: the angles opposite the edge sum to more than π, i.e. the sine of their sum
  // is negative (times the four edge lengths: no trigonometry); and no edge that splits.
  const Vec3 pa = xa - xp, pb = xb - xp, qa = xa - xq, qb = xb - xq;
  const double sine_sum = pa.cross(pb).norm() * qa.dot(qb) + pa.dot(pb) * qa.cross(qb).norm();
  if (!(sine_sum < -1e-9 * std::sqrt(pa.squaredNorm() * pb.squaredNorm() *
                                     qa.squaredNorm() * qb.squaredNorm())))
    return false;
  if ((xp - xq).squaredNorm() > std::pow(o_.split * edge_at(p, q), 2)) return false;
  // The new faces (a, q, p) and (q, b, p) keep the side of the old ones, which lie nearly
  // flat across the edge (a flip across a crease would change the surface).
  const Vec3 n1 = normal(a, q, p), n2 = normal(q, b, p);
  const Vec3 nf = normal(a, b, p), ng = normal(b, a, q);
  const double lf = nf.norm(), lg = ng.norm();
  if (!(nf.dot(ng) > 0.9 * lf * lg)) return false;
  const Vec3 mean = nf / lf + ng / lg;
  return n1.dot(mean) > 0 && n2.dot(mean) > 0;
}

template <class Flag>
void RemeshedStreakBuilder::flag_faces(const Flag& flag) {
  face_flags_.assign(topo_.face_slots(), 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, topo_.face_slots(), 1024),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      std::vector<Topology::HalfEdge> ring;
                      for (std::size_t f = r.begin(); f < r.end(); ++f) {
                        const auto fi = static_cast<std::int32_t>(f);
                        if (topo_.face_alive(fi)) face_flags_[f] = flag(fi, ring);
                      }
                    });
}

std::size_t RemeshedStreakBuilder::flip_pass() {
  const std::size_t before = report_.flips;
  // The test reads positions and the two faces alone: it runs for every edge at once, and the
  // sweep (in face order, as flips depend on earlier ones) repeats it where a flip changed a face.
  flag_faces([&](std::int32_t fi, std::vector<Topology::HalfEdge>&) {
    std::uint8_t bits = 0;
    for (int e = 0; e < 3; ++e) {
      const std::int32_t g = topo_.neighbor(fi, e);
      if (g != none && g > fi && wants_flip(fi, e)) bits |= std::uint8_t(1u << e);
    }
    return bits;
  });
  changed_faces_.assign(topo_.face_slots(), 0);
  for (std::size_t f = 0; f < topo_.face_slots(); ++f) {
    const auto fi = static_cast<std::int32_t>(f);
    if (!topo_.face_alive(fi)) continue;
    for (int e = 0; e < 3; ++e) {
      const std::int32_t g = topo_.neighbor(fi, e);
      if (g == none || g < fi) continue;
      const bool want = changed_faces_[f] || changed_faces_[idx(g)] ? wants_flip(fi, e)
                                                         : (face_flags_[f] >> e & 1u) != 0;
      if (want && topo_.flip(fi, e)) {
        ++report_.flips;
        changed_faces_[f] = changed_faces_[idx(g)] = 1;
      }
    }
  }
  return report_.flips - before;
}

double RemeshedStreakBuilder::smallest_angle_cosine(std::int32_t, std::int32_t b, std::int32_t c,
                                                    const Vec3& xa) const {
  const Vec3& xb = x_[idx(b)];
  const Vec3& xc = x_[idx(c)];
  const auto cosine = [](const Vec3& p, const Vec3& q, const Vec3& r) {
    const Vec3 u = q - p, w = r - p;
    return u.dot(w) / std::sqrt(u.squaredNorm() * w.squaredNorm());
  };
  return std::max({cosine(xa, xb, xc), cosine(xb, xc, xa), cosine(xc, xa, xb)});
}

void RemeshedStreakBuilder::smooth_pass() {
  if (!o_.smooth) return;
  const double good = std::cos(30.0 * M_PI / 180.0);  // faces with an angle under 30°
  flag_faces([&](std::int32_t f, std::vector<Topology::HalfEdge>&) {
    const auto& c = topo_.face(f);
    return static_cast<std::uint8_t>(!(smallest_angle_cosine(c[0], c[1], c[2], x_[idx(c[0])]) <= good));
  });
  // The particles that may move: those placed by interpolation (an exact particle would leave
  // its label's path), not on the newest row, at a corner of a face with an angle under 30°.
  std::vector<std::int32_t> candidates;
  std::vector<char> seen(x_.size(), 0);
  for (std::size_t f = 0; f < topo_.face_slots(); ++f) {
    if (!face_flags_[f] || !topo_.face_alive(static_cast<std::int32_t>(f))) continue;
    for (const std::int32_t v : topo_.face(static_cast<std::int32_t>(f)))
      if (!seen[idx(v)] && !label_exact_[idx(v)] && !on_chain_[idx(v)] && alive(v)) {
        seen[idx(v)] = 1;
        candidates.push_back(v);
      }
  }
  for (const std::int32_t v : candidates) {
    const bool boundary = topo_.fan(v, ring_);
    if (ring_.empty()) continue;
    const Vec3& xv = x_[idx(v)];
    // The target: the mean of the apexes that would make each face around equilateral.
    Vec3 target = Vec3::Zero();
    for (const Topology::HalfEdge& h : ring_) {
      const Vec3& xq = x_[idx(topo_.to(h))];
      const Vec3& xr = x_[idx(topo_.opposite(h.face, h.edge))];
      const Vec3 n = (xq - xv).cross(xr - xv);
      const Vec3 across = n.cross(xr - xq);
      if (!(across.squaredNorm() > 0)) continue;
      target += 0.5 * (xq + xr) + (std::sqrt(3.0) / 2) * (xr - xq).norm() * across.normalized();
    }
    target /= static_cast<double>(ring_.size());
    Vec3 d = target - xv;
    if (boundary) {
      // Along a straight boundary only (within 20°, as for collapses), toward the neighbour
      // on the side it moves to and no further than halfway: the boundary keeps its shape.
      const std::int32_t p = topo_.to(ring_.front());
      const std::int32_t q = topo_.opposite(ring_.back().face, ring_.back().edge);
      if (angle_at(xv, x_[idx(p)], x_[idx(q)]) < 160.0 * M_PI / 180.0) continue;
      const Vec3 toward_q = x_[idx(q)] - xv, toward_p = x_[idx(p)] - xv;
      const double along_q = d.dot(toward_q) / toward_q.squaredNorm();
      const double along_p = d.dot(toward_p) / toward_p.squaredNorm();
      d = along_q > along_p ? std::min(along_q, 0.5) * toward_q : std::min(along_p, 0.5) * toward_p;
    } else {
      Vec3 n = Vec3::Zero();
      for (const Topology::HalfEdge& h : ring_) {
        const auto& c = topo_.face(h.face);
        n += normal(c[0], c[1], c[2]);
      }
      if (!(n.squaredNorm() > 0)) continue;
      n.normalize();
      d -= n * n.dot(d);
    }
    const Vec3 p = xv + 0.5 * d;
    // Every face around keeps its side, no edge grows to split, and the smallest angle grows.
    double before = -1, after = -1;  // the smallest angles' cosines
    bool ok = true;
    for (const Topology::HalfEdge& h : ring_) {
      const std::int32_t q = topo_.to(h), r = topo_.opposite(h.face, h.edge);
      const Vec3 was = (x_[idx(q)] - xv).cross(x_[idx(r)] - xv);
      const Vec3 now = (x_[idx(q)] - p).cross(x_[idx(r)] - p);
      if (!(now.dot(was) > 0.5 * now.norm() * was.norm()) ||
          (x_[idx(q)] - p).squaredNorm() > std::pow(o_.split * edge_at(v, q), 2) ||
          (x_[idx(r)] - p).squaredNorm() > std::pow(o_.split * edge_at(v, r), 2)) {
        ok = false;
        break;
      }
      before = std::max(before, smallest_angle_cosine(v, q, r, xv));
      after = std::max(after, smallest_angle_cosine(v, q, r, p));
    }
    if (!ok || !(after < before)) continue;
    // The label (and the position one break ago) where p lies in the old fan.
    for (const Topology::HalfEdge& h : ring_) {
      const std::int32_t q = topo_.to(h), r = topo_.opposite(h.face, h.edge);
      const Vec3 e1 = x_[idx(q)] - xv, e2 = x_[idx(r)] - xv, w = p - xv;
      const double a11 = e1.dot(e1), a12 = e1.dot(e2), a22 = e2.dot(e2);
      const double det = a11 * a22 - a12 * a12;
      if (!(det > 0)) continue;
      const double bq = (a22 * e1.dot(w) - a12 * e2.dot(w)) / det;
      const double br = (a11 * e2.dot(w) - a12 * e1.dot(w)) / det;
      if (bq < -1e-12 || br < -1e-12 || bq + br > 1 + 1e-12) continue;
      const double bv = 1 - bq - br;
      const double sv = s_[idx(v)];
      const Eigen::Vector2d label =
          bv * label_near(v, sv) + bq * label_near(q, sv) + br * label_near(r, sv);
      previous_x_[idx(v)] = bv * previous_x_[idx(v)] + bq * previous_x_[idx(q)] + br * previous_x_[idx(r)];
      x_[idx(v)] = p;
      s_[idx(v)] = seed_.closed() ? label.x() - std::floor(label.x()) : std::clamp(label.x(), 0.0, 1.0);
      tau_[idx(v)] = label.y();
      ++report_.smoothed;
      break;
    }
  }
}

void RemeshedStreakBuilder::flip_around_reshaped() {
  std::vector<std::int32_t> work;
  for (const std::int32_t v : reshaped_) {
    topo_.fan(v, ring_);  // none for a particle that stopped
    for (const Topology::HalfEdge& h : ring_) work.push_back(h.face);
  }
  // Each flip makes its edge Delaunay and may unmake the four around it: the two faces are
  // looked at again. Bounded, as a flip's side conditions (creases, long edges) could cycle.
  std::size_t budget = 16 * work.size() + 64;
  while (!work.empty() && budget-- > 0) {
    const std::int32_t f = work.back();
    work.pop_back();
    if (!topo_.face_alive(f)) continue;
    for (int e = 0; e < 3; ++e) {
      const std::int32_t g = topo_.neighbor(f, e);
      if (g == none || !wants_flip(f, e) || !topo_.flip(f, e)) continue;
      ++report_.flips;
      for (const std::int32_t v : topo_.face(f)) flipped_.push_back(v);
      for (const std::int32_t v : topo_.face(g)) flipped_.push_back(v);
      work.push_back(f);
      work.push_back(g);
      break;
    }
  }
}

double RemeshedStreakBuilder::filament_width(std::int32_t f,
                                             std::vector<Topology::HalfEdge>& ring) const {
  constexpr double wide = std::numeric_limits<double>::infinity();
  const auto& c = topo_.face(f);
  for (const std::int32_t v : c)
    if (on_chain_[idx(v)]) return wide;
  int boundary = 0, inner = -1, outer = -1;
  for (int e = 0; e < 3; ++e) {
    if (topo_.neighbor(f, e) == none) {
      ++boundary;
      outer = e;
    } else {
      inner = e;
    }
  }
  const auto length = [&](int e) { return (x_[idx(c[e])] - x_[idx(c[(e + 1) % 3])]).norm(); };
  const double area2 = normal(c[0], c[1], c[2]).norm();
  switch (boundary) {
    case 0:
      return wide;
    case 1:
      // The face's height over its boundary edge, where the corner across lies on the boundary
      // too (on the filament's other side).
      return topo_.fan(c[(outer + 2) % 3], ring) ? area2 / length(outer) : wide;
    case 2: {
      // A loose end. Where one of its boundary edges caps the filament (the boundary turns by
      // more than 45° at both its ends), the filament is as wide as the face's smallest height;
      // otherwise (a pointed end) its one inner edge runs across the filament.
      const int e1 = (inner + 1) % 3, e2 = (inner + 2) % 3;  // boundary edges, meeting at c[e2]
      const int cap = length(e1) <= length(e2) ? e1 : e2;
      const std::int32_t far = cap == e1 ? c[e1] : c[(e2 + 1) % 3];  // the cap's other end
      if (topo_.fan(far, ring)) {
        const std::int32_t p = topo_.to(ring.front());
        const std::int32_t q = topo_.opposite(ring.back().face, ring.back().edge);
        if (angle_at(x_[idx(far)], x_[idx(p)], x_[idx(q)]) < 0.75 * M_PI)
          return area2 / std::max({length(0), length(1), length(2)});
      }
      return length(inner);
    }
    default:
      return area2 / std::max({length(0), length(1), length(2)});  // a face on its own
  }
}

void RemeshedStreakBuilder::prune(std::int32_t f) {
  removed_.clear();
  report_.faces_pruned += topo_.remove_face(f, &removed_);
  for (const auto& c : removed_) {
    report_.area_pruned += 0.5 * normal(c[0], c[1], c[2]).norm();
    for (const std::int32_t v : c) changed_vertices_[idx(v)] = 1;
  }
}

void RemeshedStreakBuilder::prune_pass() {
  if (!(o_.prune > 0)) return;
  // Filaments are eaten from their loose ends (a thin face with two boundary edges), face by
  // face along the filament, which never cuts the surface in two. A filament between two wider
  // parts is cut only where it is thinner than half the width (or where a face of it turns
  // over, see advance()): fewer pieces and less dye lost than cutting at the full width, for
  // slightly thinner faces.
  //
  // A face's width depends on its corners' fans alone, so it is measured for every face at
  // once, and measured again in the sweeps only where a removal touched a corner (changed_vertices_).
  const auto boundary_edges = [&](std::int32_t f) {
    int boundary = 0;
    for (int e = 0; e < 3; ++e) boundary += topo_.neighbor(f, e) == none ? 1 : 0;
    return boundary;
  };
  constexpr std::uint8_t loose = 1, thin = 2;  // narrower than the width; than half of it
  flag_faces([&](std::int32_t f, std::vector<Topology::HalfEdge>& ring) {
    const double w = filament_width(f, ring), width = width_at(f);
    return static_cast<std::uint8_t>((w < width && boundary_edges(f) >= 2 ? loose : 0) |
                                     (w < 0.5 * width ? thin : 0));
  });
  changed_vertices_.assign(x_.size(), 0);
  const std::size_t pruned_before = report_.faces_pruned;
  // Until something is removed no face is touched, and the flags alone decide.
  const auto touched = [&](std::int32_t f) {
    if (report_.faces_pruned == pruned_before) return false;
    const auto& c = topo_.face(f);
    return changed_vertices_[idx(c[0])] || changed_vertices_[idx(c[1])] || changed_vertices_[idx(c[2])];
  };
  const auto loose_end = [&](std::int32_t f) {
    if (!topo_.face_alive(f)) return false;
    if (!touched(f)) return (face_flags_[idx(f)] & loose) != 0;
    return filament_width(f, ring_) < width_at(f) && boundary_edges(f) >= 2;
  };
  std::vector<std::int32_t> work;
  for (std::size_t f = 0; f < topo_.face_slots(); ++f) {
    if (face_flags_[f] == 0 && report_.faces_pruned == pruned_before) continue;
    work.assign(1, static_cast<std::int32_t>(f));
    while (!work.empty()) {
      const std::int32_t g = work.back();
      work.pop_back();
      if (!loose_end(g)) continue;
      for (int e = 0; e < 3; ++e)
        if (topo_.neighbor(g, e) != none) work.push_back(topo_.neighbor(g, e));
      prune(g);
    }
  }
  for (std::size_t f = 0; f < topo_.face_slots(); ++f) {
    const auto fi = static_cast<std::int32_t>(f);
    if (face_flags_[f] == 0 && report_.faces_pruned == pruned_before) continue;
    if (!topo_.face_alive(fi)) continue;
    if (touched(fi) ? filament_width(fi, ring_) < 0.5 * width_at(fi) : (face_flags_[f] & thin) != 0)
      prune(fi);
  }
}

std::size_t RemeshedStreakBuilder::count_particles() const {
  std::size_t particles = 0;
  for (std::size_t v = 0; v < x_.size(); ++v) {
    const auto i = static_cast<std::int32_t>(v);
    particles += alive(i) && (topo_.has_faces(i) || on_chain_[v]) ? 1 : 0;
  }
  return particles;
}

double RemeshedStreakBuilder::estimate_particles(double coarsen_age,
                                                 const std::vector<AgedSize>& faces,
                                                 const std::vector<AgedSize>& boundary) const {
  // As the frames' vertex estimate, with each part's own edge length.
  double n = 0;
  for (const AgedSize& f : faces) n += 1.155 * f.size / std::pow(edge_for(f.tau, coarsen_age), 2);
  for (const AgedSize& e : boundary) n += e.size / edge_for(e.tau, coarsen_age);
  return n;
}

void RemeshedStreakBuilder::keep_budget(std::size_t particles) {
  const auto start = Clock::now();
  const double budget = static_cast<double>(o_.vertex_budget);
  std::vector<AgedSize> faces, boundary;
  for (std::size_t f = 0; f < topo_.face_slots(); ++f) {
    const auto fi = static_cast<std::int32_t>(f);
    if (!topo_.face_alive(fi)) continue;
    const auto& c = topo_.face(fi);
    faces.push_back({0.5 * normal(c[0], c[1], c[2]).norm(),
                     std::max({tau_[idx(c[0])], tau_[idx(c[1])], tau_[idx(c[2])]})});
    for (int e = 0; e < 3; ++e) {
      const std::int32_t a = c[e], b = c[(e + 1) % 3];
      if (topo_.neighbor(fi, e) == none)
        boundary.push_back({(x_[idx(a)] - x_[idx(b)]).norm(), std::max(tau_[idx(a)], tau_[idx(b)])});
    }
  }
  const auto needs = [&](double age) { return estimate_particles(age, faces, boundary); };
  // Lowered only when the surface would not fit even once meshed at today's lengths (the
  // collapses lag behind a lowered age by a few steps); never raised, so old parts do not refine
  // again. Bisection in the logarithm of the age.
  const double oldest = t_ - o_.release_begin;
  if (oldest > 0 && needs(coarsen_age_) > 0.8 * budget) {
    double hi = std::min(coarsen_age_, oldest), lo = 1e-6 * oldest;
    if (needs(hi) > 0.7 * budget) {
      for (int i = 0; i < 40; ++i) {
        const double mid = std::sqrt(lo * hi);
        (needs(mid) > 0.7 * budget ? hi : lo) = mid;
      }
      coarsen_age_ = lo;
    } else {
      coarsen_age_ = hi;
    }
    ++report_.budget_coarsenings;
  }
  report_.coarsen_seconds += seconds_since(start);
  // Collapses at the new lengths, a few passes (each collapses at most one edge around a vertex).
  for (int pass = 0; pass < 8 && particles > o_.vertex_budget; ++pass) {
    const std::size_t before = report_.collapses;
    reshaped_.clear();
    collapse_pass();
    flip_around_reshaped();
    reshaped_.clear();
    if (report_.collapses == before) break;
    particles -= std::min(particles, report_.collapses - before);
  }
}

// A full adaptation follows every break (releases and frames). The shorter moves between breaks
// (where particles would go farther than about ℓ in one) are followed by the passes that keep
// lengths and filaments in bounds only: the flip sweep and smoothing, which shape faces, wait for
// the break.
bool RemeshedStreakBuilder::adapt(bool full) {
  const auto start = Clock::now();
  prune_pass();
  // The move changed every face: one sweep over all of them. Splits and collapses change the
  // faces around a vertex: the flips they call for are sought there.
  if (full) flip_pass();
  for (int round = 0; round < o_.max_refinement_rounds; ++round) {
    std::size_t splits = 0;
    near_.swap(reshaped_);
    near_.insert(near_.end(), flipped_.begin(), flipped_.end());
    reshaped_.clear();
    flipped_.clear();
    if (!split_pass(splits, round > 0)) return false;
    if (splits == 0) break;
    flip_around_reshaped();
  }
  reshaped_.clear();
  collapse_pass();
  flip_around_reshaped();
  if (full) smooth_pass();
  report_.refine_seconds += seconds_since(start);
  return true;
}

void RemeshedStreakBuilder::compact() {
  std::vector<char> keep(x_.size(), 0);
  for (std::size_t v = 0; v < x_.size(); ++v)
    keep[v] = on_chain_[v] && status_[v] == ParticleStatus::moving ? 1 : 0;
  const std::vector<std::int32_t> index = topo_.compact(keep);
  std::size_t kept = 0;
  for (std::size_t v = 0; v < index.size(); ++v) {
    if (index[v] == none) continue;
    const std::size_t to = idx(index[v]);
    x_[to] = x_[v];
    previous_x_[to] = previous_x_[v];
    s_[to] = s_[v];
    tau_[to] = tau_[v];
    status_[to] = status_[v];
    id_[to] = id_[v];
    on_chain_[to] = on_chain_[v];
    label_exact_[to] = label_exact_[v];
    kept = std::max(kept, to + 1);
  }
  x_.resize(kept), previous_x_.resize(kept), s_.resize(kept), tau_.resize(kept);
  status_.resize(kept), id_.resize(kept), on_chain_.resize(kept);
  label_exact_.resize(kept);
  std::vector<std::int32_t> chain;
  for (const std::int32_t v : chain_)
    if (index[idx(v)] != none) chain.push_back(index[idx(v)]);
  chain_ = std::move(chain);
}

void RemeshedStreakBuilder::emit_frame(int index) {
  const auto start = Clock::now();
  compact();
  StreakFrame frame;
  frame.index = index;
  frame.time = t_;
  frame.rows = report_.rows_released;
  Mesh& mesh = frame.mesh;
  const std::size_t nv = x_.size();
  mesh.positions.reserve(nv);
  for (std::size_t v = 0; v < nv; ++v) {
    Vec3 p = x_[v];
    if (two_d_) p.z() = 0;
    mesh.add_vertex(p, t_, 0, s_[v], 0, 0, 0);
    mesh.release_time.push_back(tau_[v]);
    mesh.age.push_back(t_ - tau_[v]);
    mesh.particle_id.push_back(id_[v]);
    mesh.on_path.push_back(label_exact_[v]);
  }
  mesh.speed.resize(nv);
  tbb::parallel_for(std::size_t{0}, nv, [&](std::size_t v) {
    Vec3 u;
    mesh.speed[v] = flow_.velocity(x_[v], t_, u) == FieldStatus::inside ? u.norm() : 0.0;
  });
  double area = 0, boundary = 0, edge_ratio = 0;
  // Pieces: faces joined across shared edges (union-find).
  std::vector<std::int32_t> parent(topo_.face_slots());
  std::iota(parent.begin(), parent.end(), 0);
  const auto root = [&](std::int32_t f) {
    while (parent[idx(f)] != f) f = parent[idx(f)] = parent[idx(parent[idx(f)])];
    return f;
  };
  for (std::size_t f = 0; f < topo_.face_slots(); ++f) {
    const auto fi = static_cast<std::int32_t>(f);
    const auto& c = topo_.face(fi);
    mesh.add_triangle(c[0], c[1], c[2]);
    area += 0.5 * normal(c[0], c[1], c[2]).norm();
    for (int e = 0; e < 3; ++e) {
      const std::int32_t g = topo_.neighbor(fi, e);
      const double length = (x_[idx(c[e])] - x_[idx(c[(e + 1) % 3])]).norm();
      edge_ratio = std::max(edge_ratio, length / edge_at(c[e], c[(e + 1) % 3]));
      if (g == none)
        boundary += length;
      else
        parent[idx(root(fi))] = root(g);
    }
  }
  std::size_t pieces = 0;
  for (std::size_t f = 0; f < parent.size(); ++f)
    if (root(static_cast<std::int32_t>(f)) == static_cast<std::int32_t>(f)) ++pieces;
  report_.frame_seconds += seconds_since(start);

  StreakFrameRecord record;
  record.index = index;
  record.time = t_;
  record.vertices = mesh.vertex_count();
  record.faces = mesh.face_count();
  record.rows = report_.rows_released;
  record.dead_particles = report_.left_domain + report_.no_data;
  record.build_seconds = seconds_since(start);
  const auto finish = Clock::now();
  frame.quality = measure_quality(mesh);
  record.quality = frame.quality;
  record.max_edge = frame.quality.longest_edge;
  record.area = area;
  record.boundary_length = boundary;
  record.vertex_estimate = 1.155 * area / (o_.edge * o_.edge) + boundary / o_.edge;
  record.pieces = pieces;
  record.coarsen_age = coarsen_age_;
  record.max_edge_ratio = edge_ratio;
  record.area_pruned = report_.area_pruned;
  if (sink_) sink_(frame);
  record.finish_seconds = seconds_since(finish);
  record.seconds = seconds_since(start);
  report_.frame_finish_seconds += record.finish_seconds;
  report_.frames.push_back(record);
}

StreakReport RemeshedStreakBuilder::run() {
  start_ = Clock::now();
  check_streak_options(o_, flow_, field_name());
  if (!(o_.collapse > 0 && o_.collapse <= 0.5 * o_.split))
    throw InvalidArgument("collapse factor must lie in (0, split/2] (so a collapse never makes "
                          "an edge that splits), got " + number(o_.collapse));
  if (!(o_.prune >= 0 && o_.prune <= 0.5 * o_.split))
    throw InvalidArgument("prune width must lie in [0, split/2] edge lengths (wider would erode "
                          "well-shaped faces at the boundary), got " + number(o_.prune));
  if (!(o_.flat_split >= 0 && std::isfinite(o_.flat_split)))
    throw InvalidArgument("flat split tolerance must be a finite number of edge lengths >= 0 "
                          "(0: none), got " + number(o_.flat_split));
  if (!(o_.coarsen_age >= 0 && std::isfinite(o_.coarsen_age)))
    throw InvalidArgument("coarsening age must be a finite time >= 0 (0: none), got " +
                          number(o_.coarsen_age));
  if (o_.region) {
    const Box<3>& b = *o_.region;
    const int axes = two_d_ ? 2 : 3;
    for (int i = 0; i < axes; ++i)
      if (!(b.lo[i] < b.hi[i]))
        throw InvalidArgument("region of interest is empty along axis " + std::to_string(i) +
                              ": " + number(b.lo[i]) + " to " + number(b.hi[i]));
  }
  report_.dimension = flow_.dimension();
  report_.insertion = o_.insertion;
  report_.mesh = to_string(StreakMesh::remeshed);
  report_.release_begin = o_.release_begin;
  report_.release_end = o_.release_end;
  const int probe = std::max(3, static_cast<int>(std::ceil(seed_.length() / o_.edge)) + 1);
  std::vector<double> speeds;
  std::size_t inside = 0;
  for (const double s : seed_.sample(std::min(probe, 10001))) {
    Vec3 v;
    if (flow_.velocity(seed_point(s), o_.release_begin, v) != FieldStatus::inside) continue;
    if (!in_region(seed_point(s))) continue;
    ++inside;
    if (two_d_) v.z() = 0;
    speeds.push_back(v.norm());
  }
  if (inside == 0)
    throw InvalidArgument("seed " + o_.seed_name + " has no point inside the domain of " +
                          field_name() + " with flow at t = " + number(o_.release_begin) +
                          (o_.region ? " within the region of interest" : ""));
  // Release step: ℓ over the largest speed on the seed, so no particle leaves it further than
  // about ℓ before the next row (slower parts make narrow strips, which collapses thin out).
  const double top_speed = *std::max_element(speeds.begin(), speeds.end());
  double step = o_.release_step;
  if (step == 0) {
    if (!(top_speed > 0))
      throw InvalidArgument("the flow of " + field_name() + " is at rest on seed " + o_.seed_name +
                            " at t = " + number(o_.release_begin) + ": give --release-step");
    step = o_.edge / top_speed;
  }
  report_.release_step = step;
  if (o_.coarsen_age > 0) coarsen_age_ = o_.coarsen_age;
  step_ = step_now_ = step;

  // Breaks: every release (and the release end) and every frame, in order.
  std::vector<double> releases;
  for (std::size_t k = 0;; ++k) {
    const double tau = o_.release_begin + static_cast<double>(k) * step;
    if (tau >= o_.release_end - 1e-9 * step) break;
    releases.push_back(tau);
  }
  releases.push_back(o_.release_end);
  // A frame inside the release interval sees the dye released up to its time: a row leaves the
  // seed then too (a regular release a moment later is dropped: it would make a sliver strip).
  for (const double f : o_.frames)
    if (f > o_.release_begin && f < o_.release_end) releases.push_back(f);
  std::sort(releases.begin(), releases.end());
  std::vector<double> spaced;
  for (std::size_t k = 0; k < releases.size(); ++k) {
    const bool frame = std::binary_search(o_.frames.begin(), o_.frames.end(), releases[k]) ||
                       releases[k] == o_.release_end;
    if (!spaced.empty() && releases[k] - spaced.back() < 0.25 * step) {
      if (frame) spaced.back() = releases[k];
      continue;
    }
    spaced.push_back(releases[k]);
  }
  releases = std::move(spaced);
  std::size_t next_release = 0, next_frame = 0;
  t_ = previous_t_ = o_.release_begin;
  const double t_last = o_.frames.back();
  while (next_frame < o_.frames.size()) {
    // The mesh adapts every release step, after the release ends too (stretching goes on).
    const double r = next_release < releases.size() ? releases[next_release] : t_ + step;
    const double f = o_.frames[next_frame];
    const double b = std::min(r, f);
    if (b > t_ && !advance_to(b)) break;
    if (next_release < releases.size() && releases[next_release] <= t_) {
      release(releases[next_release]);
      ++next_release;
      if (report_.seed_count == 0) report_.seed_count = chain_.size();
    }
    if (!adapt()) break;  // the new strip too: a frame sees an adapted mesh
    std::size_t particles = count_particles();
    if (o_.vertex_budget > 0 && particles > o_.vertex_budget) {
      keep_budget(particles);
      particles = count_particles();
    }
    report_.max_particles = std::max(report_.max_particles, particles);
    if (particles > o_.max_vertices) {
      stop("stopped at t = " + number(t_) + ": " + std::to_string(particles) +
           " particles exceed the cap of " + std::to_string(o_.max_vertices) + " after " +
           std::to_string(next_frame) + " of " + std::to_string(o_.frames.size()) + " frames");
      break;
    }
    if (o_.frames[next_frame] <= t_) {
      emit_frame(static_cast<int>(next_frame));
      ++next_frame;
    }
    // Dead slots (collapsed particles, faces gone) cost every sweep over vertices or faces.
    if (x_.size() > particles + particles / 4 + 1024 ||
        topo_.face_slots() > topo_.face_count() + topo_.face_count() / 4 + 1024)
      compact();
    if (o_.progress) {
      StreakProgress p;
      p.t = t_;
      p.t_end = t_last;
      p.frames_written = next_frame;
      p.frames = o_.frames.size();
      p.particles = particles;
      p.rows = report_.rows_released;
      p.elapsed_seconds = seconds_since(start_);
      p.advect_seconds = report_.advect_seconds;
      p.refine_seconds = report_.refine_seconds;
      p.frame_seconds = report_.frame_seconds;
      p.streamed = static_cast<bool>(access_.prepare);
      if (!o_.progress(p)) {
        stop("interrupted at t = " + number(t_) + " after " + std::to_string(next_frame) + " of " +
             std::to_string(o_.frames.size()) + " frames");
        break;
      }
    }
  }
  report_.time_reached = t_;
  report_.coarsen_age = coarsen_age_;
  report_.total_seconds = seconds_since(start_);
  return report_;
}

}  // namespace

StreakReport build_remeshed_streak(const StreakFlowAccess& access, const SeedCurve& seed,
                                   const StreakOptions& options, const StreakFrameSink& sink) {
  return RemeshedStreakBuilder(access, seed, options, sink).run();
}

}  // namespace orthofront::spacetime
