#pragma once
/// What `streak` and `batch` share about streak surfaces: the --release and --frames syntax and
/// the JSON report.
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "orthofront/spacetime/streak_surface.h"

namespace orthofront::jobs {

/// A time given as a number: the whole text, finite. Throws InvalidArgument "WHAT: 'TEXT' is not
/// a finite number".
double parse_time_number(const std::string& text, const std::string& what);
/// "T0:T1". Throws InvalidArgument naming the text.
std::pair<double, double> parse_streak_release(const std::string& text);
/// "t1,t2,..." or "START:END:COUNT". Throws InvalidArgument naming the text.
std::vector<double> parse_streak_frames(const std::string& text);
nlohmann::json streak_report_json(const spacetime::StreakReport& report);

}  // namespace orthofront::jobs
