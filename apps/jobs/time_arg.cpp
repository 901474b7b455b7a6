#include "jobs/time_arg.h"

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <optional>

#include "orthofront/error.h"
#include "orthofront/io/time_series.h"
#ifdef ORTHOFRONT_HAVE_NETCDF
#include "orthofront/io/netcdf_series.h"
#endif

namespace orthofront::jobs {
namespace {

std::string lower(std::string text) {
  for (char& c : text) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return text;
}

// Seconds in one `unit`, or nullopt. Months and years have no fixed length.
std::optional<double> seconds_per(const std::string& unit) {
  const std::string u = lower(unit);
  if (u == "s" || u == "sec" || u == "secs" || u == "second" || u == "seconds") return 1.0;
  if (u == "min" || u == "mins" || u == "minute" || u == "minutes") return 60.0;
  if (u == "h" || u == "hr" || u == "hrs" || u == "hour" || u == "hours") return 3600.0;
  if (u == "d" || u == "day" || u == "days") return 86400.0;
  if (u == "week" || u == "weeks") return 7 * 86400.0;
  return std::nullopt;
}

// True when the series' times are seconds (a NetCDF series with a CF time coordinate).
bool times_in_seconds(const io::TimeSeries* series) {
#ifdef ORTHOFRONT_HAVE_NETCDF
  return series != nullptr && io::netcdf_has_calendar(*series);
#else
  (void)series;
  return false;
#endif
}

}  // namespace

double resolve_time(const std::string& text, const std::string& option, double origin,
                    const io::TimeSeries* series) {
  const auto refuse = [&](const std::string& why) {
    return InvalidArgument(option + " '" + text + "': " + why);
  };
  const char* begin = text.c_str();
  char* end = nullptr;
  const double number = std::strtod(begin, &end);
  std::string rest(end == begin ? text : std::string(end));
  while (!rest.empty() && std::isspace(static_cast<unsigned char>(rest.front()))) rest.erase(0, 1);
  while (!rest.empty() && std::isspace(static_cast<unsigned char>(rest.back()))) rest.pop_back();
  if (end != begin && rest.empty()) {
    if (!std::isfinite(number)) throw refuse("not a finite time");
    return number;
  }
  const std::string kinds =
      "a number (the field's time unit), a duration ('30 days', '12 h') or a date "
      "('2002-01-01', '2002-01-01 06:00')";
  const std::string needs =
      "durations and dates need a series that knows its time unit and calendar (NetCDF with a "
      "CF time coordinate); give a number";
  // A duration: a number, then a unit.
  if (end != begin && std::isalpha(static_cast<unsigned char>(rest.front()))) {
    const std::optional<double> unit = seconds_per(rest);
    if (!unit)
      throw refuse("unit '" + rest + "' is not seconds, minutes, hours, days or weeks (months and "
                   "years have no fixed length)");
    if (!times_in_seconds(series)) throw refuse(needs);
    if (!std::isfinite(number)) throw refuse("not a finite time");
    return origin + number * *unit;
  }
  // A date.
  if (text.size() >= 10 && std::isdigit(static_cast<unsigned char>(text[0])) && text[4] == '-') {
#ifdef ORTHOFRONT_HAVE_NETCDF
    if (series != nullptr) {
      try {
        if (const std::optional<double> t = io::netcdf_time_of_date(*series, text)) return *t;
      } catch (const Error&) {
        throw refuse("not a date YYYY-MM-DD[ hh:mm[:ss]][Z|+hh:mm]");
      }
    }
#endif
    throw refuse(needs);
  }
  throw refuse("expected " + kinds);
}

}  // namespace orthofront::jobs
