#include "cli/batch_job.h"

#include <toml++/toml.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <sstream>

#include "jobs/process_memory.h"
#include "jobs/streak_report.h"
#include "jobs/time_arg.h"
#include "orthofront/error.h"
#include "orthofront/io/error.h"
#include "orthofront/spacetime/brick_cache.h"

namespace orthofront::cli {

using namespace jobs;

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

// The job's own keys of a surface (the kinds' options are the rest).
const std::set<std::string>& own_keys() {
  static const std::set<std::string> keys{"name", "kind", "field", "seed", "format"};
  return keys;
}

// A job file's key as the option it names: '_' for '-'; a streak surface's insert was once
// spelt insertion, which it still reads.
std::string option_of(SurfaceKind kind, const std::string& key) {
  if (kind == SurfaceKind::streak && key == "insertion") return "insert";
  std::string option = key;
  std::replace(option.begin(), option.end(), '_', '-');
  return option;
}

// Whether the kind of `options` takes `option` as a surface key.
bool takes(const KindOptions& options, const std::string& option) {
  return options.set.find(option) != nullptr && batch_job_level(options.kind, option) == nullptr;
}

// The text option `spec` parses for a job file's value; InvalidArgument saying why there is none.
std::string option_text(const OptionSpec& spec, const json& v) {
  const auto finite_number = [&]() {
    if (!v.is_number()) throw InvalidArgument("must be a number, got " + v.dump());
    if (v.is_number_float() && !std::isfinite(v.get<double>()))
      throw InvalidArgument("must be finite, got " + v.dump());
    return v.dump();  // the shortest text that reads back as the same number
  };
  switch (spec.type) {
    case OptionType::real:
    case OptionType::integer:
    case OptionType::count:
      return finite_number();
    case OptionType::flag:
      if (!v.is_boolean()) throw InvalidArgument("must be true or false, got " + v.dump());
      return v.get<bool>() ? "true" : "false";
    case OptionType::choice:
      if (!v.is_string()) throw InvalidArgument("must be a string, got " + v.dump());
      return v.get<std::string>();
    case OptionType::text:
      if (v.is_number()) return finite_number();  // t0 = 0.5 as well as t0 = "0.5"
      if (!v.is_string()) throw InvalidArgument("must be a string, got " + v.dump());
      return v.get<std::string>();
  }
  return v.dump();
}

// Parses `v` into `options` as `option`, failing at `at`; returns the text parsed.
std::string apply_option(const Document& d, KindOptions& options, const std::string& option,
                         const json& v, const std::string& at) {
  try {
    const std::string text = option_text(*options.set.find(option), v);
    options.set.set(option, text);
    return text;
  } catch (const InvalidArgument& e) {
    d.fail(at, e.what());
  }
}

// What a surface's table gives: the job's own keys, and the kinds' options by key with where
// each was given.
struct Given {
  json value;
  std::string at;  ///< key path, for messages
};
using Table = std::map<std::string, Given>;

// Reads the job's own keys of `table` (at `path`) into `spec` and returns the rest (the kinds'
// options); `extra` are the family's own keys, read by the caller.
Table read_table(const Document& d, const json& table, const std::string& path, SurfaceSpec& spec,
                 const std::set<std::string>& extra) {
  if (!table.is_object()) d.fail(path, "must be a table, got " + table.dump());
  Table options;
  for (const auto& [key, v] : table.items()) {
    const std::string at = path + "." + key;
    if (extra.count(key)) continue;
    if (key == "name") {
      spec.name = text(d, v, at);
      if (spec.name.empty() || spec.name.find_first_of("/\\:*?\"<>| ") != std::string::npos ||
          spec.name[0] == '.')
        d.fail(at, "must be a plain file name (no spaces, slashes or leading dot), got " + v.dump());
    } else if (key == "kind") {
      const std::optional<SurfaceKind> kind = parse_surface_kind(text(d, v, at));
      if (!kind) d.fail(at, "must be \"stream\", \"path\" or \"streak\", got " + v.dump());
      spec.kind = *kind;
    } else if (key == "field") {
      spec.field = text(d, v, at);
    } else if (key == "seed") {
      spec.seed = text(d, v, at);
    } else if (key == "format") {
      spec.format = text(d, v, at);
      if (spec.format != "vtp" && spec.format != "ply" && spec.format != "obj")
        d.fail(at, "must be \"vtp\", \"ply\" or \"obj\", got " + v.dump());
    } else {
      options[key] = {v, at};
    }
  }
  return options;
}

// Checks the options of [defaults]: each must be a surface key of some kind, with a value that
// kind takes.
void check_defaults(const Document& d, const Table& defaults) {
  KindOptions stream(SurfaceKind::stream), path(SurfaceKind::path), streak(SurfaceKind::streak);
  for (const auto& [key, given] : defaults) {
    bool taken = false;
    const char* job_level = nullptr;
    for (KindOptions* kind_options : {&stream, &path, &streak}) {
      KindOptions& options = *kind_options;
      const SurfaceKind kind = options.kind;
      const std::string option = option_of(kind, key);
      if (!takes(options, option)) {
        if (!job_level) job_level = batch_job_level(kind, option);
        continue;
      }
      taken = true;
      apply_option(d, options, option, given.value, given.at);
    }
    if (taken) continue;
    if (job_level) d.fail(given.at, job_level);
    std::set<std::string> all;
    for (const SurfaceKind kind : kSurfaceKinds) {
      const std::set<std::string> keys = batch_surface_keys(kind);
      all.insert(keys.begin(), keys.end());
    }
    d.fail(given.at, "unknown key (known: " + known(all) + ")");
  }
}

// Applies the options of [defaults] that the surface's kind takes, then its own (each must be
// one its kind takes), onto spec.options.
void resolve_options(const Document& d, const Table& defaults,
                     const Table& own, const std::set<std::string>& extra, SurfaceSpec& spec) {
  KindOptions options(spec.kind);
  const std::string kind = to_string(spec.kind);
  for (const auto& [key, given] : defaults) {
    const std::string option = option_of(spec.kind, key);
    if (own.count(key) == 0 && takes(options, option))
      spec.options[option] = apply_option(d, options, option, given.value, given.at);
  }
  std::map<std::string, std::string> keys_of;  // option -> the own key that gave it
  for (const auto& [key, given] : own) {
    const std::string option = option_of(spec.kind, key);
    if (const auto [it, added] = keys_of.emplace(option, key); !added)
      d.fail(given.at, key + " and " + it->second + " are one key; give one of them");
    if (const char* job_level = batch_job_level(spec.kind, option)) d.fail(given.at, job_level);
    if (options.set.find(option) == nullptr) {
      for (const SurfaceKind other : kSurfaceKinds) {
        KindOptions theirs(other);
        if (takes(theirs, option_of(other, key)))
          d.fail(given.at, key + " is a " + to_string(other) + " surface's key, not a " + kind +
                               " surface's");
      }
      d.fail(given.at, "unknown key for a " + kind + " surface (known: " +
                           known(batch_surface_keys(spec.kind)) +
                           (extra.empty() ? "" : "; and for this family: " + known(extra)) + ")");
    }
    spec.options[option] = apply_option(d, options, option, given.value, given.at);
  }
}

// A command's message in a job file's spelling: --seed-count becomes seed_count.
std::string job_key_spelling(std::string message) {
  for (std::size_t at = message.find("--"); at != std::string::npos; at = message.find("--", at)) {
    message.erase(at, 2);
    for (std::size_t i = at; i < message.size() &&
                             (std::isalnum(static_cast<unsigned char>(message[i])) || message[i] == '-');
         ++i)
      if (message[i] == '-') message[i] = '_';
  }
  return message;
}

// Checks a finished spec (after defaults and the family's own keys).
void check_spec(const Document& d, const std::string& path, SurfaceSpec& s) {
  if (s.name.empty()) d.fail(path, "needs a name");
  if (s.field.empty()) d.fail(path, "needs a field (here or as job.field)");
  if (s.seed.empty()) d.fail(path, "needs a seed");
  if (s.kind == SurfaceKind::streak) {
    if (!s.given("release")) d.fail(path, "a streak surface needs release (\"T0:T1\")");
    if (!s.given("frames")) d.fail(path, "a streak surface needs frames (\"START:END:COUNT\")");
    s.format = "pvd";
  }
  // The commands' own checks of the arguments (they name flags).
  std::optional<PathArgs> path_args;
  try {
    switch (s.kind) {
      case SurfaceKind::stream: {
        const SurfaceJob job = stream_arguments(s);
        check_seed_count(job.seed_count, job.options.max_vertices);
        break;
      }
      case SurfaceKind::path:
        path_args = path_arguments(s);
        check_seed_count(path_args->seed_count, path_args->options.max_vertices);
        break;
      case SurfaceKind::streak:
        (void)streak_arguments(s);
        break;
    }
  } catch (const InvalidArgument& e) {
    d.fail(path, job_key_spelling(e.what()));
  }
  if (path_args && !(path_args->t1 > path_args->t0))
    d.fail(path, "needs t0 < t1, got t0 = " + path_args->t0_text + ", t1 = " + path_args->t1_text);
}

// Applies a spec's options (checked when the job was read) onto a fresh binding of its kind.
void replay(const SurfaceSpec& spec, KindOptions& options) {
  for (const auto& [option, text] : spec.options) options.set.set(option, text);
}

// A path surface's t0 or t1: job files give numbers in the field's time unit.
double job_time(const std::string& text, const char* key) {
  try {
    return resolve_time(text, key, 0, nullptr);
  } catch (const InvalidArgument&) {
    throw InvalidArgument(std::string(key) + " must be a number in the field's time unit, got '" +
                          text + "'");
  }
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

SurfaceJob stream_arguments(const SurfaceSpec& spec) {
  KindOptions options(SurfaceKind::stream);
  replay(spec, options);
  SurfaceJob job = options.stream;
  job.field = spec.field;
  job.seed = spec.seed;
  return job;
}

PathArgs path_arguments(const SurfaceSpec& spec) {
  KindOptions options(SurfaceKind::path);
  replay(spec, options);
  PathArgs args = options.path;
  args.field = spec.field;
  args.seed = spec.seed;
  args.t0 = job_time(args.t0_text, "t0");
  args.t1 = job_time(args.t1_text, "t1");
  return args;
}

spacetime::StreakOptions streak_arguments(const SurfaceSpec& spec) {
  KindOptions options(SurfaceKind::streak);
  replay(spec, options);
  options.streak.field = spec.field;
  options.streak.seed = spec.seed;
  return streak_options(options.set, options.streak);
}

const char* batch_job_level(SurfaceKind kind, const std::string& option) {
  if (option == "memory")
    return "memory is the job's: its surfaces share the memory available (give max_vertices)";
  if (option == "cache-budget") return "the cache budget is the job's: give it as job.cache_budget";
  if (option == "device" || option == "device-memory" || option == "device-min-vertices")
    return "the device is the job's: give it as `batch --device` (and --device-memory)";
  if (kind == SurfaceKind::path &&
      (option == "cache-unit" || option == "no-prefetch" || option == "warm"))
    return "the surfaces of one series share one cache: its unit, prefetch and warm runs are "
           "`path`'s own (for timing)";
  if (kind == SurfaceKind::streak && (option == "route" || option == "point"))
    return "a job builds streak surfaces by the direct route (`streak --route` for the others)";
  return nullptr;
}

std::set<std::string> batch_surface_keys(SurfaceKind kind) {
  std::set<std::string> keys = own_keys();
  if (kind == SurfaceKind::streak) keys.erase("format");
  const KindOptions options(kind);
  for (const OptionSpec& spec : options.set.specs()) {
    if (batch_job_level(kind, spec.name)) continue;
    std::string key = spec.name;
    std::replace(key.begin(), key.end(), '-', '_');
    keys.insert(key);
  }
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
  Table default_options;
  if (d.root.contains("defaults")) {
    default_options = read_table(d, d.root["defaults"], "defaults", defaults, {});
    if (!defaults.name.empty()) d.fail("defaults.name", "a name cannot be a default");
    check_defaults(d, default_options);
  }

  const auto array_of = [&](const char* key) -> std::vector<json> {
    if (!d.root.contains(key)) return {};
    const json& a = d.root[key];
    if (!a.is_array()) d.fail(key, "must be an array of tables ([[" + std::string(key) + "]])");
    return a.get<std::vector<json>>();
  };
  // A family's (or a single surface's) table as one checked spec its members copy.
  const auto base_of = [&](const json& table, const std::string& path, SurfaceKind kind,
                           const std::set<std::string>& extra) {
    SurfaceSpec base = defaults;
    base.kind = kind;
    const Table own = read_table(d, table, path, base, extra);
    if (base.kind == SurfaceKind::streak && table.contains("format"))
      d.fail(path + ".format", "a streak surface writes NAME.pvd; format is for stream and path surfaces");
    resolve_options(d, default_options, own, extra, base);
    base.line = d.line_of(path);
    return base;
  };
  const auto family_name = [&](const SurfaceSpec& base, const std::string& path,
                               const char* members) {
    if (base.name.empty()) d.fail(path, std::string("needs a name (members are ") + members + ")");
  };

  const auto surfaces = array_of("surface");
  for (std::size_t i = 0; i < surfaces.size(); ++i) {
    const std::string path = "surface[" + std::to_string(i) + "]";
    SurfaceSpec s = base_of(surfaces[i], path, defaults.kind, {});
    check_spec(d, path, s);
    job.surfaces.push_back(std::move(s));
  }
  const auto rakes = array_of("rake");
  for (std::size_t i = 0; i < rakes.size(); ++i) {
    const std::string path = "rake[" + std::to_string(i) + "]";
    SurfaceSpec base = base_of(rakes[i], path, defaults.kind, {"count", "offset"});
    if (!rakes[i].contains("count")) d.fail(path, "needs count (seed lines in the rake)");
    if (!rakes[i].contains("offset")) d.fail(path, "needs offset (from one seed line to the next)");
    const auto count = static_cast<std::size_t>(integer(d, rakes[i]["count"], path + ".count", 1, 100'000));
    const Vec3 offset = vector(d, rakes[i]["offset"], path + ".offset");
    family_name(base, path, "NAME-0, NAME-1, ...");
    check_spec(d, path, base);
    for (std::size_t k = 0; k < count; ++k) {
      SurfaceSpec s = base;
      s.name = member_name(base.name, k, count);
      s.offset = static_cast<double>(k) * offset;
      job.surfaces.push_back(std::move(s));
    }
  }
  const auto grids = array_of("grid");
  for (std::size_t i = 0; i < grids.size(); ++i) {
    const std::string path = "grid[" + std::to_string(i) + "]";
    SurfaceSpec base = base_of(grids[i], path, defaults.kind, {"count", "offset"});
    const json& count = grids[i].contains("count") ? grids[i]["count"] : json();
    const json& offset = grids[i].contains("offset") ? grids[i]["offset"] : json();
    if (!count.is_array() || count.size() != 2)
      d.fail(path + ".count", "must be [nu, nv], got " + count.dump());
    if (!offset.is_array() || offset.size() != 2)
      d.fail(path + ".offset", "must be [[u vector], [v vector]], got " + offset.dump());
    family_name(base, path, "NAME-i-j");
    const auto nu = static_cast<std::size_t>(integer(d, count[0], path + ".count[0]", 1, 10'000));
    const auto nv = static_cast<std::size_t>(integer(d, count[1], path + ".count[1]", 1, 10'000));
    const Vec3 du = vector(d, offset[0], path + ".offset[0]");
    const Vec3 dv = vector(d, offset[1], path + ".offset[1]");
    check_spec(d, path, base);
    for (std::size_t u = 0; u < nu; ++u)
      for (std::size_t v = 0; v < nv; ++v) {
        SurfaceSpec s = base;
        s.name = member_name(member_name(base.name, u, nu), v, nv);
        s.offset = static_cast<double>(u) * du + static_cast<double>(v) * dv;
        job.surfaces.push_back(std::move(s));
      }
  }
  const auto sweeps = array_of("sweep");
  for (std::size_t i = 0; i < sweeps.size(); ++i) {
    const std::string path = "sweep[" + std::to_string(i) + "]";
    if (sweeps[i].is_object() && sweeps[i].contains("kind") && sweeps[i]["kind"] != "path")
      d.fail(path + ".kind", "a sweep over t0 is of path surfaces");
    const std::set<std::string> extra{"t0_from", "t0_to", "count", "duration"};
    SurfaceSpec base = base_of(sweeps[i], path, SurfaceKind::path, extra);
    for (const char* key : {"t0_from", "t0_to", "count", "duration"})
      if (!sweeps[i].contains(key)) d.fail(path, std::string("needs ") + key);
    for (const char* key : {"t0", "t1"})
      if (sweeps[i].contains(key))
        d.fail(path + "." + key, "a sweep's times are t0_from, t0_to and duration");
    const double from = number(d, sweeps[i]["t0_from"], path + ".t0_from");
    const double to = number(d, sweeps[i]["t0_to"], path + ".t0_to");
    const auto count = static_cast<std::size_t>(integer(d, sweeps[i]["count"], path + ".count", 1, 100'000));
    const double duration = positive(d, sweeps[i]["duration"], path + ".duration");
    family_name(base, path, "NAME-0, NAME-1, ...");
    const auto set_times = [](SurfaceSpec& s, double t0, double t1) {
      s.options["t0"] = json(t0).dump();
      s.options["t1"] = json(t1).dump();
    };
    set_times(base, from, from + duration);
    check_spec(d, path, base);
    for (std::size_t k = 0; k < count; ++k) {
      SurfaceSpec s = base;
      s.name = member_name(base.name, k, count);
      const double t0 = count == 1 ? from : from + (to - from) * static_cast<double>(k) / static_cast<double>(count - 1);
      set_times(s, t0, t0 + duration);
      job.surfaces.push_back(std::move(s));
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
    expanded.push_back({s.name, to_string(s.kind), s.field, s.seed,
                        {s.offset.x(), s.offset.y(), s.offset.z()}, s.format, s.options});
  }
  job.digest = fnv1a(expanded.dump() + "|" + job.cache_budget);
  return job;
}

}  // namespace orthofront::cli
