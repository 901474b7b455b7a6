// `orthofront-bench gpu-streak`: a streak surface of millions of particles moved on the GPU
// through a series streamed from disk, the series several times larger than the steps the device
// may keep, against its floors measured in the same run: the I/O floor (every step read and
// decoded once through the cache, nothing computed), the GPU compute (the kernels' time) and the
// host-to-device copy rate of pinned memory (PCIe). Prints a table and JSON.
#include <tbb/info.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <span>

#include "cli/bench_series_file.h"
#include "cli/commands.h"
#include "orthofront/error.h"
#include "orthofront/field/unsteady.h"
#include "orthofront/io/hdf5_layout.h"
#include "orthofront/io/mesh_series.h"
#include "orthofront/spacetime/brick_cache.h"
#include "orthofront/spacetime/bulk_flow_map.h"
#include "orthofront/spacetime/sampled_series.h"
#include "orthofront/spacetime/streak_surface.h"

namespace orthofront::cli {

namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

struct BenchGpuStreakArgs {
  std::string field = "unsteady-abc";
  int resolution = 192;
  int steps = 41;               // over t in [0, 4]
  double edge = 0.0037;  // over 10 million particles at four releases a break
  std::string seed = "1,2,3:5,2,3";
  double release_end = 1.5;
  int frames = 3;               // evenly up to t = 3
  std::string host_budget = "4GiB";
  double data_over_device = 4;  // series bytes / device budget for steps
  std::string device = "auto";
  std::string keep;
  std::string out;              // write the frames here (DIR/NAME.pvd), as `streak` does
  bool frames_in_line = false;  // the baseline: finish frames before the particles move on
  bool per_call = false;        // the baseline: every particle up and down each interval
  bool in_turn = false;         // the baseline: refinement waits for the particles' move
  int releases_per_break = 4;  // 1: the baseline, a refinement at every release
};

}  // namespace

void add_bench_gpu_streak_command(CLI::App& app) {
  auto a = std::make_shared<BenchGpuStreakArgs>();
  CLI::App* c = app.add_subcommand(
      "gpu-streak",
      "Benchmark a streak surface of millions of particles on the GPU through a streamed series "
      "larger than the device's step budget, against the I/O floor, the GPU compute and PCIe");
  c->add_option("--field", a->field, "Unsteady 3D analytic field sampled into the series")->capture_default_str();
  c->add_option("--resolution", a->resolution, "Grid points per axis")->capture_default_str();
  c->add_option("--steps", a->steps, "Time steps over t in [0, 4]")->capture_default_str();
  c->add_option("--edge", a->edge, "Target edge length (smaller: more particles)")->capture_default_str();
  c->add_option("--seed", a->seed, "Seed segment x0,y0,z0:x1,y1,z1")->capture_default_str();
  c->add_option("--release-end", a->release_end, "Release from t = 0 to this")->capture_default_str();
  c->add_option("--frames", a->frames, "Observation times, evenly up to t = 3")->capture_default_str();
  c->add_option("--releases-per-break", a->releases_per_break,
                "Rows released per refinement (those between move to the next break in one call)")
      ->capture_default_str();
  c->add_option("--cache-budget", a->host_budget, "Host cache budget")->capture_default_str();
  c->add_option("--data-over-device", a->data_over_device,
                "Series bytes over the bytes of steps the device may keep")->capture_default_str();
  c->add_option("--device", a->device, "cuda, cpu or auto (cuda where present)")->capture_default_str();
  c->add_option("--keep", a->keep, "Write the series here and keep it (default: a temporary file)");
  c->add_option("--out", a->out, "Also write the frames, as `streak` does (DIR/NAME.pvd)");
  c->add_flag("--frames-in-line", a->frames_in_line,
              "Finish each frame (quality, writing) before the particles move on: the baseline of "
              "finishing frames aside");
  c->add_flag("--particles-per-call", a->per_call,
              "Send every particle's state to the backend and back each interval: the baseline of "
              "particles kept on the device");
  c->add_flag("--in-turn", a->in_turn,
              "Refine the rows after the particles' move instead of while the next one runs: the "
              "baseline of overlapped advection");
  c->callback([a]() {
    const auto flow = make_unsteady_field(a->field);
    if (flow->dimension() != 3) throw InvalidArgument("orthofront-bench gpu-streak: --field must be a 3D flow");
    if (a->resolution < 8 || a->resolution > 1024 || a->steps < 8 || a->frames < 1 ||
        !(a->edge > 0) || !(a->release_end > 0 && a->release_end < 3) || !(a->data_over_device >= 1))
      throw InvalidArgument("orthofront-bench gpu-streak: need --resolution in [8, 1024], --steps >= 8, "
                            "--frames >= 1, --edge > 0, --release-end in (0, 3), "
                            "--data-over-device >= 1");
    double sx0, sy0, sz0, sx1, sy1, sz1;
    if (std::sscanf(a->seed.c_str(), "%lf,%lf,%lf:%lf,%lf,%lf", &sx0, &sy0, &sz0, &sx1, &sy1, &sz1) != 6)
      throw InvalidArgument("orthofront-bench gpu-streak: --seed '" + a->seed + "' is not x0,y0,z0:x1,y1,z1");
    advect::Device device = advect::parse_device(a->device);
    std::string why;
    const bool cuda = device != advect::Device::cpu && advect::cuda_available(&why);
    if (device == advect::Device::cuda && !cuda) throw InvalidArgument("orthofront-bench gpu-streak --device cuda: " + why);
    if (device == advect::Device::auto_select) device = cuda ? advect::Device::cuda : advect::Device::cpu;

    // The series on disk (bricked, lz4), as `generate` writes it.
    const spacetime::SampledTimeSeries sampled(
        *flow, spacetime::uniform_grid(flow->domain(), 3, a->resolution),
        spacetime::uniform_times(0, 4, static_cast<std::size_t>(a->steps - 1)));
    const BenchSeriesFile series_file(a->keep, "orthofront-bench-gpu-streak");
    const std::filesystem::path& file = series_file.path();
    const auto w0 = Clock::now();
    {
      io::Hdf5WriteOptions w;
      w.codec = io::Hdf5Codec::lz4;
      w.zero_is_no_data = false;
      w.xdmf = false;
      std::vector<double> times;
      for (std::size_t k = 0; k < sampled.step_count(); ++k) times.push_back(sampled.time(k));
      io::Hdf5SeriesWriter writer(file, sampled.geometry(), 3, times, w);
      std::vector<float> values(sampled.step_floats());
      for (std::size_t k = 0; k < sampled.step_count(); ++k) {
        sampled.sample(k, values.data());
        writer.write_step(values);
      }
      writer.commit();
    }
    const double write_seconds = since(w0);
    const auto series = io::open_hdf5_series(file);
    const std::size_t step_bytes = sampled.step_floats() * sizeof(float);
    const std::size_t data_bytes = step_bytes * sampled.step_count();
    const auto device_bytes = static_cast<std::size_t>(static_cast<double>(data_bytes) / a->data_over_device);
    spacetime::CacheOptions co;
    co.budget_bytes = spacetime::parse_bytes(a->host_budget);

    spacetime::StreakOptions o;
    o.release_begin = 0;
    o.release_end = a->release_end;
    for (int i = 1; i <= a->frames; ++i) o.frames.push_back(3.0 * i / a->frames);
    o.edge = a->edge;
    o.insertion = spacetime::ParticleInsertion::interpolate;  // every step read once
    o.device = device;
    o.device_bytes = device_bytes;
    o.finish_frames_aside = !a->frames_in_line;
    o.resident_particles = !a->per_call;
    o.overlap_advection = !a->in_turn;
    o.releases_per_break = a->releases_per_break;
    const double last = o.frames.back();
    // Where the time goes along the run: six spans of simulated time (the release, then the
    // particles moving on), from the progress calls after each interval.
    constexpr int kSpans = 6;
    struct Span {
      std::size_t intervals = 0, particles = 0;
      double seconds = 0, advect = 0, refine = 0, frames = 0;
    };
    std::array<Span, kSpans> spans{};
    spacetime::StreakProgress previous;
    o.progress = [&](const spacetime::StreakProgress& p) {
      const int k = std::clamp(static_cast<int>(std::ceil(p.t / last * kSpans)) - 1, 0, kSpans - 1);
      Span& sp = spans[static_cast<std::size_t>(k)];
      ++sp.intervals;
      sp.particles = std::max(sp.particles, p.particles);
      sp.seconds += p.elapsed_seconds - previous.elapsed_seconds;
      sp.advect += p.advect_seconds - previous.advect_seconds;
      sp.refine += p.refine_seconds - previous.refine_seconds;
      sp.frames += p.frame_seconds - previous.frame_seconds;
      previous = p;
      return true;
    };
    std::size_t steps_used = 0;
    while (steps_used < sampled.step_count() && sampled.time(steps_used) < last) ++steps_used;
    steps_used = std::min(steps_used + 1, sampled.step_count());

    // I/O floor: every step the run reads, read and decoded once into the same cache, nothing
    // gathered or computed: a step's bricks pinned a group at a time (as the backend gathers
    // them), every later step requested ahead (the cache reads as far ahead as its prefetch share
    // holds, no less than the run asks for). Read ahead one step only and gathered into fresh
    // memory, the 256^3 series took longer than the whole streak surface run beside it.
    double io_floor = 0;
    spacetime::CacheStatistics floor_cache;
    {
      spacetime::BrickCache cache(*series, co);
      const auto t0 = Clock::now();
      for (std::size_t k = 0; k < steps_used; ++k) {
        cache.prefetch(cache.step_keys(k + 1, steps_used));
        const std::vector<spacetime::BrickKey> keys = cache.step_keys(k, k + 1);
        for (std::size_t first = 0; first < keys.size(); first += spacetime::CachedSteps::kGatherBricks) {
          const std::size_t end = std::min(keys.size(), first + spacetime::CachedSteps::kGatherBricks);
          static_cast<void>(cache.acquire_all(std::span<const spacetime::BrickKey>(keys).subspan(first, end - first)));
        }
      }
      io_floor = since(t0);
      floor_cache = cache.statistics();
    }
    const double pcie = cuda ? advect::cuda_upload_rate(step_bytes) : 0;

    spacetime::BrickCache cache(*series, co);
    const SeedCurve seed = SeedCurve::line(Vec3(sx0, sy0, sz0), Vec3(sx1, sy1, sz1));
    std::size_t last_vertices = 0;
    std::unique_ptr<io::MeshSeriesWriter> writer;
    if (!a->out.empty()) writer = std::make_unique<io::MeshSeriesWriter>(a->out);
    const spacetime::StreakReport r = spacetime::build_streak_surface(
        cache, seed, o, [&](const spacetime::StreakFrame& f) {
          last_vertices = f.mesh.vertex_count();
          if (writer) writer->add_frame(f.mesh, f.time);
        });
    const advect::AdvectionStatistics& b = r.bulk;
    const double floor = std::max(io_floor, b.compute_seconds);
    const double h2d = b.upload_seconds > 0 ? static_cast<double>(b.bytes_uploaded) / b.upload_seconds : 0;

    nlohmann::json j = {
        {"benchmark", "bench-gpu-streak"},
        {"field", a->field},
        {"grid", a->resolution},
        {"steps", sampled.step_count()},
        {"steps_read", steps_used},
        {"series_bytes", data_bytes},
        {"step_bytes", step_bytes},
        {"write_seconds", write_seconds},
        {"host_cache_budget_bytes", co.budget_bytes},
        {"device_step_budget_bytes", device_bytes},
        {"backend", r.device},
        {"particles_resident", !a->per_call},
        {"advection_overlapped", !a->per_call && !a->in_turn},
        {"catch_up_calls", r.catch_up_calls},
        {"catch_up_particles", r.catch_up_particles},
        {"cpu_threads", tbb::info::default_concurrency()},
        {"complete", r.complete},
        {"message", r.message},
        {"max_particles", r.max_particles},
        {"last_frame_vertices", last_vertices},
        {"particle_steps", r.particle_steps},
        {"intervals", r.intervals},
        {"releases_per_break", a->releases_per_break},
        {"last_frame",
         r.frames.empty() ? nlohmann::json()
                          : nlohmann::json{{"rows", r.frames.back().rows},
                                           {"quad_share", r.frames.back().quality.quad_share},
                                           {"max_edge_over_edge", r.frames.back().max_edge / a->edge},
                                           {"triangle_min_angle_median",
                                            r.frames.back().quality.triangle_min_angle_median},
                                           {"folds", r.frames.back().quality.folds},
                                           {"degenerate_faces", r.frames.back().quality.degenerate_faces}}},
        {"seconds",
         {{"total", r.total_seconds},
          {"advect", r.advect_seconds},
          {"catch_up", r.catch_up_seconds},
          {"catch_up_calls", r.catch_up_call_seconds},
          {"take", r.take_seconds},
          {"release_calls", r.release_call_seconds},
          {"refine", r.refine_seconds},
          {"coarsen", r.coarsen_seconds},
          {"frames", r.frame_seconds},
          {"frames_finish", r.frame_finish_seconds},
          {"wait", r.wait_seconds},
          {"io_floor", io_floor},
          {"io_floor_reading", floor_cache.read_seconds},
          {"io_floor_decoding", floor_cache.decode_seconds},
          {"reading", r.io_seconds},
          {"decoding", r.decode_seconds},
          {"gpu_compute", b.compute_seconds},
          {"backend_calls", b.total_seconds},
          {"uploads", b.upload_seconds},
          {"host_staging", b.host_seconds},
          {"pinned_memory", b.pinned_seconds},
          {"downloads", b.download_seconds},
          {"batch_calls", r.bulk_batch.total_seconds},
          {"batch_kernels", r.bulk_batch.compute_seconds},
          {"batch_downloads", r.bulk_batch.download_seconds}}},
        {"units_read_at_once", floor_cache.live_tokens},
        {"bytes_uploaded", b.bytes_uploaded},
        {"bytes_downloaded", b.bytes_downloaded},
        {"steps_uploaded", b.steps_loaded},
        {"steps_read_ahead", b.steps_read_ahead},
        {"h2d_bytes_per_second", h2d},
        {"pcie_pinned_bytes_per_second", pcie},
        {"total_over_floor", r.total_seconds / floor}};
    for (int k = 0; k < kSpans; ++k) {
      const Span& sp = spans[static_cast<std::size_t>(k)];
      j["spans"].push_back({{"t_end", last * (k + 1) / kSpans},
                            {"intervals", sp.intervals},
                            {"max_particles", sp.particles},
                            {"seconds", sp.seconds},
                            {"advect", sp.advect},
                            {"refine", sp.refine},
                            {"frames", sp.frames}});
    }
    std::printf("orthofront-bench gpu-streak: %s on %d^3, %zu steps over [0, 4] (%.2f GiB, %.0f MiB a step; "
                "%zu read up to the last frame); host cache %s; the device keeps at most %.2f GiB "
                "of steps (series / %.3g)\nbackend: %s; %d CPU threads\n",
                a->field.c_str(), a->resolution, sampled.step_count(),
                static_cast<double>(data_bytes) / (1u << 30), static_cast<double>(step_bytes) / (1u << 20),
                steps_used, a->host_budget.c_str(), static_cast<double>(device_bytes) / (1u << 30),
                a->data_over_device, r.device.c_str(), tbb::info::default_concurrency());
    std::printf("streak: seed %s, release 0 -> %g, %d frames up to t = 3, edge %g, interpolated "
                "insertion: %zu particles at most, %zu in the last frame%s; particles %s\n\n",
                a->seed.c_str(), a->release_end, a->frames, a->edge, r.max_particles, last_vertices,
                r.complete ? "" : (" (incomplete: " + r.message + ")").c_str(),
                a->per_call ? "up and down every interval"
                : a->in_turn ? "kept by the backend, refined in turn"
                             : "kept by the backend, moving on while the rows are refined");
    std::printf("%-44s %10s\n", "", "seconds");
    std::printf("%-44s %10.3f\n", "end to end (streak surface)", r.total_seconds);
    std::printf("%-44s %10.3f\n", a->per_call || a->in_turn ? "  advection (bulk calls)"
                                                             : "  advection (waits for moves, catch-up)",
                r.advect_seconds);
    if (r.catch_up_calls > 0)
      std::printf("%-44s %10.3f  (%zu calls, %zu particles; %.3f s on their thread)\n",
                  "    waiting for the catch-up, placing it", r.catch_up_seconds, r.catch_up_calls,
                  r.catch_up_particles, r.catch_up_call_seconds);
    std::printf("%-44s %10.3f\n", "    taking the positions into the rows", r.take_seconds);
    if (r.release_calls > 0)
      std::printf("%-44s %10.3f  (%zu calls, %zu rows)\n", "    moving rows released between breaks",
                  r.release_call_seconds, r.release_calls, r.rows_released_between);
    std::printf("%-44s %10.3f  (%zu intervals)\n", "    in the backend (staging, transfers, kernels)", b.total_seconds, r.intervals);
    if (r.catch_up_calls > 0)
      std::printf("%-44s %10.3f  (%s %.3f s, downloads %.3f s)\n", "      of which batch calls (catch-ups)",
                  r.bulk_batch.total_seconds, cuda ? "kernels" : "loops", r.bulk_batch.compute_seconds,
                  r.bulk_batch.download_seconds);
    std::printf("%-44s %10.3f\n", "  refinement", r.refine_seconds);
    std::printf("%-44s %10.3f\n", "    of which coarsening", r.coarsen_seconds);
    std::printf("%-44s %10.3f\n", a->frames_in_line ? "  frames (finished in line)"
                                                      : "  frames (vertices, faces; waits)",
                r.frame_seconds);
    std::printf("%-44s %10.3f\n", a->frames_in_line ? "    of which quality" : "  frames finished aside (quality)",
                r.frame_finish_seconds);
    std::printf("%-44s %10.3f  (reading %.3f s, decoding %.3f s, summed over threads)\n", "  waiting for data",
                r.wait_seconds, r.io_seconds, r.decode_seconds);
    std::printf("%-44s %10.3f  (reading %.3f s, decoding %.3f s, summed; %zu units at once)\n",
                "I/O floor (read + decode every step once)", io_floor, floor_cache.read_seconds,
                floor_cache.decode_seconds, floor_cache.live_tokens);
    std::printf("%-44s %10.3f\n", cuda ? "GPU compute (kernels)" : "compute (CPU loops)",
                b.compute_seconds);
    std::printf("%-44s %10.3f  (%.2f GiB, %.1f GB/s; pinned PCIe %.1f GB/s)\n", "uploads (steps)",
                b.upload_seconds, static_cast<double>(b.bytes_uploaded) / (1u << 30), h2d / 1e9, pcie / 1e9);
    if (cuda)
      std::printf("%-44s %10.3f  (%.2f GiB, %.1f GB/s)\n", "downloads (particles)", b.download_seconds,
                  static_cast<double>(b.bytes_downloaded) / (1u << 30),
                  b.download_seconds > 0 ? static_cast<double>(b.bytes_downloaded) / b.download_seconds / 1e9 : 0.0);
    std::printf("%-44s %10.3f  (%zu of %zu steps read ahead, between calls)\n",
                "host work in the backend (staging, changes)", b.host_seconds, b.steps_read_ahead, b.steps_loaded);
    if (cuda)
      std::printf("%-44s %10.3f  (growing particle staging and mirrors; kept for reuse)\n",
                  "page-locked memory made in the calls", b.pinned_seconds);
    std::printf("%-44s %10.2f  (goal <= 1.15)\n", "end to end / max(I/O floor, GPU compute)",
                r.total_seconds / floor);
    if (!r.frames.empty()) {
      const spacetime::StreakFrameRecord& f = r.frames.back();
      std::printf("\nlast frame: %zu rows, %.1f %% quads, longest edge %.2f edge lengths, median "
                  "smallest triangle angle %.1f deg, %zu folds, %zu degenerate faces; %d release%s "
                  "per break\n",
                  f.rows, 100 * f.quality.quad_share, f.max_edge / a->edge,
                  f.quality.triangle_min_angle_median, f.quality.folds, f.quality.degenerate_faces,
                  a->releases_per_break, a->releases_per_break == 1 ? "" : "s");
    }
    std::printf("\nframes (seconds: vertices and faces, the particles waiting; then quality and "
                "hand-over%s)\n%-8s %12s %12s %9s %9s\n",
                a->frames_in_line ? "" : ", aside", "t", "vertices", "faces", "built", "finished");
    j["frames"] = nlohmann::json::array();
    for (const spacetime::StreakFrameRecord& f : r.frames) {
      std::printf("%-8g %12zu %12zu %9.3f %9.3f\n", f.time, f.vertices, f.faces, f.build_seconds,
                  f.finish_seconds);
      j["frames"].push_back({{"time", f.time},
                             {"vertices", f.vertices},
                             {"faces", f.faces},
                             {"build_seconds", f.build_seconds},
                             {"finish_seconds", f.finish_seconds}});
    }
    std::printf("\nalong the run (seconds; frames: built in line, waits)\n%-12s %9s %12s %9s %9s %9s %9s\n",
                "t", "intervals", "particles", "total", "advect", "refine", "frames");
    for (int k = 0; k < kSpans; ++k) {
      const Span& sp = spans[static_cast<std::size_t>(k)];
      const std::string span = std::to_string(last * k / kSpans).substr(0, 4) + " - " +
                               std::to_string(last * (k + 1) / kSpans).substr(0, 4);
      std::printf("%-12s %9zu %12zu %9.3f %9.3f %9.3f %9.3f\n", span.c_str(), sp.intervals,
                  sp.particles, sp.seconds, sp.advect, sp.refine, sp.frames);
    }
    std::cout << j.dump(1) << "\n";
  });
}

}  // namespace orthofront::cli
