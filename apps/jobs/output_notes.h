#pragma once
/// What a written surface means, carried in its mesh files (.vtp field data) so that it keeps its
/// meaning away from the run that made it: the kind of surface, the data it came from, what its
/// positions and its `time` attribute are in. (The seed and the options are in the report.)
#include <string>
#include <utility>
#include <vector>

#include "orthofront/io/time_series.h"

namespace orthofront::jobs {

using MeshNotes = std::vector<std::pair<std::string, std::string>>;

/// kind: "stream", "path" or "streak". series: the time series read (null for steady fields and
/// analytic flows), whose metadata (NetCDF's CF time and lon/lat, the HDF5 layout's units) names
/// the units; otherwise they are the input's own.
MeshNotes output_notes(const std::string& kind, const std::string& field,
                       const io::TimeSeries* series);

}  // namespace orthofront::jobs
