#pragma once
/// JSON form of run reports (parameters, counts, stage times, per-step figures, quality).
#include <filesystem>

#include <nlohmann/json.hpp>

#include "orthofront/engine/report.h"
#include "orthofront/quality/quality.h"

namespace orthofront::io {

class AtomicFileSet;

nlohmann::json to_json(const StreamSurfaceOptions& options);
nlohmann::json to_json(const QualityReport& quality);
nlohmann::json to_json(const SurfaceReport& report);

/// Writes `value` pretty-printed to `path` atomically (temporary name, then rename).
void write_json(const nlohmann::json& value, const std::filesystem::path& path);

/// As above, but into `files`: `path` is replaced only when files.commit() is called.
void write_json(const nlohmann::json& value, const std::filesystem::path& path,
                AtomicFileSet& files);

}  // namespace orthofront::io
