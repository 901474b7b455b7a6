#pragma once
/// Resolves a --field argument to a field: a data file "FILE.ext[:SELECTOR]" (dispatched on the
/// extension, see data_file.h; e.g. "flow.h5:/run1") or an analytic name with parameters
/// ("lorenz:rho=28,reverse=1").
#include <memory>
#include <string>

#include "orthofront/field/field.h"
#include "orthofront/io/time_series.h"

namespace orthofront::io {

/// Throws InvalidArgument naming the unknown field, parameter or file extension; IoError /
/// FormatError naming the file for unreadable data; InvalidArgument for a time series (a steady
/// field is needed).
std::unique_ptr<Field3> open_field(const std::string& spec);

/// Opens the time series `spec` names (`what`: "path surfaces", ... for messages): an HDF5 file in
/// the project's layout, NetCDF (a file, glob or list), a ParaView .pvd, a glob or list of grid
/// files, or an OpenVDB file of timed vector grids. Throws InvalidArgument naming `spec` for a
/// missing file or another format.
std::unique_ptr<TimeSeries> open_time_series(const std::string& spec, const std::string& what);

}  // namespace orthofront::io
