#pragma once
/// Resolves a --field argument to a field: a data file "FILE.ext[:SELECTOR]" (dispatched on the
/// extension, see data_files.h; e.g. "flow.h5:/run1") or an analytic name with parameters
/// ("lorenz:rho=28,reverse=1").
#include <memory>
#include <string>

#include "orthofront/field/field.h"
#include "orthofront/io/time_series.h"

namespace orthofront::cli {

/// Throws InvalidArgument naming the unknown field, parameter or file extension; IoError /
/// FormatError naming the file for unreadable data; InvalidArgument for a time series (a steady
/// field is needed).
std::unique_ptr<Field3> open_field(const std::string& spec);

/// Opens the time series `spec` names for `path` and `streak` (`what`: "path surfaces", ...): an
/// HDF5 file in the project's layout or an OpenVDB file of timed vector grids. Throws
/// InvalidArgument naming the --field value for a missing file or another format.
std::unique_ptr<io::TimeSeries> open_time_series(const std::string& spec, const std::string& what);

}  // namespace orthofront::cli
