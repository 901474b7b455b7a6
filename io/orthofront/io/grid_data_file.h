#pragma once
/// The data-file openers of the vector-grid formats (entries of data_file_formats()): .vec,
/// AmiraMesh, NRRD, VTK XML ImageData, legacy VTK, ParaView .pvd collections and OpenVDB.
#include <memory>

#include "orthofront/io/data_file.h"
#include "orthofront/field/field.h"

namespace orthofront::io {

/// .vec, .am, .nrrd/.nhdr, .vti, .vtk: one grid; the selector names the array / data field. A
/// glob or comma-separated list of such files is a series, one step a file in natural order, at
/// times t0 + i dt from the selector "[ARRAY][,dt=DT][,t0=T0]" (default: the step index).
DataFile open_grid_file(const DataFileSpec& spec);

/// .pvd: the collection's files as a time series at their `timestep` times.
DataFile open_pvd_file(const DataFileSpec& spec);

/// .vdb: the grid the selector names (a name, "x,y,z" scalar grids) as a steady field; without a
/// selector, a file whose vector grids all carry "time" metadata (and are more than one) is a
/// time series, otherwise its first vector grid is the field.
DataFile open_vdb_file(const DataFileSpec& spec);

/// The field of a .vdb spec, sampled sparsely (VdbField): inactive voxels are no data. Throws
/// InvalidArgument when the file is a time series and no grid is named.
std::unique_ptr<Field3> open_vdb_field(const DataFileSpec& spec);

}  // namespace orthofront::io
