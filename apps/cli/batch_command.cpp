// `orthofront batch JOB`: many surfaces from one job file. Surfaces over the same data advance
// together (the one that lags in time steps first), so a streamed series is read once for all of
// them through one cache; unfinished surfaces are checkpointed and a killed job resumes.
#include <unistd.h>

#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <tuple>

#include "cli/batch_checkpoint.h"
#include "cli/batch_job.h"
#include "cli/commands.h"
#include "orthofront/io/open_field.h"
#include "jobs/edge_default.h"
#include "jobs/output_notes.h"
#include "jobs/process_memory.h"
#include "cli/progress_bar.h"
#include "jobs/seed_spec.h"
#include "jobs/streak_report.h"
#include "cli/surface_job.h"
#include "cli/work_sharing.h"
#include "orthofront/error.h"
#include "orthofront/io/atomic_file.h"
#include "orthofront/io/error.h"
#include "orthofront/io/input_files.h"
#include "orthofront/stage_timer.h"
#include "orthofront/io/mesh_io.h"
#include "orthofront/io/mesh_series.h"
#include "orthofront/io/report_json.h"
#include "orthofront/spacetime/path_command_json.h"
#include "orthofront/spacetime/path_surface.h"
#include "orthofront/spacetime/streak_surface.h"

namespace orthofront::cli {

using namespace jobs;

namespace {

using json = nlohmann::json;
using Clock = std::chrono::steady_clock;

struct BatchArgs {
  std::string job, out;
  bool resume = false, restart = false, quiet = false;
  double checkpoint_every = -1;  // < 0: the job file's
  int fail_after_steps = -1;     // tests: stop as if killed after this many front steps
  int threads = 0;               // 0: every core
  std::string device;            // empty: per vertex; else cpu, cuda or auto
  std::string device_memory;     // empty: half the device's free memory
  bool no_merge_fronts = false;  // the fronts' calls take turns unmerged (a baseline)
  std::size_t device_calls = 0;  // backend calls at once (0: what the backend allows)
};

std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

std::filesystem::path output_path(const BatchJob& job, const SurfaceSpec& s) {
  return job.out / (s.name + "." + s.format);
}

/// One surface of the run, between front steps.
class SurfaceTask {
 public:
  explicit SurfaceTask(const SurfaceSpec& spec) : spec_(spec) {}
  virtual ~SurfaceTask() = default;
  SurfaceTask(const SurfaceTask&) = delete;
  SurfaceTask& operator=(const SurfaceTask&) = delete;

  const SurfaceSpec& spec() const { return spec_; }
  bool ready() const { return ready_; }
  /// Where the surface stands in the pass: the earliest time on its front (path surfaces) or
  /// its steps (stream surfaces). A round steps the surfaces within step_span() of the least.
  virtual double lag_key() = 0;
  virtual double step_span() const = 0;
  /// Streamed path surfaces of one pass: the front as the shared band sees it.
  virtual void front_samples(std::vector<spacetime::FrontSample>&) {}
  virtual spacetime::BandPrediction prediction() const { return {}; }
  /// One front step, then the check whether another is due.
  virtual void step() = 0;
  virtual SurfaceState state() const = 0;
  /// The finished surface: its mesh and report (JSON, with the summary fields).
  virtual std::pair<Mesh, json> finish() = 0;

 protected:
  SurfaceSpec spec_;
  bool ready_ = false;
  int resumed_at_step_ = -1;  ///< the front step a checkpoint resumed it at (-1: not resumed)
  int seed_count_ = 0;
  EdgeChoice edge_;  ///< ℓ and where it came from (the key, or the grid's cell size)

 public:
  int resumed_at_step() const { return resumed_at_step_; }
  int seed_count() const { return seed_count_; }
};

class StreamTask final : public SurfaceTask {
 public:
  StreamTask(const SurfaceSpec& spec, const Field3& field, const EngineState<3>* resume)
      : SurfaceTask(spec) {
    const SeedCurve curve = parse_seed(spec.seed).translated(spec.offset);
    // As `stream`: without an edge, a grid's cell size.
    SurfaceJob job = stream_arguments(spec);
    job.edge_given = spec.given("edge");
    seed_count_ = job.seed_count;
    seed_ = prepare_stream_seed(field, curve, job);
    edge_ = {job.options.edge, job.edge_source};
    builder_ = resume ? std::make_unique<SurfaceBuilder<3>>(field, seed_, job.options, *resume)
                      : std::make_unique<SurfaceBuilder<3>>(field, seed_, job.options);
    if (resume) resumed_at_step_ = resume->step;
    ready_ = builder_->next();
  }
  double lag_key() override { return builder_->steps_done(); }
  double step_span() const override { return 0.5; }
  void step() override {
    builder_->step();
    ready_ = builder_->next();
  }
  SurfaceState state() const override { return builder_->state(); }
  std::pair<Mesh, json> finish() override {
    SurfaceResult r = builder_->finish();
    json report = io::to_json(r.report);
    add_edge_keys(report, edge_);
    report["complete"] = r.report.complete && r.report.stop_reason != StopReason::vertex_budget;
    return {std::move(r.mesh), std::move(report)};
  }

 private:
  Seed<3> seed_;
  std::unique_ptr<SurfaceBuilder<3>> builder_;
};

class PathTask final : public SurfaceTask {
 public:
  /// From an in-memory flow, or one of the surfaces of a pass over `shared`.
  PathTask(const SurfaceSpec& spec, const UnsteadyField& flow, const spacetime::PathState* resume)
      : SurfaceTask(spec), args_(path_arguments(spec)) {
    edge_ = choose_edge(args_.options.edge, spec.given("edge"), nullptr);
    seed_count_ = args_.seed_count;
    builder_ = std::make_unique<spacetime::PathSurfaceBuilder>(flow, seed(), args_.seed_count,
                                                               options(), resume);
    if (resume) resumed_at_step_ = resumed_step(*resume);
    ready_ = builder_->next();
  }
  PathTask(const SurfaceSpec& spec, spacetime::StreamedField& shared,
           spacetime::BrickCache& cache, const spacetime::PathState* resume,
           std::shared_ptr<spacetime::SharedBulkAdvance> bulk)
      : SurfaceTask(spec), args_(path_arguments(spec)), bulk_(std::move(bulk)) {
    // As `path`: without an edge, the series' cell size.
    edge_ = choose_edge(args_.options.edge, spec.given("edge"), &cache.series().geometry());
    args_.options.edge = edge_.edge;
    seed_count_ = args_.seed_count;
    builder_ = std::make_unique<spacetime::PathSurfaceBuilder>(shared, cache, seed(),
                                                               args_.seed_count, options(), resume);
    if (resume) resumed_at_step_ = resumed_step(*resume);
    ready_ = builder_->next();
  }
  double lag_key() override { return builder_->front_time(); }
  double step_span() const override { return builder_->step_time(); }
  void front_samples(std::vector<spacetime::FrontSample>& out) override {
    builder_->front_samples(out);
  }
  spacetime::BandPrediction prediction() const override { return builder_->prediction(); }
  void step() override {
    builder_->step();
    ready_ = builder_->next();
  }
  SurfaceState state() const override { return builder_->state(); }
  std::pair<Mesh, json> finish() override {
    spacetime::PathSurfaceResult r = builder_->finish();
    json report = io::to_json(r.report);
    add_edge_keys(report, edge_);
    report["path"] = spacetime::to_json(r.path);
    // As `path` writes them: a 2D flow's surface in (x, y, c t).
    report["path"]["positions"] = spacetime::path_positions(r, args_.flat);
    spacetime::place_for_output(r, args_.flat);
    report["complete"] = r.report.complete;
    return {std::move(r.mesh), std::move(report)};
  }

 private:
  static int resumed_step(const spacetime::PathState& state) {
    return std::visit([](const auto& e) { return e.step; }, state.engine);
  }
  SeedCurve seed() const { return parse_seed(spec_.seed).translated(spec_.offset); }
  spacetime::PathSurfaceOptions options() const {
    spacetime::PathSurfaceOptions o = path_options(args_);
    o.shared_bulk = bulk_;
    return o;
  }
  PathArgs args_;  // `path`'s arguments with the surface's options
  std::shared_ptr<spacetime::SharedBulkAdvance> bulk_;  // the pass's bulk front advance, or null
  std::unique_ptr<spacetime::PathSurfaceBuilder> builder_;
};

/// Surfaces that read the same data: one steady field, one analytic flow, or one series through
/// one cache.
struct Group {
  std::string field;
  SurfaceKind kind = SurfaceKind::path;
  bool streamed = false;
  std::vector<std::size_t> members;  // indices into job.surfaces
};

std::vector<Group> group_surfaces(const BatchJob& job) {
  std::vector<Group> groups;
  std::map<std::pair<std::string, int>, std::size_t> index;
  for (std::size_t i = 0; i < job.surfaces.size(); ++i) {
    const SurfaceSpec& s = job.surfaces[i];
    const auto key = std::make_pair(s.field, static_cast<int>(s.kind));
    auto [it, added] = index.emplace(key, groups.size());
    if (added) {
      Group g;
      g.field = s.field;
      g.kind = s.kind;
      g.streamed = s.kind == SurfaceKind::path && !is_unsteady_field_name(s.field);
      groups.push_back(std::move(g));
    }
    groups[it->second].members.push_back(i);
  }
  return groups;
}

json summary_row(const SurfaceSpec& s, const std::string& status, const json& report,
                 double seconds, const std::string& message, const std::string& output) {
  json row = {{"name", s.name}, {"kind", to_string(s.kind)}, {"status", status},
              {"seconds", seconds}, {"message", message}, {"output", output}};
  if (!report.is_null()) {
    if (report.contains("counts")) {
      row["vertices"] = report["counts"].value("vertices", 0);
      row["faces"] = report["counts"].value("faces", 0);
    }
    row["steps"] = report.value("steps", 0);
    row["stop_reason"] = report.value("stop_reason", std::string());
    row["resumed_at_step"] = report.value("resumed_at_step", -1);
    if (report.contains("path")) row["time_reached"] = report["path"].value("time_reached", 0.0);
    if (report.contains("quality")) {
      const json& q = report["quality"];
      row["quad_share"] = q.value("quad_share", 0.0);
      row["quad_angles_within_10"] = q.value("quad_angles_within_10deg", 0.0);
      row["folds"] = q.value("folds", 0);
      row["degenerate_faces"] = q.value("degenerate_faces", 0);
    }
  }
  return row;
}

std::string summary_table(const json& rows) {
  std::string out;
  char line[512];
  std::snprintf(line, sizeof line, "%-24s %-6s %-10s %9s %9s %6s %7s %6s %5s %8s\n", "surface",
                "kind", "status", "vertices", "faces", "steps", "quads%", "±10°%", "folds",
                "seconds");
  out += line;
  for (const json& r : rows) {
    std::snprintf(line, sizeof line, "%-24s %-6s %-10s %9lld %9lld %6lld %7.1f %6.1f %5lld %8.2f\n",
                  r.value("name", std::string()).c_str(), r.value("kind", std::string()).c_str(),
                  r.value("status", std::string()).c_str(), r.value("vertices", 0LL),
                  r.value("faces", 0LL), r.value("steps", 0LL), 100.0 * r.value("quad_share", 0.0),
                  100.0 * r.value("quad_angles_within_10", 0.0), r.value("folds", 0LL),
                  r.value("seconds", 0.0));
    out += line;
    if (const std::string m = r.value("message", std::string()); !m.empty())
      out += "    " + m + "\n";
  }
  return out;
}

class BatchRun {
 public:
  BatchRun(BatchJob job, const BatchArgs& args)
      : job_(std::move(job)), args_(args), checkpoints_(job_.out / ".checkpoint", job_.digest) {
    if (args.checkpoint_every >= 0) job_.checkpoint_every = args.checkpoint_every;
    rows_.resize(job_.surfaces.size());
  }

  void run() {
    const auto start = Clock::now();
    const std::unique_ptr<WorkSharing> sharing = start_work_sharing();
    const bool lead = sharing->rank() == 0;
    rank_ = sharing->rank();
    std::error_code ec;
    std::filesystem::create_directories(job_.out, ec);
    // Rank 0 checks and prepares the folder; the others wait for its word.
    std::optional<io::OutputLock> lock;
    std::string error;
    if (lead) {
      try {
        if (ec)
          throw io::IoError("cannot create the output folder '" + job_.out.string() + "': " +
                            ec.message());
        lock.emplace(job_.out / "summary.json");
        prepare_checkpoints();
      } catch (const std::exception& e) {
        error = e.what();
      }
    }
    error = sharing->broadcast(error);
    if (!error.empty()) {
      if (lead) throw InvalidArgument(error);
      return;  // rank 0 says why
    }
    last_checkpoint_ = Clock::now();
    // Work items: whole groups for one process (one pass over each data set); under MPI each
    // group in up to 2 K pieces, handed out as ranks free up.
    const std::vector<Group> items = work_items(sharing->size());
    try {
      for (long item; (item = sharing->next(static_cast<long>(items.size()))) >= 0;)
        run_group(items[static_cast<std::size_t>(item)]);
    } catch (const std::exception& e) {
      if (sharing->size() == 1) throw;
      std::fprintf(stderr, "orthofront: error (rank %d): %s\n", sharing->rank(), e.what());
      sharing->abort(2);
    }
    if (sharing->size() > 1) {
      // Each rank's passes, for rank 0's summary; every row is in its .done record.
      io::write_json(passes_, checkpoints_.folder() /
                                  ("passes-" + std::to_string(sharing->rank()) + ".json"));
      sharing->barrier();
      if (!lead) return;
      passes_ = json::array();
      for (int r = 0; r < sharing->size(); ++r) {
        const auto file = checkpoints_.folder() / ("passes-" + std::to_string(r) + ".json");
        for (json& p : json::parse(read_text(file))) {
          p["rank"] = r;
          passes_.push_back(std::move(p));
        }
        std::filesystem::remove(file, ec);
      }
      for (std::size_t i = 0; i < job_.surfaces.size(); ++i)
        if (auto row = checkpoints_.load_done(job_.surfaces[i].name)) rows_[i] = *row;
    }
    // Every surface has its row: the job is finished, the checkpoint holds only .done records.
    checkpoints_.start();
    json summary = {{"job", job_.file.string()},
                    {"name", job_.name},
                    {"surfaces", rows_},
                    {"seconds", seconds_since(start)},
                    {"resumed", args_.resume},
                    {"ranks", sharing->size()},
                    {"checkpoints_written", checkpoints_written_},
                    {"checkpoint_seconds", checkpoint_seconds_},
                    {"passes", passes_},
                    {"peak_rss_bytes", peak_rss_bytes()}};
    std::size_t failed = 0, incomplete = 0;
    for (const json& r : rows_) {
      failed += r["status"] == "failed";
      incomplete += r["status"] == "incomplete";
    }
    summary["failed"] = failed;
    summary["incomplete"] = incomplete;
    const std::string table = summary_table(rows_);
    io::AtomicFileSet files;
    io::write_json(summary, job_.out / "summary.json", files);
    files.add(job_.out / "summary.txt", [&](std::ofstream& out) { out << table; });
    files.commit();
    if (!args_.quiet) {
      std::printf("%s", table.c_str());
      std::printf("Batch %s: %zu surfaces, %zu failed, %zu incomplete, %.2f s. Wrote %s and %s\n",
                  job_.file.string().c_str(), rows_.size(), failed, incomplete,
                  seconds_since(start), (job_.out / "summary.json").string().c_str(),
                  (job_.out / "summary.txt").string().c_str());
    }
    // A surface cut short (a cap, a budget, the data's end) is written and marked, and the job
    // does not end as if all had finished.
    if (failed > 0 || incomplete > 0)
      throw Error((failed > 0 ? std::to_string(failed) + " of " + std::to_string(rows_.size()) +
                                    " surfaces failed"
                              : std::string()) +
                  (failed > 0 && incomplete > 0 ? ", " : "") +
                  (incomplete > 0 ? std::to_string(incomplete) + " of " +
                                        std::to_string(rows_.size()) +
                                        " surfaces are incomplete (written, marked so)"
                                  : std::string()) +
                  " (see " + (job_.out / "summary.txt").string() + ")");
  }

 private:
  std::vector<Group> work_items(int ranks) const {
    std::vector<Group> items;
    for (const Group& g : group_surfaces(job_)) {
      const std::size_t n = g.members.size();
      const std::size_t pieces = ranks == 1 ? 1 : std::min<std::size_t>(n, 2 * static_cast<std::size_t>(ranks));
      for (std::size_t p = 0; p < pieces; ++p) {
        Group piece = g;
        piece.members.assign(g.members.begin() + static_cast<std::ptrdiff_t>(n * p / pieces),
                             g.members.begin() + static_cast<std::ptrdiff_t>(n * (p + 1) / pieces));
        items.push_back(std::move(piece));
      }
    }
    return items;
  }

  void prepare_checkpoints() {
    if (checkpoints_.exists()) {
      if (args_.resume) {
        checkpoints_.check_owner();
        checkpoints_.check_inputs();
        return;
      }
      if (!args_.restart)
        throw InvalidArgument("the output folder '" + job_.out.string() +
                              "' holds the checkpoint of an earlier run: continue it with "
                              "--resume, or start afresh with --restart");
      checkpoints_.clear();
    } else if (args_.resume && !args_.quiet) {
      std::printf("No checkpoint in '%s': starting the job from the beginning.\n",
                  checkpoints_.folder().string().c_str());
    }
    checkpoints_.start();
  }

  std::size_t device_bytes() const {
    return args_.device_memory.empty() ? 0 : spacetime::parse_bytes(args_.device_memory);
  }

  void run_group(const Group& g) {
    std::vector<std::unique_ptr<SurfaceTask>> tasks;
    // What the group reads, opened once for all of its surfaces.
    std::unique_ptr<Field3> steady;
    std::unique_ptr<UnsteadyField> flow;
    std::unique_ptr<io::TimeSeries> series;
    std::unique_ptr<spacetime::BrickCache> cache;
    std::unique_ptr<spacetime::StreamedField> shared;
    std::shared_ptr<spacetime::SharedBulkAdvance> bulk;
    std::vector<std::size_t> todo;
    for (std::size_t i : g.members) {
      const SurfaceSpec& s = job_.surfaces[i];
      if (auto done = checkpoints_.load_done(s.name);
          done && std::filesystem::exists(output_path(job_, s))) {
        rows_[i] = *done;
        rows_[i]["resumed"] = "finished before";
        continue;
      }
      todo.push_back(i);
    }
    if (todo.empty()) return;
    if (g.kind == SurfaceKind::streak) {
      // Streak surfaces read their data one step interval at a time for all their particles
      // (each step once); they run one after another and are not checkpointed between frames:
      // one cut short runs again from its release on --resume.
      for (std::size_t i : todo) run_streak(job_.surfaces[i], i);
      passes_.push_back({{"field", g.field}, {"kind", "streak"}, {"surfaces", todo.size()}});
      return;
    }
    try {
      if (g.kind == SurfaceKind::stream) {
        steady = io::open_field(g.field);
      } else if (!g.streamed) {
        flow = make_unsteady_field(g.field);
      } else {
        series = io::open_time_series(g.field, "path surfaces");
        spacetime::CacheOptions co;
        co.budget_bytes = job_.cache_budget.empty()
                              ? cache_budget_for(available_memory_bytes())
                              : spacetime::parse_bytes(job_.cache_budget);
        cache = std::make_unique<spacetime::BrickCache>(*series, co);
        shared = std::make_unique<spacetime::StreamedField>(*cache);
        if (!args_.device.empty())
          bulk = std::make_shared<spacetime::SharedBulkAdvance>(
              *cache, advect::parse_device(args_.device), device_bytes(), !args_.no_merge_fronts,
              args_.device_calls);
      }
    } catch (const std::exception& e) {
      for (std::size_t i : todo)
        rows_[i] = summary_row(job_.surfaces[i], "failed", json(), 0, e.what(), "");
      return;
    }
    std::vector<std::size_t> index;  // job index of each task
    // The surfaces of a pass grow together: where the job does not set max_vertices, they share
    // the vertex cap one surface alone would have (half the memory available at ~300 B a vertex).
    const std::size_t vertex_share =
        std::max<std::size_t>(default_vertex_budget() / todo.size(), 1000);
    for (std::size_t i : todo) {
      SurfaceSpec s = job_.surfaces[i];
      if (!s.given("max-vertices")) s.options["max-vertices"] = std::to_string(vertex_share);
      try {
        std::optional<SurfaceState> saved = checkpoints_.load_state(s.name);
        std::unique_ptr<SurfaceTask> task;
        if (s.kind == SurfaceKind::stream) {
          const auto* resume = saved ? std::get_if<EngineState<3>>(&*saved) : nullptr;
          if (saved && !resume) throw InvalidArgument("checkpoint of '" + s.name + "' is not a stream surface's");
          task = std::make_unique<StreamTask>(s, *steady, resume);
        } else {
          const auto* resume = saved ? std::get_if<spacetime::PathState>(&*saved) : nullptr;
          if (saved && !resume) throw InvalidArgument("checkpoint of '" + s.name + "' is not a path surface's");
          if (shared)
            task = std::make_unique<PathTask>(s, *shared, *cache, resume, bulk);
          else
            task = std::make_unique<PathTask>(s, *flow, resume);
        }
        tasks.push_back(std::move(task));
        index.push_back(i);
      } catch (const std::exception& e) {
        fail(s, i, e.what());
      }
    }
    // The pass, in rounds: the surfaces whose fronts lie within one front step of the one
    // furthest behind step once (in parallel), the others wait; streamed surfaces share one band,
    // pinned for all of them before each round, so each brick is read once for the whole group.
    // Where the band of all of them does not fit the budget, half of them are set aside (their
    // state kept) for a later pass over the data; a surface whose band alone does not fit fails.
    std::vector<char> finished(tasks.size(), 0), waiting(tasks.size(), 0);
    std::vector<std::size_t> round, active;
    std::vector<spacetime::FrontSample> samples;
    int data_passes = 1;
    std::size_t set_aside = 0;
    while (true) {
      round.clear();
      active.clear();
      double least = 0, span = 0;
      for (std::size_t k = 0; k < tasks.size(); ++k) {
        if (finished[k] || waiting[k]) continue;
        if (!tasks[k]->ready()) {  // stopped: write it now
          complete(*tasks[k], index[k], series.get());
          finished[k] = 1;
          continue;
        }
        const double key = tasks[k]->lag_key();
        if (active.empty() || key < least) least = key;
        span = std::max(span, tasks[k]->step_span());
        active.push_back(k);
      }
      if (active.empty()) {
        // This pass is over: the surfaces set aside go on in the next one.
        std::size_t resumed = 0;
        for (std::size_t k = 0; k < tasks.size(); ++k)
          if (waiting[k]) waiting[k] = 0, ++resumed;
        if (resumed == 0) break;
        ++data_passes;
        continue;
      }
      maybe_checkpoint(tasks, finished);
      if (shared) {
        samples.clear();
        spacetime::BandPrediction prediction;
        prediction.time_scale = std::numeric_limits<double>::infinity();
        for (std::size_t k : active) {
          tasks[k]->front_samples(samples);
          const spacetime::BandPrediction p = tasks[k]->prediction();
          // The widest reach of any surface: the largest ℓ (each sample carries its own c).
          prediction.edge = std::max(prediction.edge, p.edge);
          prediction.time_scale = std::min(prediction.time_scale, p.time_scale);
          prediction.back_time = std::max(prediction.back_time, p.back_time);
        }
        try {
          shared->update_front(samples, prediction);
        } catch (const InvalidArgument& e) {  // the band does not fit the budget
          if (active.size() > 1) {
            for (std::size_t j = active.size() / 2; j < active.size(); ++j) waiting[active[j]] = 1;
            set_aside += active.size() - active.size() / 2;
            continue;
          }
          fail(tasks[active[0]]->spec(), index[active[0]], e.what());
          finished[active[0]] = 1;
          continue;
        } catch (const std::exception& e) {  // a read error: no surface of this data can go on
          for (std::size_t k = 0; k < tasks.size(); ++k)
            if (!finished[k]) {
              fail(tasks[k]->spec(), index[k], e.what());
              finished[k] = 1;
            }
          break;
        }
      }
      for (std::size_t k : active)
        if (tasks[k]->lag_key() <= least + span) round.push_back(k);
      std::vector<std::string> errors(round.size());
      tbb::parallel_for(std::size_t{0}, round.size(), [&](std::size_t r) {
        try {
          tasks[round[r]]->step();
        } catch (const std::exception& e) {
          errors[r] = e.what();
        }
      });
      for (std::size_t r = 0; r < round.size(); ++r)
        if (!errors[r].empty()) {
          fail(tasks[round[r]]->spec(), index[round[r]], errors[r]);
          finished[round[r]] = 1;
        }
      steps_taken_ += static_cast<long long>(round.size());
    }
    json pass = {{"field", g.field},          {"kind", to_string(g.kind)},
                 {"surfaces", tasks.size()},   {"data_passes", data_passes},
                 {"set_aside", set_aside}};
    if (cache) pass["cache"] = spacetime::to_json(cache->statistics());
    if (const auto merged = bulk ? bulk->merge_statistics() : std::nullopt)
      pass["device"] = {{"backend", bulk->backend()->name()},
                        {"merged", !args_.no_merge_fronts},
                        {"concurrent_calls", bulk->concurrent_calls()},
                        {"front_calls", merged->requests},
                        {"backend_calls", merged->backend_calls},
                        {"largest_merge", merged->largest_merge},
                        {"particles", merged->particles},
                        {"backend_seconds", merged->backend_seconds},
                        {"kernel_seconds", merged->kernel_seconds},
                        {"host_seconds", merged->host_seconds},
                        {"wait_seconds", merged->wait_seconds}};
    passes_.push_back(pass);
  }

  void run_streak(const SurfaceSpec& s, std::size_t i) {
    const auto t0 = Clock::now();
    try {
      const std::filesystem::path pvd = output_path(job_, s);
      io::MeshSeriesWriter writer(pvd);
      spacetime::StreakOptions o = streak_arguments(s);
      o.progress = [](const spacetime::StreakProgress&) { return !interrupted(); };
      if (!args_.device.empty() && !is_unsteady_field_name(s.field)) {
        o.device = advect::parse_device(args_.device);
        o.device_bytes = device_bytes();
      }
      writer.set_notes(output_notes("streak", s.field, nullptr));
      const auto sink = [&](const spacetime::StreakFrame& frame) {
        writer.add_frame(frame.mesh, frame.time);
      };
      const SeedCurve seed = parse_seed(s.seed).translated(s.offset);
      spacetime::StreakReport result;
      EdgeChoice edge = choose_edge(o.edge, s.given("edge"), nullptr);
      if (is_unsteady_field_name(s.field)) {
        result = spacetime::build_streak_surface(*make_unsteady_field(s.field), seed, o, sink);
      } else {
        const auto series = io::open_time_series(s.field, "streak surfaces");
        writer.set_notes(output_notes("streak", s.field, series.get()));
        // As `streak`: without an edge, the series' cell size.
        edge = choose_edge(o.edge, s.given("edge"), &series->geometry());
        o.edge = edge.edge;
        spacetime::CacheOptions co;
        co.budget_bytes = job_.cache_budget.empty() ? cache_budget_for(available_memory_bytes())
                                                    : spacetime::parse_bytes(job_.cache_budget);
        spacetime::BrickCache cache(*series, co);
        result = spacetime::build_streak_surface(cache, seed, o, sink);
      }
      if (interrupted())
        throw Error("interrupted during streak surface '" + s.name +
                    "' (it runs again from its release on --resume)");
      json report = streak_report_json(result);
      add_edge_keys(report, edge);
      report["name"] = s.name;
      report["field"] = s.field;
      report["seed"] = s.seed;
      report["seed_offset"] = {s.offset.x(), s.offset.y(), s.offset.z()};
      report["output"] = pvd.string();
      report["frames_written"] = writer.frames();
      io::write_json(report, job_.out / (s.name + ".json"));
      json row = summary_row(s, result.complete ? "done" : "incomplete", json(),
                             result.total_seconds, result.complete ? "" : result.message,
                             pvd.string());
      if (!result.frames.empty()) {
        const auto& f = result.frames.back();
        row["vertices"] = f.vertices;
        row["faces"] = f.faces;
        row["steps"] = result.intervals;
        row["frames"] = result.frames.size();
        row["quad_share"] = f.quality.quad_share;
        row["quad_angles_within_10"] = f.quality.quad_angles_within_10;
        row["folds"] = f.quality.folds;
        row["degenerate_faces"] = f.quality.degenerate_faces;
      }
      rows_[i] = row;
    } catch (const std::exception& e) {
      if (interrupted()) throw;
      rows_[i] = summary_row(s, "failed", json(), seconds_since(t0), e.what(), "");
    }
    save_done(s.name, rows_[i]);
  }

  void fail(const SurfaceSpec& s, std::size_t i, const std::string& message) {
    rows_[i] = summary_row(s, "failed", json(), 0, message, "");
    save_done(s.name, rows_[i]);
    checkpoints_.remove_state(s.name);
  }

  // A finished surface's row, after the fingerprints of the files it read.
  void save_done(const std::string& surface, const json& row) {
    checkpoints_.record_inputs(io::noted_inputs(), rank_);
    checkpoints_.save_done(surface, row);
  }

  void maybe_checkpoint(const std::vector<std::unique_ptr<SurfaceTask>>& tasks,
                        const std::vector<char>& finished) {
    const bool killed = args_.fail_after_steps >= 0 && steps_taken_ >= args_.fail_after_steps;
    const bool due = job_.checkpoint_every > 0 &&
                     seconds_since(last_checkpoint_) >= job_.checkpoint_every;
    if (!due && !interrupted() && !killed) return;
    if (killed) std::_Exit(9);  // as kill -9: nothing saved since the last checkpoint
    const auto t0 = Clock::now();
    checkpoints_.record_inputs(io::noted_inputs(), rank_);
    for (std::size_t k = 0; k < tasks.size(); ++k)
      if (!finished[k]) checkpoints_.save_state(tasks[k]->spec().name, tasks[k]->state());
    last_checkpoint_ = Clock::now();
    checkpoint_seconds_ += seconds_since(t0);
    ++checkpoints_written_;
    if (interrupted())
      throw Error("interrupted: the unfinished surfaces were checkpointed in '" +
                  checkpoints_.folder().string() + "'; continue with --resume");
  }

  // `series`: the group's streamed series (null for steady fields and analytic flows).
  void complete(SurfaceTask& task, std::size_t i, const io::TimeSeries* series) {
    const SurfaceSpec& s = task.spec();
    const auto t0 = Clock::now();
    try {
      auto [mesh, report] = task.finish();
      mesh.notes = output_notes(to_string(s.kind), s.field, series);
      const std::filesystem::path out = output_path(job_, s);
      report["name"] = s.name;
      report["field"] = s.field;
      report["seed"] = s.seed;
      report["seed_offset"] = {s.offset.x(), s.offset.y(), s.offset.z()};
      report["seed_count"] = task.seed_count();
      report["output"] = out.string();
      report["resumed_at_step"] = task.resumed_at_step();
      const bool complete = report.value("complete", true);
      io::AtomicFileSet files;
      io::write_mesh(mesh, out, files);
      io::write_json(report, job_.out / (s.name + ".json"), files);
      files.commit();
      const double seconds =
          report.contains("times_s") ? report["times_s"].value("total", 0.0) : 0.0;
      rows_[i] = summary_row(s, complete ? "done" : "incomplete", report, seconds,
                             complete ? "" : report.value("message", std::string()), out.string());
    } catch (const std::exception& e) {
      rows_[i] = summary_row(s, "failed", json(), seconds_since(t0), e.what(), "");
    }
    save_done(s.name, rows_[i]);
    checkpoints_.remove_state(s.name);
  }

  BatchJob job_;
  BatchArgs args_;
  CheckpointFolder checkpoints_;
  int rank_ = 0;  // this process's rank (0 without MPI)
  std::vector<json> rows_;
  json passes_ = json::array();
  Clock::time_point last_checkpoint_;
  long long steps_taken_ = 0;
  std::size_t checkpoints_written_ = 0;
  double checkpoint_seconds_ = 0;  // writing checkpoints (the overhead they add)
};

}  // namespace

void add_batch_command(CLI::App& app) {
  auto args = std::make_shared<BatchArgs>();
  CLI::App* c = app.add_subcommand(
      "batch",
      "Build the surfaces of a job file (TOML or JSON; see docs/examples/batch/): one pass over the "
      "data for all surfaces that share it, checkpoints, --resume after a kill");
  c->add_option("job", args->job, "Job file (.toml or .json)")->required();
  c->add_option("--out", args->out, "Output folder (default: the job file's job.out)");
  c->add_flag("--resume", args->resume,
              "Continue from the output folder's checkpoint: finished surfaces are kept, "
              "unfinished ones continue from their last saved step");
  c->add_flag("--restart", args->restart,
              "Start afresh over an earlier run's checkpoint (removes it)");
  c->add_option("--checkpoint-every", args->checkpoint_every,
                "Seconds between checkpoints (default: the job file's job.checkpoint_every, "
                "else 60; 0: only on SIGTERM/SIGINT)")
      ->check(CLI::NonNegativeNumber);
  c->add_option("--fail-after-steps", args->fail_after_steps,
                "Testing: exit at once, as if killed with SIGKILL, after this many front steps")
      ->group("");
  c->add_option("--device", args->device,
                 "Series: advance path surfaces' fronts (one backend and one set of device-resident "
                 "steps for a pass) and move streak particles by bulk advection on cpu, cuda or "
                 "auto (as `path --device`); default: per vertex")
      ->check(CLI::IsMember({"cpu", "cuda", "auto"}));
  c->add_option("--device-memory", args->device_memory,
                 "With --device cuda/auto: time steps kept on the device (default: half its free "
                 "memory)");
  c->add_flag("--no-merge-fronts", args->no_merge_fronts,
              "With --device: the fronts of a pass take turns on the backend, one call each, "
              "instead of going together in merged calls (the same meshes; a baseline to measure "
              "against)")
      ->group("");  // left out of the user's help
  c->add_option("--device-calls", args->device_calls,
                 "With --device: backend calls running at once (0: as many as the backend allows, "
                 "16 on CUDA, each on a stream of its own; 1: one at a time, the fronts that come "
                 "meanwhile merged)")
      ->check(CLI::Range(0, 4096))
      ->capture_default_str();
  c->add_option("--threads", args->threads,
                "Threads of this process (0: every core; under MPI, per rank)")
      ->check(CLI::Range(0, 4096))
      ->capture_default_str();
  c->add_flag("--quiet", args->quiet, "No table on stdout");
  c->callback([args]() {
    if (args->resume && args->restart)
      throw InvalidArgument("--resume and --restart exclude each other");
    if (args->device == "cuda") {
      std::string why;
      if (!advect::cuda_available(&why)) throw InvalidArgument("--device cuda: " + why);
    }
    if (!args->device_memory.empty()) (void)spacetime::parse_bytes(args->device_memory);
    std::optional<tbb::global_control> threads;
    if (args->threads > 0)
      threads.emplace(tbb::global_control::max_allowed_parallelism,
                      static_cast<std::size_t>(args->threads));
    BatchJob job = read_batch_job(args->job);
    if (!args->out.empty()) job.out = args->out;
    BatchRun(std::move(job), *args).run();
  });
}

}  // namespace orthofront::cli
