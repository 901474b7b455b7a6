#include "cli/batch_job.h"

#include <toml++/toml.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "orthofront/io/open_field.h"
#include "jobs/process_memory.h"
#include "jobs/streak_report.h"
#include "orthofront/error.h"
#include "orthofront/io/error.h"
#include "orthofront/spacetime/brick_cache.h"

namespace orthofront::cli {

using namespace jobs;

const char* to_string(SurfaceKind kind) {
  switch (kind) {
    case SurfaceKind::stream:
      return "stream";
    case SurfaceKind::path:
      return "path";
    case SurfaceKind::streak:
      return "streak";
  }
  return "?";
}

namespace {

using json = nlohmann::json;

/// The parsed file as JSON, with the line of every key path ("surface[2].edge").
struct Document {
  std::string file;
  json root;
  std::map<std::string, int> lines;

  int line_of(const std::string& path) const {
    const auto it = lines.find(path);
    return it == lines.end() ? 0 : it->second;
  }
  [[noreturn]] void fail(const std::string& path, const std::string& what) const {
    const int line = line_of(path);
    throw InvalidArgument(file + (line > 0 ? ":" + std::to_string(line) : "") + ": " + path +
                          ": " + what);
  }
};

json from_toml(const toml::node& node, const std::string& path, std::map<std::string, int>& lines) {
  lines[path] = static_cast<int>(node.source().begin.line);
  if (const auto* t = node.as_table()) {
    json out = json::object();
    for (const auto& [key, value] : *t) {
      const std::string child = path.empty() ? std::string(key.str()) : path + "." + std::string(key.str());
      out[std::string(key.str())] = from_toml(value, child, lines);
    }
    return out;
  }
  if (const auto* a = node.as_array()) {
    json out = json::array();
    for (std::size_t i = 0; i < a->size(); ++i)
      out.push_back(from_toml(*a->get(i), path + "[" + std::to_string(i) + "]", lines));
    return out;
  }
  if (const auto* s = node.as_string()) return s->get();
  if (const auto* i = node.as_integer()) return i->get();
  if (const auto* f = node.as_floating_point()) return f->get();
  if (const auto* b = node.as_boolean()) return b->get();
  return json();  // dates and times: refused where a value is read
}

// The line of every key path of a JSON text that parsed (so its strings and brackets are well
// formed): nlohmann's parser tells positions of syntax errors only.
void index_json_lines(const std::string& text, std::map<std::string, int>& lines) {
  struct Frame {
    bool array = false;
    std::size_t index = 0;
    std::string path, key;
  };
  std::vector<Frame> stack;
  int line = 1;
  bool expect_key = false;
  const auto value_path = [&]() -> std::string {
    if (stack.empty()) return "";
    const Frame& f = stack.back();
    if (f.array) return f.path + "[" + std::to_string(f.index) + "]";
    return f.path.empty() ? f.key : f.path + "." + f.key;
  };
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (c == '\n') {
      ++line;
    } else if (c == '"') {
      std::string value;
      for (++i; i < text.size() && text[i] != '"'; ++i) {
        if (text[i] == '\\' && i + 1 < text.size()) ++i;  // an escape: the next one is literal
        value += text[i];
      }
      if (expect_key && !stack.empty() && !stack.back().array) {
        stack.back().key = value;
        lines[value_path()] = line;
        expect_key = false;
      }
    } else if (c == '{' || c == '[') {
      const std::string path = value_path();
      if (!path.empty() && !lines.count(path)) lines[path] = line;
      stack.push_back({c == '[', 0, path, ""});
      expect_key = c == '{';
    } else if (c == '}' || c == ']') {
      if (!stack.empty()) stack.pop_back();
    } else if (c == ',' && !stack.empty()) {
      if (stack.back().array)
        ++stack.back().index;
      else
        expect_key = true;
    }
  }
}

Document parse(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw io::IoError("cannot open job file '" + file.string() + "'");
  std::stringstream buffer;
  buffer << in.rdbuf();
  const std::string text = buffer.str();
  Document doc;
  doc.file = file.string();
  const std::string ext = file.extension().string();
  if (ext == ".json") {
    try {
      doc.root = json::parse(text, nullptr, true, true);
      index_json_lines(text, doc.lines);
    } catch (const json::parse_error& e) {
      int line = 1;
      for (std::size_t i = 0; i < std::min<std::size_t>(e.byte, text.size()); ++i)
        line += text[i] == '\n';
      throw InvalidArgument(doc.file + ":" + std::to_string(line) + ": not valid JSON: " +
                            e.what());
    }
  } else if (ext == ".toml") {
    try {
      const toml::table table = toml::parse(text, doc.file);
      doc.root = from_toml(table, "", doc.lines);
    } catch (const toml::parse_error& e) {
      throw InvalidArgument(doc.file + ":" + std::to_string(e.source().begin.line) +
                            ": not valid TOML: " + std::string(e.description()));
    }
  } else {
    throw InvalidArgument("job file '" + doc.file + "' has the extension '" + ext +
                          "' (expected .toml or .json)");
  }
  if (!doc.root.is_object()) doc.fail("(top level)", "must be a table of keys");
  return doc;
}

// Reading typed values with messages naming the key path.
double number(const Document& d, const json& v, const std::string& path) {
  if (!v.is_number()) d.fail(path, "must be a number, got " + v.dump());
  const double x = v.get<double>();
  if (!std::isfinite(x)) d.fail(path, "must be finite, got " + v.dump());
  return x;
}
double positive(const Document& d, const json& v, const std::string& path) {
  const double x = number(d, v, path);
  if (!(x > 0)) d.fail(path, "must be a number > 0, got " + v.dump());
  return x;
}
long long integer(const Document& d, const json& v, const std::string& path, long long lo,
                  long long hi) {
  if (!v.is_number_integer()) d.fail(path, "must be an integer, got " + v.dump());
  const long long x = v.get<long long>();
  if (x < lo || x > hi)
    d.fail(path, "must lie in [" + std::to_string(lo) + ", " + std::to_string(hi) + "], got " +
                     std::to_string(x));
  return x;
}
std::string text(const Document& d, const json& v, const std::string& path) {
  if (!v.is_string()) d.fail(path, "must be a string, got " + v.dump());
  return v.get<std::string>();
}
Vec3 vector(const Document& d, const json& v, const std::string& path) {
  if (!v.is_array() || v.size() < 2 || v.size() > 3)
    d.fail(path, "must be an array of 2 or 3 numbers, got " + v.dump());
  Vec3 out = Vec3::Zero();
  for (std::size_t i = 0; i < v.size(); ++i)
    out[static_cast<int>(i)] = number(d, v[i], path + "[" + std::to_string(i) + "]");
  return out;
}

std::string known(const std::set<std::string>& keys) {
  std::string out;
  for (const auto& k : keys) out += (out.empty() ? "" : ", ") + k;
  return out;
}

// Applies the surface keys of `table` (at `path`) onto `spec`; `extra` are the family's own
// keys, read by the caller.
void apply_keys(const Document& d, const json& table, const std::string& path, SurfaceSpec& spec,
                const std::set<std::string>& extra) {
  if (!table.is_object()) d.fail(path, "must be a table, got " + table.dump());
  for (const auto& [key, v] : table.items()) {
    const std::string at = path + "." + key;
    if (extra.count(key)) continue;
    if (!batch_surface_keys().count(key))
      d.fail(at, "unknown key (known: " + known(batch_surface_keys()) +
                     (extra.empty() ? "" : "; and for this family: " + known(extra)) + ")");
    StreamSurfaceOptions& o = spec.options;
    if (key == "name") {
      spec.name = text(d, v, at);
      if (spec.name.empty() || spec.name.find_first_of("/\\:*?\"<>| ") != std::string::npos ||
          spec.name[0] == '.')
        d.fail(at, "must be a plain file name (no spaces, slashes or leading dot), got " + v.dump());
    } else if (key == "kind") {
      const std::string k = text(d, v, at);
      if (k == "stream") spec.kind = SurfaceKind::stream;
      else if (k == "path") spec.kind = SurfaceKind::path;
      else if (k == "streak") spec.kind = SurfaceKind::streak;
      else d.fail(at, "must be \"stream\", \"path\" or \"streak\", got " + v.dump());
    } else if (key == "field") {
      spec.field = text(d, v, at);
    } else if (key == "seed") {
      spec.seed = text(d, v, at);
    } else if (key == "seed_count") {
      spec.seed_count = static_cast<int>(integer(d, v, at, 2, 10'000'000));
      spec.seed_count_given = true;
    } else if (key == "edge") {
      o.edge = positive(d, v, at);
    } else if (key == "steps") {
      o.max_steps = static_cast<int>(integer(d, v, at, 0, 1'000'000'000));
      spec.steps_given = true;
    } else if (key == "t0") {
      spec.t0 = number(d, v, at);
    } else if (key == "t1") {
      spec.t1 = number(d, v, at);
    } else if (key == "time_scale") {
      spec.time_scale = number(d, v, at);
      if (spec.time_scale < 0) d.fail(at, "must be >= 0 (0: derived), got " + v.dump());
    } else if (key == "max_band") {
      spec.max_band = number(d, v, at);
      if (spec.max_band < 0) d.fail(at, "must be >= 0 (0: none), got " + v.dump());
    } else if (key == "max_vertices") {
      o.max_vertices = static_cast<std::size_t>(integer(d, v, at, 2, 4'000'000'000LL));
      spec.max_vertices_given = true;
    } else if (key == "damping") {
      o.damping = number(d, v, at);
      if (!(o.damping > 0 && o.damping < 1)) d.fail(at, "must lie in (0, 1), got " + v.dump());
    } else if (key == "tolerance") {
      o.tolerance = positive(d, v, at);
    } else if (key == "shot_evaluations") {
      o.shot_evaluations = static_cast<int>(integer(d, v, at, 0, 1'000'000'000));
    } else if (key == "integrator") {
      const std::string k = text(d, v, at);
      if (k == "dopri5") o.integrator = IntegratorKind::dopri5;
      else if (k == "rk4") o.integrator = IntegratorKind::rk4;
      else d.fail(at, "must be \"dopri5\" or \"rk4\", got " + v.dump());
    } else if (key == "insertion" || key == "insert") {
      spec.insertion = text(d, v, at);  // checked with the kind (check_spec)
      spec.insertion_key = key;
    } else if (key == "release") {
      spec.release = text(d, v, at);
      try {
        (void)parse_streak_release(spec.release);
      } catch (const std::exception& e) {
        d.fail(at, e.what());
      }
    } else if (key == "frames") {
      spec.frames = text(d, v, at);
      try {
        (void)parse_streak_frames(spec.frames);
      } catch (const std::exception& e) {
        d.fail(at, e.what());
      }
    } else if (key == "split") {
      spec.split = positive(d, v, at);
    } else if (key == "merge") {
      spec.merge = positive(d, v, at);
    } else if (key == "release_step") {
      spec.release_step = number(d, v, at);
      if (spec.release_step < 0) d.fail(at, "must be >= 0 (0: derived), got " + v.dump());
    } else if (key == "releases_per_break") {
      const double k = number(d, v, at);
      if (!(k >= 1 && k <= 1e6 && k == std::floor(k))) d.fail(at, "must be a whole number >= 1, got " + v.dump());
      else spec.releases_per_break = static_cast<int>(k);
    } else if (key == "format") {
      spec.format = text(d, v, at);
      if (spec.format != "vtp" && spec.format != "ply" && spec.format != "obj")
        d.fail(at, "must be \"vtp\", \"ply\" or \"obj\", got " + v.dump());
    }
  }
}

// Checks a finished spec (after defaults and the family's own keys).
void check_spec(const Document& d, const std::string& path, SurfaceSpec& s) {
  if (!s.insertion.empty()) {
    // Each kind's key is its option's name: streak surfaces take insert (insertion, the older
    // spelling, too), stream and path surfaces insertion.
    const std::string at = path + "." + s.insertion_key;
    if (s.kind != SurfaceKind::streak && s.insertion_key == "insert")
      d.fail(at, "insert is a streak surface's key; stream and path surfaces take insertion");
    if (s.kind == SurfaceKind::streak) {
      if (s.insertion != "exact" && s.insertion != "interpolate")
        d.fail(at, "a streak surface's insertion is \"exact\" or \"interpolate\", got \"" +
                       s.insertion + "\"");
    } else if (s.insertion == "streamline") {
      s.options.insertion = Insertion::streamline;
    } else if (s.insertion == "cubic") {
      s.options.insertion = Insertion::cubic;
    } else if (s.insertion == "linear") {
      s.options.insertion = Insertion::linear;
    } else if (s.insertion == "previous-row") {
      s.options.insertion = Insertion::previous_row;
    } else {
      d.fail(at, "must be \"streamline\", \"previous-row\", \"cubic\" or \"linear\", got \"" +
                     s.insertion + "\"");
    }
  }
  if (s.kind == SurfaceKind::streak) {
    if (s.release.empty()) d.fail(path, "a streak surface needs release (\"T0:T1\")");
    if (s.frames.empty()) d.fail(path, "a streak surface needs frames (\"START:END:COUNT\")");
    s.format = "pvd";
  }
  if (s.name.empty()) d.fail(path, "needs a name");
  if (s.field.empty()) d.fail(path, "needs a field (here or as job.field)");
  if (s.seed.empty()) d.fail(path, "needs a seed");
  if (s.kind == SurfaceKind::path && !(s.t1 > s.t0))
    d.fail(path, "needs t0 < t1, got t0 = " + std::to_string(s.t0) + ", t1 = " +
                     std::to_string(s.t1));
  if (static_cast<std::size_t>(s.seed_count) > s.options.max_vertices)
    d.fail(path, "seed_count " + std::to_string(s.seed_count) + " exceeds max_vertices " +
                     std::to_string(s.options.max_vertices));
}

std::string member_name(const std::string& base, std::size_t k, std::size_t count) {
  const int width = static_cast<int>(std::to_string(count > 0 ? count - 1 : 0).size());
  char index[32];
  std::snprintf(index, sizeof index, "%0*zu", width, k);
  return base + "-" + index;
}

// FNV-1a over the text: a stable digest across runs and machines.
std::uint64_t fnv1a(const std::string& text) {
  std::uint64_t h = 1469598103934665603ULL;
  for (unsigned char c : text) {
    h ^= c;
    h *= 1099511628211ULL;
  }
  return h;
}

}  // namespace

const std::set<std::string>& batch_surface_keys() {
  static const std::set<std::string> keys{
      "name",     "kind",        "field",     "seed",      "seed_count", "edge",   "steps",
      "t0",       "t1",          "time_scale", "max_band", "max_vertices", "damping",
      "tolerance", "integrator", "insertion", "insert", "format",  "release", "frames", "split",
      "merge",    "release_step", "releases_per_break", "shot_evaluations"};
  return keys;
}


BatchJob read_batch_job(const std::filesystem::path& file) {
  const Document d = parse(file);
  BatchJob job;
  job.file = file;
  static const std::set<std::string> top{"job", "defaults", "surface", "rake", "grid", "sweep"};
  for (const auto& [key, v] : d.root.items())
    if (!top.count(key)) d.fail(key, "unknown table (known: " + known(top) + ")");

  SurfaceSpec defaults;
  defaults.options.max_vertices = default_vertex_budget();
  if (d.root.contains("job")) {
    const json& j = d.root["job"];
    if (!j.is_object()) d.fail("job", "must be a table");
    static const std::set<std::string> keys{"name", "field", "out", "cache_budget",
                                            "checkpoint_every"};
    for (const auto& [key, v] : j.items()) {
      const std::string at = "job." + key;
      if (!keys.count(key)) d.fail(at, "unknown key (known: " + known(keys) + ")");
      if (key == "name") job.name = text(d, v, at);
      if (key == "field") defaults.field = text(d, v, at);
      if (key == "out") job.out = text(d, v, at);
      if (key == "cache_budget") {
        job.cache_budget = text(d, v, at);
        try {
          (void)spacetime::parse_bytes(job.cache_budget);
        } catch (const std::exception& e) {
          d.fail(at, e.what());
        }
      }
      if (key == "checkpoint_every") {
        job.checkpoint_every = number(d, v, at);
        if (job.checkpoint_every < 0) d.fail(at, "must be >= 0 (0: only on a signal)");
      }
    }
  }
  if (d.root.contains("defaults")) {
    apply_keys(d, d.root["defaults"], "defaults", defaults, {});
    if (!defaults.name.empty()) d.fail("defaults.name", "a name cannot be a default");
  }

  const auto array_of = [&](const char* key) -> std::vector<json> {
    if (!d.root.contains(key)) return {};
    const json& a = d.root[key];
    if (!a.is_array()) d.fail(key, "must be an array of tables ([[" + std::string(key) + "]])");
    return a.get<std::vector<json>>();
  };
  const auto add = [&](SurfaceSpec s, const std::string& path) {
    // As the commands: `stream` takes 100 steps, `path` runs until its path lines reach t1.
    if (!s.steps_given) s.options.max_steps = s.kind == SurfaceKind::path ? 1'000'000 : 100;
    if (!s.seed_count_given && s.kind == SurfaceKind::streak) s.seed_count = 0;
    check_spec(d, path, s);
    s.line = d.line_of(path);
    job.surfaces.push_back(std::move(s));
  };

  const auto surfaces = array_of("surface");
  for (std::size_t i = 0; i < surfaces.size(); ++i) {
    const std::string path = "surface[" + std::to_string(i) + "]";
    SurfaceSpec s = defaults;
    apply_keys(d, surfaces[i], path, s, {});
    add(std::move(s), path);
  }
  const auto rakes = array_of("rake");
  for (std::size_t i = 0; i < rakes.size(); ++i) {
    const std::string path = "rake[" + std::to_string(i) + "]";
    SurfaceSpec base = defaults;
    apply_keys(d, rakes[i], path, base, {"count", "offset"});
    if (!rakes[i].contains("count")) d.fail(path, "needs count (seed lines in the rake)");
    if (!rakes[i].contains("offset")) d.fail(path, "needs offset (from one seed line to the next)");
    const auto count = static_cast<std::size_t>(integer(d, rakes[i]["count"], path + ".count", 1, 100'000));
    const Vec3 offset = vector(d, rakes[i]["offset"], path + ".offset");
    if (base.name.empty()) d.fail(path, "needs a name (members are NAME-0, NAME-1, ...)");
    for (std::size_t k = 0; k < count; ++k) {
      SurfaceSpec s = base;
      s.name = member_name(base.name, k, count);
      s.offset = static_cast<double>(k) * offset;
      add(std::move(s), path);
    }
  }
  const auto grids = array_of("grid");
  for (std::size_t i = 0; i < grids.size(); ++i) {
    const std::string path = "grid[" + std::to_string(i) + "]";
    SurfaceSpec base = defaults;
    apply_keys(d, grids[i], path, base, {"count", "offset"});
    const json& count = grids[i].contains("count") ? grids[i]["count"] : json();
    const json& offset = grids[i].contains("offset") ? grids[i]["offset"] : json();
    if (!count.is_array() || count.size() != 2)
      d.fail(path + ".count", "must be [nu, nv], got " + count.dump());
    if (!offset.is_array() || offset.size() != 2)
      d.fail(path + ".offset", "must be [[u vector], [v vector]], got " + offset.dump());
    if (base.name.empty()) d.fail(path, "needs a name (members are NAME-i-j)");
    const auto nu = static_cast<std::size_t>(integer(d, count[0], path + ".count[0]", 1, 10'000));
    const auto nv = static_cast<std::size_t>(integer(d, count[1], path + ".count[1]", 1, 10'000));
    const Vec3 du = vector(d, offset[0], path + ".offset[0]");
    const Vec3 dv = vector(d, offset[1], path + ".offset[1]");
    for (std::size_t u = 0; u < nu; ++u)
      for (std::size_t v = 0; v < nv; ++v) {
        SurfaceSpec s = base;
        s.name = member_name(member_name(base.name, u, nu), v, nv);
        s.offset = static_cast<double>(u) * du + static_cast<double>(v) * dv;
        add(std::move(s), path);
      }
  }
  const auto sweeps = array_of("sweep");
  for (std::size_t i = 0; i < sweeps.size(); ++i) {
    const std::string path = "sweep[" + std::to_string(i) + "]";
    SurfaceSpec base = defaults;
    base.kind = SurfaceKind::path;
    apply_keys(d, sweeps[i], path, base, {"t0_from", "t0_to", "count", "duration"});
    if (base.kind != SurfaceKind::path) d.fail(path + ".kind", "a sweep over t0 is of path surfaces");
    for (const char* key : {"t0_from", "t0_to", "count", "duration"})
      if (!sweeps[i].contains(key)) d.fail(path, std::string("needs ") + key);
    const double from = number(d, sweeps[i]["t0_from"], path + ".t0_from");
    const double to = number(d, sweeps[i]["t0_to"], path + ".t0_to");
    const auto count = static_cast<std::size_t>(integer(d, sweeps[i]["count"], path + ".count", 1, 100'000));
    const double duration = positive(d, sweeps[i]["duration"], path + ".duration");
    if (base.name.empty()) d.fail(path, "needs a name (members are NAME-0, NAME-1, ...)");
    for (std::size_t k = 0; k < count; ++k) {
      SurfaceSpec s = base;
      s.name = member_name(base.name, k, count);
      s.t0 = count == 1 ? from : from + (to - from) * static_cast<double>(k) / static_cast<double>(count - 1);
      s.t1 = s.t0 + duration;
      add(std::move(s), path);
    }
  }
  if (job.surfaces.empty()) d.fail("(top level)", "names no surface ([[surface]], [[rake]], [[grid]] or [[sweep]])");
  std::map<std::string, std::string> seen;
  json expanded = json::array();
  for (const SurfaceSpec& s : job.surfaces) {
    // The job's own files share the output folder with the surfaces'.
    if (s.name == "summary")
      throw InvalidArgument(job.file.string() + (s.line ? ":" + std::to_string(s.line) : "") +
                            ": the name 'summary' is reserved for the job's summary.json and "
                            "summary.txt; name the surface otherwise");
    if (!seen.emplace(s.name, s.seed).second)
      throw InvalidArgument(job.file.string() + (s.line ? ":" + std::to_string(s.line) : "") +
                            ": two surfaces are named '" + s.name + "'");
    const StreamSurfaceOptions& o = s.options;
    expanded.push_back({s.name, to_string(s.kind), s.field, s.seed,
                        {s.offset.x(), s.offset.y(), s.offset.z()}, s.seed_count, s.t0, s.t1,
                        s.time_scale, s.max_band, o.edge, o.max_steps,
                        s.max_vertices_given ? o.max_vertices : 0, o.damping,
                        o.tolerance, static_cast<int>(o.integrator), static_cast<int>(o.insertion),
                        s.format, s.release, s.frames, s.split, s.merge, s.release_step,
                        s.insertion});
    // Added to jobs later: in the digest only where set, so earlier checkpoints still resume.
    if (s.releases_per_break != 1) expanded.back().push_back(s.releases_per_break);
  }
  job.digest = fnv1a(expanded.dump() + "|" + job.cache_budget);
  return job;
}

}  // namespace orthofront::cli
