#pragma once
/// OpenVDB helpers shared by the VDB grid reader/writer and the VDB field (internal: includes
/// OpenVDB's headers, which nothing outside io/ should see).
#include <openvdb/openvdb.h>

#include <filesystem>
#include <istream>
#include <string>
#include <vector>

#include "orthofront/field/grid.h"

namespace orthofront::io::detail {

/// A vector grid selected from a file: float or double voxels (three scalar grids are combined
/// into one of these when loaded).
struct LoadedVdbGrid {
  openvdb::Vec3SGrid::Ptr grid_f;  ///< set for float data
  openvdb::Vec3DGrid::Ptr grid_d;  ///< set for double data
  std::string name;                ///< the grid's name, or "x,y,z" for combined scalar grids
  bool staggered = false;          ///< GRID_STAGGERED: component c lives at the face -1/2 e_c
  int components = 3;              ///< 2 when the grid was written from a 2-component VectorGrid

  const openvdb::GridBase& base() const {
    return grid_f ? static_cast<const openvdb::GridBase&>(*grid_f)
                  : static_cast<const openvdb::GridBase&>(*grid_d);
  }
};

/// Chooses and loads a grid from `grids` (all grids of a file, fully read):
/// - `selector` "NAME": the vector grid NAME;
/// - `selector` "A,B,C": three scalar grids combined (a voxel is active where all three are);
/// - empty: the first Vec3 grid, else scalar grids named x/y/z, u/v/w, vx/vy/vz or
///   NAME.x/NAME.y/NAME.z (the first complete triple).
/// Throws FormatError naming `file`, the selector and the grids the file holds.
LoadedVdbGrid select_vdb_grid(const openvdb::GridPtrVec& grids, const std::string& selector,
                              const std::string& file);

/// Loads only the grid(s) `selector` chooses from a .vdb file (see select_vdb_grid); `where` names
/// the file (and step) in messages. Throws IoError / FormatError.
LoadedVdbGrid load_vdb_grid(const std::filesystem::path& path, const std::string& selector,
                            const std::string& where);

/// Reads every grid of a .vdb file. Throws IoError / FormatError naming the file.
openvdb::GridPtrVecPtr read_vdb_file(const std::filesystem::path& path);

/// Reads every grid of a .vdb file held in memory.
openvdb::GridPtrVecPtr read_vdb_stream(std::istream& in, const std::string& file);

/// The index box a dense copy of `grid` covers: the orthofront_index_min/max metadata of a grid we
/// wrote, joined with the active voxels' bounding box. Empty when the grid has no active voxel and
/// no such metadata.
openvdb::CoordBBox dense_index_box(const LoadedVdbGrid& grid);

/// A dense VectorGrid of `grid` over `box` (inactive voxels: NaN). The transform must map index
/// space to world space by an axis-aligned scale and a translation. Staggered grids are sampled
/// at the voxel centres (the average of the two faces per component; NaN unless both are active).
VectorGrid densify(const LoadedVdbGrid& grid, const openvdb::CoordBBox& box, const std::string& file);

/// A float grid of `grid`'s samples: NaN (in any component) → inactive, anything else active.
/// 2-component grids get w = 0. The transform maps index (i, j, k) to origin + (i, j, k) * spacing.
/// Throws InvalidArgument for rectilinear grids.
openvdb::Vec3SGrid::Ptr to_vdb(const VectorGrid& grid, const std::string& name);

}  // namespace orthofront::io::detail
