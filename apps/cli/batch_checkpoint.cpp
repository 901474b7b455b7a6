#include "cli/batch_checkpoint.h"

#include <zlib.h>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <sstream>

#include "orthofront/error.h"
#include "orthofront/io/atomic_file.h"
#include "orthofront/io/error.h"
#include "orthofront/io/state_codec.h"

namespace orthofront::cli {

namespace {

// 2: the report stores clamped-α and insertion-fallback counts by cause; 3: stall cuts, gaps
// closed and the gap-closing time; 4: front vertices beside a missed seed shot, and the shots
// skipped; 5: triangles by cause; 6: the seed-shot time limit and the shots over budget.
constexpr std::uint32_t kFormat = 8;  // 7: a CRC-32 of the state follows it; 8: path states lift time from t0
constexpr char kMagic[] = "orthofront-checkpoint\n";

std::string read_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw io::IoError("cannot read checkpoint file '" + path.string() + "'");
  std::stringstream buffer;
  buffer << in.rdbuf();
  return buffer.str();
}

void write_path_state(io::ByteWriter& out, const spacetime::PathState& state) {
  out.u8(static_cast<std::uint8_t>(state.engine.index()));
  if (const auto* e3 = std::get_if<EngineState<3>>(&state.engine))
    io::write_engine_state(out, *e3);
  else
    io::write_engine_state(out, std::get<EngineState<4>>(state.engine));
  out.f64(state.time_scale);
  out.text(state.time_scale_source);
  out.u64(state.band.size());
  for (const spacetime::BandRecord& b : state.band) {
    out.i32(b.step);
    for (double v : {b.t_min, b.t_max, b.vertex_t_min, b.vertex_t_max}) out.f64(v);
    for (std::size_t v : {b.first_step, b.last_step, b.pinned_units}) out.u64(v);
  }
  out.f64(state.time_reached);
  out.f64(state.observed_begin);
  out.f64(state.observed_end);
}

spacetime::PathState read_path_state(io::ByteReader& in) {
  spacetime::PathState state;
  const std::uint8_t kind = in.u8();
  if (kind == 0)
    state.engine = io::read_engine_state<3>(in);
  else if (kind == 1)
    state.engine = io::read_engine_state<4>(in);
  else
    in.fail("a path state of kind " + std::to_string(kind));
  state.time_scale = in.f64();
  state.time_scale_source = in.text();
  state.band.resize(in.count(4 + 4 * 8 + 3 * 8));
  for (spacetime::BandRecord& b : state.band) {
    b.step = in.i32();
    for (double* v : {&b.t_min, &b.t_max, &b.vertex_t_min, &b.vertex_t_max}) *v = in.f64();
    for (std::size_t* v : {&b.first_step, &b.last_step, &b.pinned_units}) *v = in.u64();
  }
  state.time_reached = in.f64();
  state.observed_begin = in.f64();
  state.observed_end = in.f64();
  if (!(state.time_scale > 0)) in.fail("time scale " + std::to_string(state.time_scale));
  return state;
}

std::string digest_text(std::uint64_t digest) {
  char text[32];
  std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(digest));
  return text;
}

std::uint32_t state_checksum(std::string_view bytes) {
  return static_cast<std::uint32_t>(
      ::crc32(0L, reinterpret_cast<const Bytef*>(bytes.data()), static_cast<uInt>(bytes.size())));
}

// What identifies an input file's contents without reading all of it: its size, its
// modification time and a CRC-32 of its first and last 64 KiB (headers, chunk indexes).
nlohmann::json fingerprint(const std::filesystem::path& path) {
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  if (ec) return nullptr;
  const auto modified = std::filesystem::last_write_time(path, ec);
  if (ec) return nullptr;
  std::ifstream in(path, std::ios::binary);
  if (!in) return nullptr;
  constexpr std::uintmax_t kSpan = 64 * 1024;
  uLong crc = ::crc32(0L, Z_NULL, 0);
  std::string buffer;
  for (const std::uintmax_t begin : {std::uintmax_t{0}, size > kSpan ? size - kSpan : 0}) {
    buffer.resize(static_cast<std::size_t>(std::min(kSpan, size - begin)));
    in.seekg(static_cast<std::streamoff>(begin));
    if (!in.read(buffer.data(), static_cast<std::streamsize>(buffer.size()))) return nullptr;
    crc = ::crc32(crc, reinterpret_cast<const Bytef*>(buffer.data()),
                  static_cast<uInt>(buffer.size()));
  }
  return {{"size", size},
          {"modified_ns", std::chrono::duration_cast<std::chrono::nanoseconds>(
                              modified.time_since_epoch())
                              .count()},
          {"crc32_ends", static_cast<std::uint32_t>(crc)}};
}

}  // namespace

std::string checkpoint_version() {
  return std::string(ORTHOFRONT_VERSION) + "/state-" + std::to_string(kFormat);
}

CheckpointFolder::CheckpointFolder(std::filesystem::path folder, std::uint64_t job_digest)
    : folder_(std::move(folder)), digest_(job_digest) {}

std::filesystem::path CheckpointFolder::file(const std::string& surface, const char* ext) const {
  return folder_ / (surface + ext);
}

bool CheckpointFolder::exists() const { return std::filesystem::exists(folder_ / "job.id"); }

void CheckpointFolder::start() {
  std::error_code ec;
  std::filesystem::create_directories(folder_, ec);
  if (ec)
    throw io::IoError("cannot create the checkpoint folder '" + folder_.string() + "': " +
                      ec.message());
  const nlohmann::json id = {{"version", checkpoint_version()}, {"job", digest_text(digest_)}};
  io::write_atomically(folder_ / "job.id", [&](std::ofstream& out) { out << id.dump() << '\n'; });
}

void CheckpointFolder::check_owner() const {
  const std::filesystem::path path = folder_ / "job.id";
  nlohmann::json id;
  try {
    id = nlohmann::json::parse(read_file(path));
  } catch (const nlohmann::json::exception&) {
    throw io::FormatError("corrupt checkpoint '" + path.string() + "': not the JSON it writes");
  }
  const std::string version = id.value("version", std::string("?"));
  const std::string job = id.value("job", std::string("?"));
  if (version != checkpoint_version())
    throw InvalidArgument("the checkpoint in '" + folder_.string() + "' was written by version " +
                          version + ", this is " + checkpoint_version() +
                          "; it cannot be resumed (remove the folder to start again)");
  if (job != digest_text(digest_))
    throw InvalidArgument("the checkpoint in '" + folder_.string() + "' belongs to another job " +
                          "(digest " + job + ", this job file's is " + digest_text(digest_) +
                          "); resume with the job file that wrote it, or remove the folder");
}

void CheckpointFolder::clear() {
  std::error_code ec;
  std::filesystem::remove_all(folder_, ec);
  if (ec)
    throw io::IoError("cannot remove the old checkpoint folder '" + folder_.string() + "': " +
                      ec.message());
}

void CheckpointFolder::save_state(const std::string& surface, const SurfaceState& state) const {
  io::ByteWriter out;
  out.text(checkpoint_version());
  out.u64(digest_);
  out.text(surface);
  out.u8(static_cast<std::uint8_t>(state.index()));
  if (const auto* stream = std::get_if<EngineState<3>>(&state))
    io::write_engine_state(out, *stream);
  else
    write_path_state(out, std::get<spacetime::PathState>(state));
  const std::uint32_t crc = state_checksum(out.bytes());
  io::write_atomically(file(surface, ".state"), [&](std::ofstream& f) {
    f.write(kMagic, sizeof kMagic - 1);
    f.write(out.bytes().data(), static_cast<std::streamsize>(out.bytes().size()));
    const char tail[4] = {static_cast<char>(crc & 0xff), static_cast<char>((crc >> 8) & 0xff),
                          static_cast<char>((crc >> 16) & 0xff),
                          static_cast<char>((crc >> 24) & 0xff)};
    f.write(tail, 4);
  });
}

std::optional<SurfaceState> CheckpointFolder::load_state(const std::string& surface) const {
  const std::filesystem::path path = file(surface, ".state");
  if (!std::filesystem::exists(path)) return std::nullopt;
  const std::string bytes = read_file(path);
  const std::string_view magic(kMagic, sizeof kMagic - 1);
  if (bytes.compare(0, magic.size(), magic) != 0)
    throw io::FormatError("'" + path.string() + "' is not an orthofront checkpoint");
  // A state that changed after it was written (a flipped bit, a partial copy) would resume into
  // another surface without a word: its checksum must match.
  if (bytes.size() < magic.size() + 4)
    throw io::FormatError("corrupt checkpoint '" + path.string() + "': cut short");
  const std::string_view payload =
      std::string_view(bytes).substr(magic.size(), bytes.size() - magic.size() - 4);
  std::uint32_t stored = 0;
  for (int k = 3; k >= 0; --k)
    stored = stored << 8 | static_cast<unsigned char>(bytes[bytes.size() - 4 + static_cast<std::size_t>(k)]);
  if (stored != state_checksum(payload))
    throw io::FormatError("corrupt checkpoint '" + path.string() +
                          "': its checksum does not match (it changed after it was written); "
                          "resume with --restart to build the surface again");
  io::ByteReader in(payload, path.string());
  const std::string version = in.text();
  if (version != checkpoint_version())
    throw InvalidArgument("checkpoint '" + path.string() + "' was written by version " + version +
                          ", this is " + checkpoint_version());
  if (in.u64() != digest_)
    throw InvalidArgument("checkpoint '" + path.string() + "' belongs to another job file");
  if (const std::string name = in.text(); name != surface)
    in.fail("it names surface '" + name + "', not '" + surface + "'");
  const std::uint8_t kind = in.u8();
  SurfaceState state;
  if (kind == 0)
    state = io::read_engine_state<3>(in);
  else if (kind == 1)
    state = read_path_state(in);
  else
    in.fail("a surface state of kind " + std::to_string(kind));
  if (in.left() != 0) in.fail(std::to_string(in.left()) + " bytes after the state");
  return state;
}

void CheckpointFolder::remove_state(const std::string& surface) const {
  std::error_code ec;
  std::filesystem::remove(file(surface, ".state"), ec);
}

void CheckpointFolder::save_done(const std::string& surface, const nlohmann::json& row) const {
  nlohmann::json record = {{"version", checkpoint_version()}, {"job", digest_text(digest_)},
                           {"row", row}};
  io::write_atomically(file(surface, ".done"),
                       [&](std::ofstream& out) { out << record.dump() << '\n'; });
}

std::optional<nlohmann::json> CheckpointFolder::load_done(const std::string& surface) const {
  const std::filesystem::path path = file(surface, ".done");
  if (!std::filesystem::exists(path)) return std::nullopt;
  nlohmann::json record;
  try {
    record = nlohmann::json::parse(read_file(path));
  } catch (const nlohmann::json::exception&) {
    throw io::FormatError("corrupt checkpoint '" + path.string() + "': not the JSON it writes");
  }
  if (record.value("version", std::string()) != checkpoint_version() ||
      record.value("job", std::string()) != digest_text(digest_) || !record.contains("row"))
    throw InvalidArgument("checkpoint '" + path.string() +
                          "' belongs to another job file or version");
  return record["row"];
}

}  // namespace orthofront::cli

namespace orthofront::cli {

void CheckpointFolder::record_inputs(const std::vector<std::filesystem::path>& inputs,
                                     int rank) const {
  const std::filesystem::path path = folder_ / ("inputs-" + std::to_string(rank) + ".json");
  nlohmann::json recorded = nlohmann::json::object();
  if (std::filesystem::exists(path)) {
    try {
      recorded = nlohmann::json::parse(read_file(path));
    } catch (const nlohmann::json::exception&) {
      throw io::FormatError("corrupt checkpoint '" + path.string() + "': not the JSON it writes");
    }
  }
  bool added = false;
  for (const std::filesystem::path& input : inputs) {
    const std::string key = std::filesystem::absolute(input).lexically_normal().string();
    if (recorded.contains(key)) continue;  // checked when the job resumed, or new this run
    recorded[key] = fingerprint(input);
    added = true;
  }
  if (added || !std::filesystem::exists(path))
    io::write_atomically(path, [&](std::ofstream& out) { out << recorded.dump(1) << '\n'; });
}

void CheckpointFolder::check_inputs() const {
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(folder_, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("inputs-", 0) == 0 && entry.path().extension() == ".json")
      check_inputs(entry.path());
  }
}

void CheckpointFolder::check_inputs(const std::filesystem::path& path) const {
  nlohmann::json recorded;
  try {
    recorded = nlohmann::json::parse(read_file(path));
  } catch (const nlohmann::json::exception&) {
    throw io::FormatError("corrupt checkpoint '" + path.string() + "': not the JSON it writes");
  }
  if (!recorded.is_object())
    throw io::FormatError("corrupt checkpoint '" + path.string() + "': not the JSON it writes");
  for (const auto& [file, then] : recorded.items()) {
    const nlohmann::json now = fingerprint(file);
    if (now == then) continue;
    std::string what;
    if (now.is_null())
      what = "it cannot be read any more";
    else if (!then.is_object() || now["size"] != then["size"])
      what = "its size changed from " + (then.is_object() ? then["size"].dump() : "?") + " to " +
             now["size"].dump() + " bytes";
    else if (now["crc32_ends"] != then["crc32_ends"])
      what = "its contents changed";
    else
      what = "it was modified (the same size and the same first and last 64 KiB, but a new "
             "modification time)";
    throw InvalidArgument("input '" + file + "' of the checkpoint in '" + folder_.string() +
                          "' has changed since it was read: " + what +
                          ". Resumed, the surfaces would mix two data sets; restore the file, or "
                          "start afresh with --restart");
  }
}

}  // namespace orthofront::cli
