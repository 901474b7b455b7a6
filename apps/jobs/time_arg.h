#pragma once
/// \file
/// Times on the command line (--t0, --t1): a number in the field's time unit, a duration
/// ("30 days", "12 h") or a date ("2002-01-01", "2002-01-01 06:00"). Durations and dates need a
/// series that knows its time unit and calendar (NetCDF with a CF time coordinate, whose times are
/// seconds since its epoch); anything else is refused naming the option and the value.
#include <string>

namespace orthofront::io {
class TimeSeries;
}

namespace orthofront::jobs {

/// The time `text` gives for `option`. A duration counts from `origin` (for --t0 the series' first
/// time, for --t1 the run's t0); `series` is null for an analytic field.
double resolve_time(const std::string& text, const std::string& option, double origin,
                    const io::TimeSeries* series);

}  // namespace orthofront::jobs
