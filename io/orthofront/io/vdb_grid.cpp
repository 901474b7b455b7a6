#include "orthofront/io/vdb_grid.h"

#include <openvdb/io/Stream.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <list>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <sstream>

#include "orthofront/error.h"
#include "orthofront/io/atomic_file.h"
#include "orthofront/io/child_read.h"
#include "orthofront/io/error.h"
#include "orthofront/io/grid_decode.h"
#include "orthofront/io/input_files.h"
#include "orthofront/io/readable_file.h"
#include "orthofront/io/vdb_detail.h"
#include "orthofront/io/vdb_module.h"

namespace orthofront::io {

// This file and vdb_field.cpp make the OpenVDB module (vdb_module.h): the functions of
// vdb_grid.h are defined here in namespace `module`, and orthofront_io forwards to them.
namespace module {

void initialize_openvdb() {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

}  // namespace module

namespace detail {
namespace {

constexpr const char* kComponents = "orthofront_components";
constexpr const char* kIndexMin = "orthofront_index_min";
constexpr const char* kIndexMax = "orthofront_index_max";

bool is_vector_type(const openvdb::GridBase& g) {
  return g.isType<openvdb::Vec3SGrid>() || g.isType<openvdb::Vec3DGrid>();
}
bool is_scalar_type(const openvdb::GridBase& g) {
  return g.isType<openvdb::FloatGrid>() || g.isType<openvdb::DoubleGrid>();
}

std::string grid_list(const openvdb::GridPtrVec& grids) {
  std::string list;
  for (const auto& g : grids) {
    list += (list.empty() ? "" : ", ") + g->getName() + " (" + g->valueType() + ")";
  }
  return list.empty() ? "no grids" : list;
}

openvdb::GridBase::Ptr find_grid(const openvdb::GridPtrVec& grids, const std::string& name) {
  for (const auto& g : grids) {
    if (g->getName() == name) return g;
  }
  return nullptr;
}

std::vector<std::string> split_commas(const std::string& text) {
  std::vector<std::string> parts;
  std::size_t pos = 0;
  for (;;) {
    const std::size_t comma = text.find(',', pos);
    parts.push_back(text.substr(pos, comma == std::string::npos ? std::string::npos : comma - pos));
    if (comma == std::string::npos) break;
    pos = comma + 1;
  }
  return parts;
}

/// The names to load: one vector grid, or three scalar grids.
std::vector<std::string> choose_names(const openvdb::GridPtrVec& grids, const std::string& selector,
                                      const std::string& file) {
  const auto fail = [&](const std::string& what) {
    return FormatError(file + ": " + what + " (the file holds " + grid_list(grids) + ")");
  };
  if (!selector.empty()) {
    const std::vector<std::string> parts = split_commas(selector);
    if (parts.size() == 1) {
      const auto g = find_grid(grids, selector);
      if (!g) throw fail("no grid named '" + selector + "'");
      if (!is_vector_type(*g)) {
        throw fail("grid '" + selector + "' holds " + g->valueType() +
                   " values, not vectors (name three scalar grids as FILE.vdb:x,y,z)");
      }
      return {selector};
    }
    if (parts.size() != 3) throw fail("grid selector '" + selector + "' names neither 1 nor 3 grids");
    for (const std::string& part : parts) {
      const auto g = find_grid(grids, part);
      if (!g) throw fail("no grid named '" + part + "'");
      if (!is_scalar_type(*g))
        throw fail("grid '" + part + "' holds " + g->valueType() + " values, not float or double scalars");
    }
    return parts;
  }
  for (const auto& g : grids) {
    if (is_vector_type(*g)) return {g->getName()};
  }
  std::vector<std::array<std::string, 3>> triples = {
      {"x", "y", "z"}, {"u", "v", "w"}, {"vx", "vy", "vz"}, {"X", "Y", "Z"}, {"U", "V", "W"}};
  for (const auto& g : grids) {
    const std::string& n = g->getName();
    if (n.size() > 2 && n.ends_with(".x")) {
      const std::string stem = n.substr(0, n.size() - 2);
      triples.push_back({stem + ".x", stem + ".y", stem + ".z"});
    }
  }
  for (const auto& triple : triples) {
    bool complete = true;
    for (const std::string& name : triple) {
      const auto g = find_grid(grids, name);
      complete = complete && g && is_scalar_type(*g);
    }
    if (complete) return {triple[0], triple[1], triple[2]};
  }
  throw fail("no Vec3f/Vec3d grid and no x/y/z, u/v/w or NAME.x/.y/.z scalar grids");
}

template <typename ScalarGrid, typename VecGrid>
typename VecGrid::Ptr combine(const std::array<openvdb::GridBase::Ptr, 3>& parts) {
  using VecT = typename VecGrid::ValueType;
  auto out = VecGrid::create(VecT(0));
  out->setTransform(parts[0]->transform().copy());
  std::array<typename ScalarGrid::Ptr, 3> typed;
  for (std::size_t c = 0; c < 3; ++c) {
    // Float and double scalar grids may be mixed: convert through double.
    if (auto same = openvdb::gridPtrCast<ScalarGrid>(parts[c])) {
      typed[c] = same;
    } else {
      typed[c] = ScalarGrid::create(0);
      typed[c]->setTransform(parts[c]->transform().copy());
      if (auto f = openvdb::gridPtrCast<openvdb::FloatGrid>(parts[c])) {
        for (auto it = f->cbeginValueOn(); it; ++it) {
          openvdb::CoordBBox box;
          it.getBoundingBox(box);
          typed[c]->fill(box, static_cast<typename ScalarGrid::ValueType>(*it), true);
        }
      } else if (auto d = openvdb::gridPtrCast<openvdb::DoubleGrid>(parts[c])) {
        for (auto it = d->cbeginValueOn(); it; ++it) {
          openvdb::CoordBBox box;
          it.getBoundingBox(box);
          typed[c]->fill(box, static_cast<typename ScalarGrid::ValueType>(*it), true);
        }
      }
    }
  }
  auto acc = out->getAccessor();
  auto acc_y = typed[1]->getConstAccessor();
  auto acc_z = typed[2]->getConstAccessor();
  for (auto it = typed[0]->cbeginValueOn(); it; ++it) {
    openvdb::CoordBBox box;
    it.getBoundingBox(box);
    for (auto ijk = box.begin(); ijk; ++ijk) {
      typename ScalarGrid::ValueType vy{};
      typename ScalarGrid::ValueType vz{};
      if (acc_y.probeValue(*ijk, vy) && acc_z.probeValue(*ijk, vz))
        acc.setValue(*ijk, VecT(*it, vy, vz));
    }
  }
  return out;
}

int metadata_int(const openvdb::GridBase& g, const char* key, int fallback) {
  if (auto m = g.getMetadata<openvdb::Int32Metadata>(key)) return m->value();
  return fallback;
}

/// Converts an OpenVDB exception into ours.
[[noreturn]] void rethrow_vdb(const std::string& file) {
  try {
    throw;
  } catch (const openvdb::Exception& e) {
    // OpenVDB quotes bytes of a damaged file in its messages (a grid type of 8 KB of blanks):
    // runs of white space become one blank, and the message is cut at 300 characters.
    std::string what;
    for (const char c : std::string(e.what())) {
      const bool blank = std::isspace(static_cast<unsigned char>(c)) != 0;
      if (blank && (what.empty() || what.back() == ' ')) continue;
      what += std::isprint(static_cast<unsigned char>(c)) != 0 && !blank ? c : ' ';
    }
    if (what.size() > 300) what = what.substr(0, 300) + "...";
    throw FormatError(file + ": not a readable OpenVDB file: " + what);
  } catch (const std::ios_base::failure& e) {
    throw IoError("cannot read " + file + ": " + e.what());
  }
}

/// Memory and time for reading a file of `bytes` in a child: a valid file expands to at most a few
/// times its size (tiles stay tiles); a generous margin over that still stops a 12 KB file from
/// claiming gigabytes.
ChildReadLimits vdb_read_limits(std::size_t bytes) {
  ChildReadLimits limits;
  limits.memory_bytes = (std::size_t{1} << 30) + 64 * bytes;
  limits.seconds = child_read_seconds(bytes);
  return limits;
}

/// Every read this process may make of a file, in full: all grids without delayed loading (as
/// read_vdb_file), and each grid with delayed loading and then every leaf buffer loaded (as
/// load_vdb_grid and the series, which touch leaves later).
void read_vdb_file_every_way(const std::filesystem::path& path) {
  {
    openvdb::io::File file(path.string());
    file.open(false);
    (void)file.getGrids();
    file.close();
  }
  openvdb::io::File file(path.string());
  file.open(true);
  const auto metadata = file.readAllGridMetadata();
  for (const auto& grid : *metadata) file.readGrid(grid->getName())->readNonresidentBuffers();
  file.close();
}

/// OpenVDB's reader trusts its input: a corrupt file can fail an assertion, loop or allocate
/// gigabytes in it (fuzzing found all three). Each file is read first in a child process under
/// limits (io/child_read.h), once per file version, before this process reads it.
void vet_vdb_file(const std::filesystem::path& path, const std::string& where) {
  if (files_trusted()) return;
  // Each file version is vetted once; a refusal is remembered too (a hang costs its time limit).
  static std::mutex mutex;
  static std::map<std::string, std::optional<std::string>> vetted;  // key -> the refusal, if any
  std::error_code ec;
  const auto bytes = std::filesystem::file_size(path, ec);
  const auto stamp = std::filesystem::last_write_time(path, ec).time_since_epoch().count();
  const std::string key = std::filesystem::absolute(path).string() + '\n' + std::to_string(bytes) +
                          '\n' + std::to_string(stamp);
  {
    const std::lock_guard<std::mutex> lock(mutex);
    const auto known = vetted.find(key);
    if (known != vetted.end()) {
      if (!known->second) return;
      throw FormatError(*known->second);
    }
  }
  std::optional<std::string> refusal;
  try {
    read_in_child(where, "OpenVDB",
                  [&] {
                    try {
                      read_vdb_file_every_way(path);
                    } catch (...) {
                      rethrow_vdb(where);
                    }
                  },
                  vdb_read_limits(ec ? 0 : bytes));
  } catch (const FormatError& e) {
    refusal = e.what();
  }
  {
    const std::lock_guard<std::mutex> lock(mutex);
    vetted.emplace(key, refusal);
  }
  if (refusal) throw FormatError(*refusal);
}

}  // namespace

LoadedVdbGrid select_vdb_grid(const openvdb::GridPtrVec& grids, const std::string& selector,
                              const std::string& file) {
  const std::vector<std::string> names = choose_names(grids, selector, file);
  LoadedVdbGrid loaded;
  if (names.size() == 1) {
    const auto g = find_grid(grids, names[0]);
    loaded.grid_f = openvdb::gridPtrCast<openvdb::Vec3SGrid>(g);
    loaded.grid_d = openvdb::gridPtrCast<openvdb::Vec3DGrid>(g);
    loaded.name = names[0];
  } else {
    std::array<openvdb::GridBase::Ptr, 3> parts;
    bool any_double = false;
    for (std::size_t c = 0; c < 3; ++c) {
      parts[c] = find_grid(grids, names[c]);
      any_double = any_double || parts[c]->isType<openvdb::DoubleGrid>();
      if (parts[c]->transform() != parts[0]->transform()) {
        throw FormatError(file + ": scalar grids '" + names[0] + "' and '" + names[c] +
                          "' have different transforms");
      }
    }
    if (any_double) {
      loaded.grid_d = combine<openvdb::DoubleGrid, openvdb::Vec3DGrid>(parts);
    } else {
      loaded.grid_f = combine<openvdb::FloatGrid, openvdb::Vec3SGrid>(parts);
    }
    loaded.name = names[0] + "," + names[1] + "," + names[2];
    for (const auto& part : parts) {
      if (part->getGridClass() == openvdb::GRID_STAGGERED) loaded.staggered = true;
    }
    if (loaded.grid_d) loaded.grid_d->setName(loaded.name);
    if (loaded.grid_f) loaded.grid_f->setName(loaded.name);
    return loaded;
  }
  const openvdb::GridBase& base = loaded.base();
  loaded.staggered = base.getGridClass() == openvdb::GRID_STAGGERED;
  loaded.components = metadata_int(base, kComponents, 3) == 2 ? 2 : 3;
  return loaded;
}

openvdb::GridPtrVecPtr read_vdb_file(const std::filesystem::path& path) {
  module::initialize_openvdb();
  if (const std::string why = why_unreadable(path); !why.empty())
    throw IoError("cannot read " + path.string() + ": " + why);
  note_input(path);
  vet_vdb_file(path, path.string());
  try {
    openvdb::io::File file(path.string());
    file.open(false);
    auto grids = file.getGrids();
    file.close();
    return grids;
  } catch (...) {
    rethrow_vdb(path.string());
  }
}

openvdb::GridPtrVecPtr read_vdb_stream(std::istream& in, const std::string& file) {
  module::initialize_openvdb();
  // As for files (vet_vdb_file): the stream is read in a child first.
  const std::streampos start = in.tellg();
  if (!files_trusted()) {
    read_in_child(file, "OpenVDB",
                  [&] {
                    try {
                      openvdb::io::Stream stream(in, false);
                      (void)stream.getGrids();
                    } catch (...) {
                      rethrow_vdb(file);
                    }
                  },
                  vdb_read_limits(0));
  }
  in.clear();
  in.seekg(start);
  try {
    openvdb::io::Stream stream(in, false);
    return stream.getGrids();
  } catch (...) {
    rethrow_vdb(file);
  }
}

LoadedVdbGrid load_vdb_grid(const std::filesystem::path& path, const std::string& selector,
                            const std::string& where) {
  module::initialize_openvdb();
  if (const std::string why = why_unreadable(path); !why.empty())
    throw IoError("cannot read " + path.string() + ": " + why);
  note_input(path);
  vet_vdb_file(path, where);
  openvdb::GridPtrVec chosen;
  try {
    openvdb::io::File file(path.string());
    file.open();
    const auto metadata = file.readAllGridMetadata();
    for (const std::string& name : choose_names(*metadata, selector, where)) {
      chosen.push_back(file.readGrid(name));
    }
    file.close();
  } catch (const Error&) {
    throw;
  } catch (...) {
    rethrow_vdb(where);
  }
  return select_vdb_grid(chosen, selector, where);
}

openvdb::CoordBBox dense_index_box(const LoadedVdbGrid& grid) {
  const openvdb::GridBase& base = grid.base();
  openvdb::CoordBBox box = base.evalActiveVoxelBoundingBox();
  const auto lo = base.getMetadata<openvdb::Vec3IMetadata>(kIndexMin);
  const auto hi = base.getMetadata<openvdb::Vec3IMetadata>(kIndexMax);
  if (lo && hi) {
    box.expand(openvdb::CoordBBox(openvdb::Coord(lo->value()), openvdb::Coord(hi->value())));
  }
  return box;
}

namespace {

template <typename GridT>
void fill_dense(const GridT& grid, bool staggered, const openvdb::CoordBBox& box,
                int components, std::vector<float>& values) {
  using VecT = typename GridT::ValueType;
  auto acc = grid.getConstUnsafeAccessor();
  const openvdb::Coord lo = box.min();
  const openvdb::Coord dim = box.dim();
  const auto nc = static_cast<std::size_t>(components);
  std::size_t at = 0;
  for (int k = 0; k < dim.z(); ++k) {
    for (int j = 0; j < dim.y(); ++j) {
      for (int i = 0; i < dim.x(); ++i, at += nc) {
        const openvdb::Coord ijk = lo + openvdb::Coord(i, j, k);
        VecT v;
        if (!staggered) {
          if (!acc.probeValue(ijk, v)) continue;
          for (std::size_t c = 0; c < nc; ++c) values[at + c] = static_cast<float>(v[static_cast<int>(c)]);
          continue;
        }
        // Staggered: component c is stored at the face ijk - e_c / 2; the centre value is the
        // mean of the faces at ijk and ijk + e_c (what StaggeredBoxSampler gives at ijk).
        std::array<double, 3> centre{};
        bool ok = true;
        for (int c = 0; c < 3 && ok; ++c) {
          openvdb::Coord next = ijk;
          next[c] += 1;
          VecT a;
          VecT b;
          ok = acc.probeValue(ijk, a) && acc.probeValue(next, b);
          centre[static_cast<std::size_t>(c)] = 0.5 * (static_cast<double>(a[c]) + static_cast<double>(b[c]));
        }
        if (!ok) continue;
        for (std::size_t c = 0; c < nc; ++c) values[at + c] = static_cast<float>(centre[c]);
      }
    }
  }
}

}  // namespace

VectorGrid densify(const LoadedVdbGrid& grid, const openvdb::CoordBBox& box, const std::string& file) {
  const openvdb::GridBase& base = grid.base();
  const openvdb::math::Transform& xform = base.transform();
  const std::string what = file + ": grid '" + grid.name + "'";
  if (!xform.isLinear()) throw FormatError(what + " has a non-linear (frustum) transform");
  const openvdb::Mat4d m = xform.baseMap()->getAffineMap()->getMat4();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      if (r != c && m(r, c) != 0.0) {
        throw FormatError(what + " has a rotated or sheared transform; a dense grid needs "
                                 "axis-aligned voxels (sample it as a field instead)");
      }
    }
  }
  if (box.empty()) throw FormatError(what + " has no active voxels");
  VectorGrid out;
  GridGeometry& g = out.geometry;
  const openvdb::Coord dim = box.dim();
  g.size = {dim.x(), dim.y(), dim.z()};
  g.dimension = dim.z() == 1 ? 2 : 3;
  const openvdb::Vec3d origin = xform.indexToWorld(box.min());
  for (int a = 0; a < 3; ++a) {
    g.origin[a] = origin[a];
    g.spacing[a] = m(a, a);
  }
  out.components = grid.components;
  const std::size_t points = checked_point_count(g.size, out.components, file, "VDB box");
  // A sparse grid's box can be vast (two voxels far apart, or a damaged file): a dense copy must
  // fit in memory, judged against half the machine's physical memory before allocating.
  const double dense_bytes = static_cast<double>(points) * out.components * sizeof(float);
  const double memory = static_cast<double>(::sysconf(_SC_PHYS_PAGES)) *
                        static_cast<double>(::sysconf(_SC_PAGESIZE));
  if (memory > 0 && dense_bytes > memory / 2) {
    char text[160];
    std::snprintf(text, sizeof text,
                  " over its active box %d x %d x %d would need %.3g GiB, more than half of this "
                  "machine's %.3g GiB",
                  dim.x(), dim.y(), dim.z(), dense_bytes / 0x1p30, memory / 0x1p30);
    throw FormatError(what + ": a dense copy" + text +
                      " (a sparse grid over a vast region, or a damaged file)");
  }
  out.values.assign(points * static_cast<std::size_t>(out.components),
                    std::numeric_limits<float>::quiet_NaN());
  if (grid.grid_f) {
    fill_dense(*grid.grid_f, grid.staggered, box, out.components, out.values);
  } else {
    fill_dense(*grid.grid_d, grid.staggered, box, out.components, out.values);
  }
  validate_grid(out, file);
  return out;
}

openvdb::Vec3SGrid::Ptr to_vdb(const VectorGrid& grid, const std::string& name) {
  module::initialize_openvdb();
  const GridGeometry& g = grid.geometry;
  if (g.rectilinear()) {
    throw InvalidArgument("grid '" + name +
                          "' is rectilinear; OpenVDB stores uniform voxels only (resample it first)");
  }
  if (grid.components != 2 && grid.components != 3)
    throw InvalidArgument("grid '" + name + "' has " + std::to_string(grid.components) + " components");
  if (grid.values.size() != g.point_count() * static_cast<std::size_t>(grid.components))
    throw InvalidArgument("grid '" + name + "' has a value count that does not match its size");
  for (std::size_t a = 0; a < 3; ++a) {
    if (g.size[a] > std::numeric_limits<std::int32_t>::max())
      throw InvalidArgument("grid '" + name + "' is too large for OpenVDB's 32-bit coordinates");
  }
  auto out = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.0f));
  auto xform = openvdb::math::Transform::createLinearTransform(1.0);
  xform->preScale(openvdb::Vec3d(g.spacing[0], g.spacing[1], g.spacing[2]));
  xform->postTranslate(openvdb::Vec3d(g.origin[0], g.origin[1], g.origin[2]));
  out->setTransform(xform);
  out->setName(name);
  auto acc = out->getAccessor();
  const auto nc = static_cast<std::size_t>(grid.components);
  for (std::int64_t k = 0; k < g.size[2]; ++k) {
    for (std::int64_t j = 0; j < g.size[1]; ++j) {
      for (std::int64_t i = 0; i < g.size[0]; ++i) {
        const float* v = grid.values.data() + g.index(i, j, k) * nc;
        openvdb::Vec3s value(v[0], v[1], nc == 3 ? v[2] : 0.0f);
        if (std::isnan(value[0]) || std::isnan(value[1]) || std::isnan(value[2])) continue;
        acc.setValue(openvdb::Coord(static_cast<int>(i), static_cast<int>(j), static_cast<int>(k)), value);
      }
    }
  }
  out->insertMeta(kComponents, openvdb::Int32Metadata(grid.components));
  out->insertMeta(kIndexMin, openvdb::Vec3IMetadata(openvdb::Vec3i(0, 0, 0)));
  out->insertMeta(kIndexMax, openvdb::Vec3IMetadata(openvdb::Vec3i(static_cast<int>(g.size[0] - 1),
                                                                   static_cast<int>(g.size[1] - 1),
                                                                   static_cast<int>(g.size[2] - 1))));
  return out;
}

}  // namespace detail

namespace module {

std::vector<VdbGridInfo> list_vdb_grids(const std::filesystem::path& path) {
  initialize_openvdb();
  if (const std::string why = why_unreadable(path); !why.empty())
    throw IoError("cannot read " + path.string() + ": " + why);
  detail::vet_vdb_file(path, path.string());
  openvdb::GridPtrVecPtr grids;
  try {
    openvdb::io::File file(path.string());
    file.open();
    grids = file.readAllGridMetadata();
    file.close();
  } catch (...) {
    detail::rethrow_vdb(path.string());
  }
  std::vector<VdbGridInfo> infos;
  for (const auto& g : *grids) {
    VdbGridInfo info;
    info.name = g->getName();
    info.value_type = g->valueType();
    info.grid_class = openvdb::GridBase::gridClassToString(g->getGridClass());
    const openvdb::Vec3d voxel = g->transform().voxelSize();
    info.voxel_size = Vec3(voxel[0], voxel[1], voxel[2]);
    const auto lo = g->getMetadata<openvdb::Vec3IMetadata>(openvdb::GridBase::META_FILE_BBOX_MIN);
    const auto hi = g->getMetadata<openvdb::Vec3IMetadata>(openvdb::GridBase::META_FILE_BBOX_MAX);
    if (lo && hi) {
      info.index_box = {lo->value()[0], lo->value()[1], lo->value()[2],
                        hi->value()[0], hi->value()[1], hi->value()[2]};
    }
    if (const auto n = g->getMetadata<openvdb::Int64Metadata>(openvdb::GridBase::META_FILE_VOXEL_COUNT))
      info.active_voxels = static_cast<std::uint64_t>(n->value());
    if (const auto t = g->getMetadata<openvdb::DoubleMetadata>("time")) info.time = t->value();
    if (const auto t = g->getMetadata<openvdb::FloatMetadata>("time")) info.time = t->value();
    infos.push_back(info);
  }
  return infos;
}

VectorGrid read_vdb_grid(const std::filesystem::path& path, const std::string& selector) {
  const detail::LoadedVdbGrid grid = detail::load_vdb_grid(path, selector, path.string());
  return detail::densify(grid, detail::dense_index_box(grid), path.string());
}

VectorGrid parse_vdb_grid(std::string_view content, const std::string& file,
                          const std::string& selector) {
  std::istringstream in{std::string(content)};
  const auto grids = detail::read_vdb_stream(in, file);
  const detail::LoadedVdbGrid grid = detail::select_vdb_grid(*grids, selector, file);
  return detail::densify(grid, detail::dense_index_box(grid), file);
}

/// VdbFileWriter's work: grids converted as they come, written on commit().
class Writer final : public VdbFileWriter::Impl {
 public:
  explicit Writer(std::filesystem::path path) : path_(std::move(path)) {
    initialize_openvdb();
    check_writable(path_);
  }

  void add(const std::string& name, const VectorGrid& grid, std::optional<double> time) override {
    if (name.empty()) throw InvalidArgument("write_vdb: a grid needs a name");
    if (!names_.insert(name).second)
      throw InvalidArgument("write_vdb: two grids are named '" + name + "'");
    auto vdb = detail::to_vdb(grid, name);
    if (time) vdb->insertMeta("time", openvdb::DoubleMetadata(*time));
    grids_.push_back(vdb);
  }

  std::size_t grids() const override { return grids_.size(); }

  void commit() override;

 private:
  std::filesystem::path path_;
  openvdb::GridPtrVec grids_;
  std::set<std::string> names_;
};

void Writer::commit() {
  const std::filesystem::path& path = path_;
  const std::filesystem::path temp = temporary_path(path);
  try {
    openvdb::io::File file(temp.string());
    file.write(grids_);
    file.close();
    // OpenVDB does not check its stream after writing: a full disk leaves a truncated file
    // without an error. Reading every voxel back (no delayed loading) is the check.
    bool complete = false;
    try {
      openvdb::io::File check(temp.string());
      check.open(false);
      const openvdb::GridPtrVecPtr back = check.getGrids();
      check.close();
      complete = back && back->size() == grids_.size();
    } catch (const std::exception&) {
      complete = false;
    }
    if (!complete) {
      std::error_code error;
      const auto written = std::filesystem::file_size(temp, error);
      const auto space = std::filesystem::space(temp.parent_path().empty() ? "." : temp.parent_path(), error);
      throw std::runtime_error("the file did not read back after writing (" +
                               std::to_string(written) + " bytes written, " +
                               std::to_string(error ? 0 : space.available) +
                               " bytes free: is the disk full?)");
    }
    std::filesystem::rename(temp, path);
  } catch (const std::exception& e) {
    std::error_code ignored;
    std::filesystem::remove(temp, ignored);
    throw IoError("cannot write " + path.string() + ": " + e.what());
  }
}

// ---------------------------------------------------------------------------------------------
// Time series

namespace {

class VdbSeries final : public TimeSeries {
 public:
  VdbSeries(std::vector<VdbStep> steps, std::vector<double> times)
      : steps_(std::move(steps)), times_(std::move(times)) {
    if (steps_.empty()) throw InvalidArgument("a VDB time series needs at least one step");
    if (steps_.size() != times_.size()) {
      throw InvalidArgument(std::to_string(steps_.size()) + " VDB steps but " +
                            std::to_string(times_.size()) + " times");
    }
    for (std::size_t i = 0; i < times_.size(); ++i) {
      if (!std::isfinite(times_[i]) || (i > 0 && !(times_[i] > times_[i - 1])))
        throw InvalidArgument("times must be finite and strictly increasing (step " + std::to_string(i) + ")");
    }
    // Every step's box and transform, from its grid (loaded once here).
    openvdb::CoordBBox box;
    for (std::size_t s = 0; s < steps_.size(); ++s) {
      const detail::LoadedVdbGrid grid = load(s);
      const openvdb::CoordBBox step_box = detail::dense_index_box(grid);
      if (step_box.empty()) throw FormatError(where(s) + ": grid '" + grid.name + "' has no active voxels");
      box.expand(step_box);
      if (s == 0) {
        transform_ = grid.base().transform().copy();
        components_ = grid.components;
      } else if (grid.base().transform() != *transform_) {
        throw FormatError(where(s) + ": grid '" + grid.name +
                          "' has a different transform (voxel size or origin) than step 0");
      } else if (grid.components != components_) {
        throw FormatError(where(s) + ": grid '" + grid.name + "' has a different component count");
      }
    }
    box_ = box;
    // The geometry, from a densified (empty) box: the same code path as every step.
    detail::LoadedVdbGrid empty;
    empty.grid_f = openvdb::Vec3SGrid::create();
    empty.grid_f->setTransform(transform_->copy());
    empty.components = components_;
    empty.name = "geometry";
    geometry_ = detail::densify(empty, box_, steps_.front().file.string()).geometry;
  }

  std::size_t step_count() const override { return steps_.size(); }
  double time(std::size_t step) const override { return times_.at(step); }
  const GridGeometry& geometry() const override { return geometry_; }
  int components() const override { return components_; }
  std::string describe() const override {
    std::ostringstream out;
    out << steps_.size() << " OpenVDB grid" << (steps_.size() == 1 ? "" : "s") << " ("
        << steps_.front().file.filename().string();
    if (!steps_.front().selector.empty()) out << ":" << steps_.front().selector;
    if (steps_.size() > 1) {
      out << " .. " << steps_.back().file.filename().string();
      if (!steps_.back().selector.empty()) out << ":" << steps_.back().selector;
    }
    out << "), " << detail::size_text(geometry_) << " x " << components_;
    return out.str();
  }

  /// Bricks of 32³ voxels from the dense box's corner. OpenVDB reads a grid's topology first and
  /// a leaf's voxels (8³) only when they are accessed, so a brick reads just its leaves.
  BrickLayout bricks() const override { return BrickLayout::cubes(geometry_, kBrick); }

  RawStep read_raw_brick(std::size_t step, std::size_t brick) const override {
    if (step >= steps_.size()) throw InvalidArgument("step " + std::to_string(step) + " out of range");
    const BrickLayout layout = bricks();
    if (brick >= layout.bricks())
      throw InvalidArgument("brick " + std::to_string(brick) + " out of range");
    const auto b = static_cast<std::int64_t>(brick);
    const openvdb::Coord first = box_.min() + openvdb::Coord(
        static_cast<int>(b % layout.count[0] * kBrick),
        static_cast<int>(b / layout.count[0] % layout.count[1] * kBrick),
        geometry_.dimension == 3 ? static_cast<int>(b / (layout.count[0] * layout.count[1]) * kBrick) : 0);
    openvdb::CoordBBox region(first, first + openvdb::Coord(static_cast<int>(layout.size[0]) - 1,
                                                            static_cast<int>(layout.size[1]) - 1,
                                                            static_cast<int>(layout.size[2]) - 1));
    region.intersect(box_);
    const VectorGrid part = detail::densify(cached(step), region, where(step) + ", brick " +
                                                                     std::to_string(brick));
    // Into the brick's layout: layout.size points per axis, padded past the dense box.
    const auto c = static_cast<std::size_t>(components_);
    std::vector<float> values(layout.brick_points() * c, std::numeric_limits<float>::quiet_NaN());
    const openvdb::Coord dim = region.dim();
    for (int k = 0; k < dim.z(); ++k)
      for (int j = 0; j < dim.y(); ++j)
        std::memcpy(values.data() + static_cast<std::size_t>((k * layout.size[1] + j) * layout.size[0]) * c,
                    part.values.data() + part.geometry.index(0, j, k) * c,
                    static_cast<std::size_t>(dim.x()) * c * sizeof(float));
    RawStep raw;
    raw.step = step;
    raw.brick = brick;
    raw.bytes.resize(values.size() * sizeof(float));
    std::memcpy(raw.bytes.data(), values.data(), raw.bytes.size());
    return raw;
  }
  void decode_brick(const RawStep& raw, std::span<float> values) const override {
    if (raw.bytes.size() != values.size_bytes())
      throw FormatError(where(raw.step) + ": brick of " + std::to_string(raw.bytes.size()) +
                        " bytes, expected " + std::to_string(values.size_bytes()));
    std::memcpy(values.data(), raw.bytes.data(), raw.bytes.size());
  }

  RawStep read_raw(std::size_t step) const override {
    if (step >= steps_.size()) throw InvalidArgument("step " + std::to_string(step) + " out of range");
    const VectorGrid dense = detail::densify(load(step), box_, where(step));
    RawStep raw;
    raw.step = step;
    raw.encoded = false;
    raw.bytes.resize(dense.bytes());
    std::memcpy(raw.bytes.data(), dense.values.data(), dense.bytes());
    return raw;
  }

 private:
  std::string where(std::size_t s) const {
    return steps_[s].file.string() + " (step " + std::to_string(s) + ")";
  }

  detail::LoadedVdbGrid load(std::size_t s) const {
    return detail::load_vdb_grid(steps_[s].file, steps_[s].selector, where(s));
  }

  // The grids of the steps read last (topology, leaves loaded as touched), most recent first:
  // brick reads of a band revisit a few steps many times. Used by the one reader thread.
  const detail::LoadedVdbGrid& cached(std::size_t s) const {
    const auto hit =
        std::find_if(open_.begin(), open_.end(), [s](const OpenStep& o) { return o.step == s; });
    if (hit != open_.end()) {
      open_.splice(open_.begin(), open_, hit);
    } else {
      detail::LoadedVdbGrid grid = load(s);
      if (open_.size() == kOpenSteps) open_.pop_back();
      open_.push_front(OpenStep{s, std::move(grid)});
    }
    return open_.front().grid;
  }

  static constexpr std::int64_t kBrick = 32;
  static constexpr std::size_t kOpenSteps = 16;
  struct OpenStep {
    std::size_t step = 0;
    detail::LoadedVdbGrid grid;
  };
  mutable std::list<OpenStep> open_;
  std::vector<VdbStep> steps_;
  std::vector<double> times_;
  openvdb::math::Transform::Ptr transform_;
  openvdb::CoordBBox box_;
  GridGeometry geometry_;
  int components_ = 3;
};

}  // namespace

std::unique_ptr<TimeSeries> open_vdb_series(std::vector<VdbStep> steps, std::vector<double> times) {
  return std::make_unique<VdbSeries>(std::move(steps), std::move(times));
}

std::unique_ptr<TimeSeries> open_vdb_file_series(const std::filesystem::path& path) {
  std::vector<std::pair<std::optional<double>, std::string>> entries;
  for (const VdbGridInfo& info : module::list_vdb_grids(path)) {
    if (info.value_type == "vec3s" || info.value_type == "vec3d") entries.emplace_back(info.time, info.name);
  }
  if (entries.empty()) throw FormatError(path.string() + ": no Vec3f/Vec3d grids for a time series");
  const auto timed = std::count_if(entries.begin(), entries.end(), [](const auto& e) { return e.first.has_value(); });
  if (timed != 0 && timed != static_cast<std::ptrdiff_t>(entries.size()))
    throw FormatError(path.string() + ": some vector grids have \"time\" metadata and some do not");
  if (timed != 0) {
    std::stable_sort(entries.begin(), entries.end(), [](const auto& a, const auto& b) { return *a.first < *b.first; });
  }
  std::vector<VdbStep> steps;
  std::vector<double> times;
  for (std::size_t i = 0; i < entries.size(); ++i) {
    steps.push_back(VdbStep{path, entries[i].second});
    times.push_back(timed != 0 ? *entries[i].first : static_cast<double>(i));
  }
  return module::open_vdb_series(std::move(steps), std::move(times));
}

std::unique_ptr<VdbFileWriter::Impl> open_vdb_writer(const std::filesystem::path& path) {
  return std::make_unique<Writer>(path);
}

std::unique_ptr<VdbField> open_vdb_field(const std::filesystem::path& path,
                                         const std::string& selector);  // vdb_field.cpp
std::unique_ptr<VdbField> vdb_field_from_grid(const VectorGrid& grid, const std::string& name);

}  // namespace module

}  // namespace orthofront::io

extern "C" const orthofront::io::VdbModule* orthofront_vdb_module() {
  namespace m = orthofront::io::module;
  static const orthofront::io::VdbModule table{
      m::initialize_openvdb, m::list_vdb_grids,   m::read_vdb_grid,
      m::parse_vdb_grid,     m::open_vdb_writer,  m::open_vdb_series,
      m::open_vdb_file_series, m::open_vdb_field, m::vdb_field_from_grid};
  return &table;
}
