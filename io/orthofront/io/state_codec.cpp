#include "orthofront/io/state_codec.h"

#include <cstring>

#include "orthofront/io/error.h"

namespace orthofront::io {

void ByteReader::fail(const std::string& what) const {
  throw FormatError("corrupt checkpoint '" + source_ + "': " + what + " at byte " +
                    std::to_string(at_) + " of " + std::to_string(bytes_.size()));
}

void ByteReader::take(void* out, std::size_t size) {
  if (size > left()) fail("ends early (" + std::to_string(size) + " bytes wanted)");
  std::memcpy(out, bytes_.data() + at_, size);
  at_ += size;
}

std::uint64_t ByteReader::count(std::size_t item_bytes) {
  const std::uint64_t n = u64();
  if (item_bytes > 0 && n > left() / item_bytes)
    fail("a count of " + std::to_string(n) + " items that the " + std::to_string(left()) +
         " bytes left cannot hold");
  return n;
}

std::string ByteReader::text() {
  const std::uint64_t n = count(1);
  std::string s(n, '\0');
  if (n) take(s.data(), n);
  return s;
}

namespace {

template <typename Allocator>
void write_vec3s(ByteWriter& out, const std::vector<Vec3, Allocator>& values) {
  out.u64(values.size());
  for (const Vec3& p : values)
    for (int a = 0; a < 3; ++a) out.f64(p[a]);
}

template <typename Allocator>
void read_vec3s(ByteReader& in, std::vector<Vec3, Allocator>& values) {
  const std::uint64_t n = in.count(3 * sizeof(double));
  values.assign(n, Vec3::Zero());
  for (Vec3& p : values)
    for (int a = 0; a < 3; ++a) p[a] = in.f64();
}

// The report's counters, stage times and per-step figures, in the order they are stored: one
// list for writing and reading alike.
constexpr std::size_t SurfaceReport::*kReportCounts[] = {
    &SurfaceReport::vertices,
    &SurfaceReport::faces,
    &SurfaceReport::quads,
    &SurfaceReport::triangles,
    &SurfaceReport::vertex_steps,
    &SurfaceReport::rips,
    &SurfaceReport::negative_alpha,
    &SurfaceReport::clamped_alpha,
    &SurfaceReport::lag_raised_alpha,
    &SurfaceReport::splits,
    &SurfaceReport::merges,
    &SurfaceReport::streamline_insertions,
    &SurfaceReport::insertion_fallbacks,
    &SurfaceReport::skipped_vertex_steps,
    &SurfaceReport::domain_exits,
    &SurfaceReport::no_data_hits,
    &SurfaceReport::zero_velocity_cuts,
    &SurfaceReport::fronts_created,
    &SurfaceReport::fronts_dropped_short,
    &SurfaceReport::fronts_stalled,
    &SurfaceReport::infeasible_damping_steps,
    &SurfaceReport::field_evaluations,
    &SurfaceReport::clamped_slow_flow,
    &SurfaceReport::clamped_front_end,
    &SurfaceReport::clamped_infeasible_step,
    &SurfaceReport::clamped_ahead,
    &SurfaceReport::fallback_left_domain,
    &SurfaceReport::fallback_far_from_front,
    &SurfaceReport::fold_rips,
    &SurfaceReport::folds_left,
    &SurfaceReport::previous_row_insertions,
    &SurfaceReport::stall_cuts,
    &SurfaceReport::gap_stretches,
    &SurfaceReport::gap_faces,
    &SurfaceReport::gaps_refused,
    &SurfaceReport::seed_shots_skipped,
    &SurfaceReport::triangles_at_row_changes,
    &SurfaceReport::triangles_at_waiting_vertices,
    &SurfaceReport::triangles_closing_gaps,
    &SurfaceReport::seed_shots_over_budget,
};
constexpr double StageTimes::*kStageTimes[] = {
    &StageTimes::alpha,  &StageTimes::rip,     &StageTimes::advance, &StageTimes::adapt,
    &StageTimes::stitch, &StageTimes::quality, &StageTimes::total, &StageTimes::gaps};
constexpr double StepRecord::*kStepFigures[] = {&StepRecord::h_min, &StepRecord::h_max,
                                                &StepRecord::orthogonality_mean,
                                                &StepRecord::orthogonality_max};

void write_report(ByteWriter& out, const SurfaceReport& r) {
  out.u8(static_cast<std::uint8_t>(r.stop_reason));
  out.i32(r.steps);
  for (const auto count : kReportCounts) out.u64(r.*count);
  out.f64(r.timeline_step);
  out.u8(r.closed_seed);
  out.u8(r.closed_front_opened);
  out.f64(r.closed_log_product);
  out.f64(r.seed_shot_time_limit);
  out.u64(r.per_step.size());
  for (const StepRecord& s : r.per_step) {
    out.i32(s.step);
    out.u64(s.fronts);
    out.u64(s.front_vertices);
    for (const auto figure : kStepFigures) out.f64(s.*figure);
  }
  for (const auto time : kStageTimes) out.f64(r.times.*time);
  out.u8(r.complete);
  out.text(r.message);
}

SurfaceReport read_report(ByteReader& in) {
  SurfaceReport r;
  const std::uint8_t reason = in.u8();
  if (reason > static_cast<std::uint8_t>(StopReason::end_time))
    in.fail("stop reason " + std::to_string(reason) + " is not one this version knows");
  r.stop_reason = static_cast<StopReason>(reason);
  r.steps = in.i32();
  for (const auto count : kReportCounts) r.*count = in.u64();
  r.timeline_step = in.f64();
  r.closed_seed = in.u8() != 0;
  r.closed_front_opened = in.u8() != 0;
  r.closed_log_product = in.f64();
  r.seed_shot_time_limit = in.f64();
  const std::uint64_t steps = in.count(4 + 2 * 8 + 4 * 8);
  r.per_step.resize(steps);
  for (StepRecord& s : r.per_step) {
    s.step = in.i32();
    s.fronts = in.u64();
    s.front_vertices = in.u64();
    for (const auto figure : kStepFigures) s.*figure = in.f64();
  }
  for (const auto time : kStageTimes) r.times.*time = in.f64();
  r.complete = in.u8() != 0;
  r.message = in.text();
  return r;
}

}  // namespace

void write_mesh_state(ByteWriter& out, const Mesh& mesh) {
  write_vec3s(out, mesh.positions);
  out.u64(mesh.faces.size());
  for (const Face& f : mesh.faces) {
    out.u8(f.size);
    for (std::int32_t v : f.v) out.i32(v);
  }
  out.array(mesh.time);
  out.array(mesh.alpha);
  out.array(mesh.s);
  out.array(mesh.error);
  out.array(mesh.front_id);
  out.array(mesh.step);
  out.array(mesh.release_time);
  out.array(mesh.age);
  out.array(mesh.speed);
  out.array(mesh.particle_id);
}

Mesh read_mesh_state(ByteReader& in) {
  Mesh mesh;
  read_vec3s(in, mesh.positions);
  const std::uint64_t faces = in.count(1 + 4 * 4);
  const auto vertices = static_cast<std::int64_t>(mesh.positions.size());
  mesh.faces.resize(faces);
  for (Face& f : mesh.faces) {
    f.size = in.u8();
    if (f.size != 3 && f.size != 4) in.fail("a face of " + std::to_string(f.size) + " vertices");
    for (std::int32_t& v : f.v) v = in.i32();
    for (int k = 0; k < f.size; ++k)
      if (f.v[static_cast<std::size_t>(k)] < 0 || f.v[static_cast<std::size_t>(k)] >= vertices)
        in.fail("a face names vertex " + std::to_string(f.v[static_cast<std::size_t>(k)]) + " of " +
                std::to_string(vertices));
  }
  in.array(mesh.time);
  in.array(mesh.alpha);
  in.array(mesh.s);
  in.array(mesh.error);
  in.array(mesh.front_id);
  in.array(mesh.step);
  in.array(mesh.release_time);
  in.array(mesh.age);
  in.array(mesh.speed);
  in.array(mesh.particle_id);
  const auto n = mesh.positions.size();
  for (const std::size_t size : {mesh.time.size(), mesh.alpha.size(), mesh.s.size(),
                                 mesh.error.size(), mesh.front_id.size(), mesh.step.size()})
    if (size != n)
      in.fail("a vertex attribute of " + std::to_string(size) + " values for " + std::to_string(n) +
              " vertices");
  return mesh;
}

template <int N>
void write_engine_state(ByteWriter& out, const EngineState<N>& state) {
  out.u8(N);
  out.u64(state.fronts.size());
  for (const Front<N>& f : state.fronts) {
    out.u8(f.closed);
    out.i32(f.id);
    out.u64(f.v.size());
    for (const FrontVertex<N>& fv : f.v) {
      for (int a = 0; a < N; ++a) out.f64(fv.x[a]);
      for (int a = 0; a < N; ++a) out.f64(fv.anchor[a]);
      out.f64(fv.s);
      out.f64(fv.t);
      out.i32(fv.mesh);
      out.i32(fv.origin);
      out.u8(fv.seed_misses);
    }
  }
  out.i32(state.step);
  out.u8(state.died_outside);
  out.i32(state.next_front_id);
  out.f64(state.elapsed_seconds);
  write_mesh_state(out, state.mesh);
  write_report(out, state.report);
}

template <int N>
EngineState<N> read_engine_state(ByteReader& in) {
  EngineState<N> state;
  const std::uint8_t n = in.u8();
  if (n != N)
    in.fail("a state in R^" + std::to_string(n) + " where R^" + std::to_string(N) +
            " was expected");
  const std::uint64_t fronts = in.count(1 + 4 + 8);
  state.fronts.resize(fronts);
  for (Front<N>& f : state.fronts) {
    f.closed = in.u8() != 0;
    f.id = in.i32();
    f.v.resize(in.count((2 * N + 2) * 8 + 2 * 4 + 1));
    for (FrontVertex<N>& fv : f.v) {
      for (int a = 0; a < N; ++a) fv.x[a] = in.f64();
      for (int a = 0; a < N; ++a) fv.anchor[a] = in.f64();
      fv.s = in.f64();
      fv.t = in.f64();
      fv.mesh = in.i32();
      fv.origin = in.i32();
      fv.seed_misses = in.u8();
    }
  }
  state.step = in.i32();
  state.died_outside = in.u8() != 0;
  state.next_front_id = in.i32();
  state.elapsed_seconds = in.f64();
  state.mesh = read_mesh_state(in);
  state.report = read_report(in);
  const auto vertices = static_cast<std::int64_t>(state.mesh.vertex_count());
  for (const Front<N>& f : state.fronts)
    for (const FrontVertex<N>& fv : f.v)
      if (fv.mesh < -1 || fv.mesh >= vertices)
        in.fail("a front vertex stands for mesh vertex " + std::to_string(fv.mesh) + " of " +
                std::to_string(vertices));
  return state;
}

template void write_engine_state<3>(ByteWriter&, const EngineState<3>&);
template void write_engine_state<4>(ByteWriter&, const EngineState<4>&);
template EngineState<3> read_engine_state<3>(ByteReader&);
template EngineState<4> read_engine_state<4>(ByteReader&);

}  // namespace orthofront::io
