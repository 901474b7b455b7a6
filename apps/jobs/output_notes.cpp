#include "jobs/output_notes.h"

#include "orthofront/io/hdf5_layout.h"
#include "orthofront/io/netcdf_series.h"

namespace orthofront::jobs {

MeshNotes output_notes(const std::string& kind, const std::string& field,
                       const io::TimeSeries* series) {
  std::string positions = "the input's coordinates (the input states no unit)";
  std::string time = kind == "stream"
                         ? "integration time along the stream lines: position units over "
                           "velocity units"
                         : "the series' times (the input states no unit)";
  if (series != nullptr) {
    if (const io::NetcdfDescription* nc = io::netcdf_description(*series)) {
      if (nc->lonlat)
        positions = nc->metric == io::LonLatMetric::degrees
                        ? "degrees: x longitude east, y latitude north"
                        : "metres east and north: " + nc->metric_note;
      else if (!nc->coordinates.empty())
        positions = nc->coordinates;
      if (!nc->time.empty()) time = nc->time;
    } else if (const auto* h5 = dynamic_cast<const io::Hdf5TimeSeries*>(series)) {
      const io::Hdf5Units& units = h5->description().units;
      if (!units.length.empty()) positions = units.length;
      if (!units.time.empty()) time = units.time;
    }
  }
  return {{"orthofront_surface", kind + " surface, orthofront " ORTHOFRONT_VERSION},
          {"source", field},
          {"position_units", positions},
          {"time", time}};
}

}  // namespace orthofront::jobs
