// Reading the HDF5 layout: description, steady reads, and time series with raw chunk reads
// (H5Dread_chunk) decoded in parallel.
#include <tbb/blocked_range.h>
#include <blosc.h>
#include <tbb/parallel_for.h>
#include <zlib.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <map>
#include <mutex>
#include <optional>

#include "orthofront/error.h"
#include "orthofront/huge_pages.h"
#include "orthofront/io/child_read.h"
#include "orthofront/io/error.h"
#include "orthofront/io/hdf5_detail.h"
#include "orthofront/io/input_files.h"
#include "orthofront/io/readable_file.h"

namespace orthofront::io {

using detail::H5Id;

namespace {

/// True in the child process that vets a file (vet_hdf5_file): its own opens are not vetted again,
/// and it checks every dataset's storage against the file's length.
bool vetting_child = false;

void vet_hdf5_file(const std::filesystem::path& path, const std::string& group,
                   const Hdf5ReadOptions& options);

std::string number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.17g", value);
  return text;
}

std::string shape_text(const std::vector<hsize_t>& dims) {
  std::string text;
  for (hsize_t d : dims) text += "[" + std::to_string(d) + "]";
  return text;
}

std::string step_name(std::size_t step) {
  char name[32];
  std::snprintf(name, sizeof name, "%06zu", step);
  return name;
}

bool link_exists(hid_t location, const std::string& name) {
  return H5Lexists(location, name.c_str(), H5P_DEFAULT) > 0;
}

std::vector<hsize_t> dataset_shape(hid_t set) {
  H5Id space(H5Dget_space(set), H5Sclose);
  const int rank = H5Sget_simple_extent_ndims(space.get());
  std::vector<hsize_t> dims(static_cast<std::size_t>(std::max(rank, 0)));
  if (rank > 0) H5Sget_simple_extent_dims(space.get(), dims.data(), nullptr);
  return dims;
}

std::string type_text(hid_t type) {
  const H5T_class_t type_class = H5Tget_class(type);
  const std::size_t bits = 8 * H5Tget_size(type);
  const char* order = H5Tget_order(type) == H5T_ORDER_BE ? " big-endian" : " little-endian";
  switch (type_class) {
    case H5T_FLOAT:
      return "float" + std::to_string(bits) + order;
    case H5T_INTEGER:
      return (H5Tget_sign(type) == H5T_SGN_NONE ? "uint" : "int") + std::to_string(bits) + order;
    case H5T_STRING:
      return "string";
    case H5T_COMPOUND:
      return "compound";
    default:
      return "type class " + std::to_string(static_cast<int>(type_class));
  }
}

// Layout of RawStep::bytes for encoded steps: a ChunkCount, ChunkRecords, then the payloads.
struct ChunkRecord {
  std::uint64_t first_slice;
  std::uint64_t slices;
  std::uint64_t bytes;
  std::uint32_t filter_mask;
  std::uint32_t reserved;
};

}  // namespace

/// Everything an open field group needs; shared by describe_hdf5, read_hdf5_grid and the series.
struct Hdf5TimeSeries::Impl {
  Hdf5Description d;
  Hdf5ReadOptions options;
  H5Id file, group, dataset, steps;
  detail::SliceLayout layout;
  BrickLayout bricks;                 // bricked storage; otherwise the whole step
  std::vector<H5Z_filter_t> filters;  // pipeline order
  bool raw = false;                   // raw chunk reads possible and wanted

  std::string where() const { return d.file.string(); }
  std::string step_where(std::size_t step) const {
    return where() + ": step " + std::to_string(step) + " of '" +
           (d.storage == Hdf5Storage::per_step ? detail::child_path(d.dataset, step_name(step))
                                               : d.dataset) +
           "'";
  }

  Impl(const std::filesystem::path& path, const std::string& group_path,
       const Hdf5ReadOptions& read_options)
      : options(read_options) {
    detail::silence_hdf5();
    detail::register_blosc_filter();
    d.file = path;
    if (const std::string why = why_unreadable(path); !why.empty())
      throw IoError("cannot open " + path.string() + ": " + why);
    if (H5Fis_hdf5(path.c_str()) <= 0)
      throw FormatError(path.string() + " is not an HDF5 file (or cannot be read)");
    if (!vetting_child) vet_hdf5_file(path, group_path, read_options);
    file = H5Id(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
    if (file.valid()) note_input(path);
    if (!file.valid()) {
      // HDF5 says why on its error stack; a truncated file is the common case, worth plain words.
      const std::string cause = detail::hdf5_error_cause();
      unsigned long long eof = 0, base = 0, stored = 0;
      if (std::sscanf(cause.c_str(), "truncated file: eof = %llu, sblock->base_addr = %llu, stored_eof = %llu",
                      &eof, &base, &stored) == 3)
        throw IoError("cannot open HDF5 file " + path.string() + ": truncated: the file has " +
                      std::to_string(eof) + " bytes, its superblock says " + std::to_string(stored) +
                      " (cut short in a copy or download, or still being written?)");
      throw IoError("cannot open HDF5 file " + path.string() +
                    (cause.empty() ? std::string() : ": " + cause));
    }

    const std::string object_path = detail::normalize_group(group_path);
    std::string velocity_name = "velocity";
    d.group = object_path;
    if (object_path != "/") {
      for (std::size_t p = object_path.find('/', 1);; p = object_path.find('/', p + 1)) {
        const std::string prefix = object_path.substr(0, p);
        if (!link_exists(file.get(), prefix))
          throw FormatError(where() + ": no group or dataset '" + prefix + "'");
        if (p == std::string::npos) break;
      }
      H5Id object(H5Oopen(file.get(), object_path.c_str(), H5P_DEFAULT), H5Oclose);
      if (H5Iget_type(object.get()) == H5I_DATASET) {
        const std::size_t slash = object_path.rfind('/');
        d.group = slash == 0 ? "/" : object_path.substr(0, slash);
        velocity_name = object_path.substr(slash + 1);
      } else if (H5Iget_type(object.get()) != H5I_GROUP) {
        throw FormatError(where() + ": '" + object_path + "' is neither a group nor a dataset");
      }
    }
    group = H5Id(H5Gopen2(file.get(), d.group.c_str(), H5P_DEFAULT), H5Gclose);
    if (!group.valid()) throw FormatError(where() + ": cannot open group '" + d.group + "'");
    const std::string group_where = where() + ": group '" + d.group + "'";
    const std::string velocity_path = detail::child_path(d.group, velocity_name);
    const std::string times_path = detail::child_path(d.group, "times");

    // Storage and the dataset that defines the shape.
    std::vector<hsize_t> shape;
    H5Id shape_set;
    std::string shape_path;
    if (link_exists(group.get(), "times")) {
      read_times(times_path);
      if (link_exists(group.get(), velocity_name)) {
        d.storage = Hdf5Storage::chunked;
        d.dataset = velocity_path;
      } else if (link_exists(group.get(), "steps")) {
        d.storage = Hdf5Storage::per_step;
        d.dataset = detail::child_path(d.group, "steps");
        steps = H5Id(H5Gopen2(group.get(), "steps", H5P_DEFAULT), H5Gclose);
        if (!steps.valid())
          throw FormatError(where() + ": '" + d.dataset + "' is not a group of step datasets");
      } else {
        throw FormatError(where() + ": '" + times_path + "' exists but there is no dataset '" +
                          velocity_path + "' (chunked series) nor group '" +
                          detail::child_path(d.group, "steps") + "' (one dataset per step)");
      }
    } else {
      if (!link_exists(group.get(), velocity_name))
        throw FormatError(where() + ": no dataset '" + velocity_path + "' (steady field) nor '" +
                          times_path + "' (time series)");
      d.storage = Hdf5Storage::steady;
      d.dataset = velocity_path;
    }
    if (d.storage == Hdf5Storage::per_step) {
      shape_path = detail::child_path(d.dataset, step_name(0));
      if (!link_exists(steps.get(), step_name(0)))
        throw FormatError(where() + ": no dataset '" + shape_path + "' (step 0)");
      shape_set = H5Id(H5Dopen2(steps.get(), step_name(0).c_str(), H5P_DEFAULT), H5Dclose);
    } else {
      shape_path = d.dataset;
      dataset = H5Id(H5Dopen2(group.get(), velocity_name.c_str(), H5P_DEFAULT), H5Dclose);
      if (!dataset.valid()) throw FormatError(where() + ": '" + d.dataset + "' is not a dataset");
    }
    const hid_t samples = d.storage == Hdf5Storage::per_step ? shape_set.get() : dataset.get();
    if (samples < 0) throw FormatError(where() + ": '" + shape_path + "' is not a dataset");
    shape = dataset_shape(samples);

    // Shape: [T][nz][ny][nx][C] (chunked, bricked), [nz][ny][nx][C] (steady, per step); 2D
    // without nz.
    const bool series_axis = has_step_axis(d.storage);
    const int leading = series_axis ? 1 : 0;
    const int spatial = static_cast<int>(shape.size()) - 1 - leading;
    const std::string expected = std::string(series_axis ? "[steps]" : "") +
                                 "[nz][ny][nx][components] (3D) or " +
                                 (series_axis ? "[steps]" : "") + "[ny][nx][components] (2D)";
    if (spatial != 2 && spatial != 3)
      throw FormatError(where() + ": dataset '" + shape_path + "' has shape " + shape_text(shape) +
                        "; expected " + expected);
    if (shape.back() != 2 && shape.back() != 3)
      throw FormatError(where() + ": dataset '" + shape_path +
                        "' is not a vector field: its last dimension is " +
                        std::to_string(shape.back()) + " (expected 2 or 3 components), shape " +
                        shape_text(shape));
    d.components = static_cast<int>(shape.back());
    if (series_axis && shape[0] != d.times.size())
      throw FormatError(where() + ": dataset '" + shape_path + "' holds " +
                        std::to_string(shape[0]) + " steps but '" + times_path + "' has " +
                        std::to_string(d.times.size()) + " times");
    GridGeometry& g = d.geometry;
    g.dimension = spatial;
    const auto at = [&](int i) {
      return static_cast<std::int64_t>(shape[static_cast<std::size_t>(leading + i)]);
    };
    g.size = spatial == 3 ? std::array<std::int64_t, 3>{at(2), at(1), at(0)}
                          : std::array<std::int64_t, 3>{at(1), at(0), 1};
    for (std::int64_t n : g.size)
      if (n < 1)
        throw FormatError(where() + ": dataset '" + shape_path + "' is empty, shape " +
                          shape_text(shape));
    if (auto dimension = detail::read_doubles_attribute(group.get(), "dimension", group_where))
      if ((*dimension)[0] != spatial)
        throw FormatError(group_where + ": attribute 'dimension' is " + number((*dimension)[0]) +
                          " but dataset '" + shape_path + "' has shape " + shape_text(shape) +
                          " (" + std::to_string(spatial) + "D)");
    if (auto components = detail::read_doubles_attribute(group.get(), "components", group_where))
      if ((*components)[0] != d.components)
        throw FormatError(group_where + ": attribute 'components' is " + number((*components)[0]) +
                          " but dataset '" + shape_path + "' has last dimension " +
                          std::to_string(d.components));
    read_geometry(group_where, shape_path);

    // Per-step datasets must agree. A missing one is recorded, not fatal here: reading that step
    // fails, naming it, so a surface stops there and keeps what it built before.
    if (d.storage == Hdf5Storage::per_step) {
      for (std::size_t s = 1; s < d.times.size(); ++s) {
        const std::string name = step_name(s);
        const std::string path_s = detail::child_path(d.dataset, name);
        if (!link_exists(steps.get(), name)) {
          d.missing_steps.push_back(s);
          continue;
        }
        H5Id set(H5Dopen2(steps.get(), name.c_str(), H5P_DEFAULT), H5Dclose);
        if (!set.valid()) throw FormatError(where() + ": '" + path_s + "' is not a dataset");
        const auto other = dataset_shape(set.get());
        if (other != shape)
          throw FormatError(where() + ": dataset '" + path_s + "' has shape " + shape_text(other) +
                            " but step 0 has " + shape_text(shape));
        d.stored_bytes += H5Dget_storage_size(set.get());
      }
    }
    d.stored_bytes += H5Dget_storage_size(samples);

    // Metadata.
    d.units.length =
        detail::read_string_attribute(group.get(), "units_length", group_where).value_or("");
    d.units.time =
        detail::read_string_attribute(group.get(), "units_time", group_where).value_or("");
    d.units.velocity =
        detail::read_string_attribute(group.get(), "units_velocity", group_where).value_or("");
    for (hid_t holder : {group.get(), samples}) {
      for (const char* name : {"fill_value", "_FillValue"}) {
        if (d.fill_value) break;
        if (auto fill = detail::read_doubles_attribute(holder, name, group_where))
          d.fill_value = static_cast<float>((*fill)[0]);
      }
    }
    if (auto zero = detail::read_doubles_attribute(group.get(), "zero_is_no_data", group_where))
      d.zero_is_no_data = (*zero)[0] != 0;

    // Type, filters, chunks.
    H5Id type(H5Dget_type(samples), H5Tclose);
    d.stored_type = type_text(type.get());
    const H5T_class_t type_class = H5Tget_class(type.get());
    if (type_class != H5T_FLOAT && type_class != H5T_INTEGER)
      throw FormatError(where() + ": dataset '" + shape_path + "' holds " + d.stored_type +
                        " values, not numbers");
    H5Id create(H5Dget_create_plist(samples), H5Pclose);
    const int filter_count = H5Pget_nfilters(create.get());
    for (int i = 0; i < filter_count; ++i) {
      unsigned flags = 0, config = 0;
      std::size_t values = 8;
      unsigned cd[8] = {};
      char name[64] = {};
      const H5Z_filter_t id = H5Pget_filter2(create.get(), static_cast<unsigned>(i), &flags,
                                             &values, cd, sizeof name, name, &config);
      filters.push_back(id);
      d.filters.push_back(id == H5Z_FILTER_DEFLATE   ? "deflate"
                          : id == H5Z_FILTER_SHUFFLE ? "shuffle"
                          : name[0] != 0             ? name
                                                     : "filter " + std::to_string(id));
      if (id == H5Z_FILTER_DEFLATE && values > 0) d.gzip_level = static_cast<int>(cd[0]);
      if (id == kBloscFilterId) {
        const char* compressor = "blosc";
        if (values > 6) blosc_compcode_to_compname(static_cast<int>(cd[6]), &compressor);
        d.filters.back() = std::string("blosc ") + compressor +
                           (values > 4 ? " level " + std::to_string(cd[4]) : std::string());
      }
    }
    layout = detail::slice_layout(g, d.components, std::numeric_limits<std::size_t>::max());
    bricks = BrickLayout::whole(g);
    if (H5Pget_layout(create.get()) == H5D_CHUNKED) {
      std::vector<hsize_t> chunk(shape.size());
      H5Pget_chunk(create.get(), static_cast<int>(chunk.size()), chunk.data());
      d.chunk_slices = static_cast<std::int64_t>(chunk[static_cast<std::size_t>(leading)]);
      layout.chunk_slices = d.chunk_slices;
      // Raw reads need whole steps split into whole slices only, in our float32 LE encoding.
      bool whole_slices = !series_axis || chunk[0] == 1;
      for (std::size_t i = static_cast<std::size_t>(leading) + 1; i < shape.size(); ++i)
        whole_slices = whole_slices && chunk[i] == shape[i];
      // Bricked: one chunk per brick and step ([1][bz][by][bx][C]), read brick by brick.
      const std::string storage_name =
          detail::read_string_attribute(group.get(), "storage", group_where).value_or("");
      if (series_axis && chunk[0] == 1 && chunk.back() == shape.back() &&
          (storage_name == "bricked" || !whole_slices)) {
        d.storage = Hdf5Storage::bricked;
        const std::size_t n = chunk.size();
        d.brick = {static_cast<std::int64_t>(chunk[n - 2]), static_cast<std::int64_t>(chunk[n - 3]),
                   g.dimension == 3 ? static_cast<std::int64_t>(chunk[n - 4]) : 1};
        bricks.size = d.brick;
        for (std::size_t a = 0; a < 3; ++a)
          bricks.count[a] = (g.size[a] + bricks.size[a] - 1) / bricks.size[a];
      }
      const bool bricked = d.storage == Hdf5Storage::bricked;
      bool known_filters = !filters.empty() || bricked;
      for (std::size_t i = 0; i < filters.size(); ++i)
        known_filters =
            known_filters && (filters[i] == H5Z_FILTER_DEFLATE || filters[i] == kBloscFilterId ||
                              (filters[i] == H5Z_FILTER_SHUFFLE && i + 1 < filters.size()));
      raw = options.raw_chunks && (whole_slices || bricked) && known_filters &&
            std::endian::native == std::endian::little && H5Tequal(type.get(), H5T_IEEE_F32LE) > 0;
    }
    if (vetting_child) check_storage();
  }

  /// The stored bytes of the chunk at `offset` of `set`; 0 for a chunk never written. For a
  /// filtered dataset with a step axis, one lookup in the chunk index: H5Dget_chunk_info_by_coord
  /// walks every chunk stored before the one asked for, so its cost grows with the chunk's place
  /// in the index and held back the reading of large series (figures:
  /// docs/benchmarks/measurements.md).
  /// Unfiltered, HDF5 1.10 reports the chunk's nominal size instead of the stored one (which
  /// H5Dread_chunk copies), and a chunk never written looks stored once HDF5 has filled it.
  hsize_t stored_chunk_bytes(hid_t set, const hsize_t* offset) const {
    hsize_t bytes = 0;
    if (set == dataset.get() && !filters.empty())
      return H5Dget_chunk_storage_size(set, offset, &bytes) >= 0 ? bytes : 0;
    unsigned mask = 0;
    haddr_t address = HADDR_UNDEF;
    const bool stored = H5Dget_chunk_info_by_coord(set, offset, &mask, &address, &bytes) >= 0 &&
                        address != HADDR_UNDEF;
    return stored ? bytes : 0;
  }

  /// Every sample dataset's storage lies inside the file: contiguous data, and each chunk the
  /// index lists (the index itself is walked in full). HDF5 reads what its metadata says without
  /// such checks, and a damaged index or layout makes it copy out of bounds.
  void check_storage() const {
    const auto file_bytes = static_cast<haddr_t>(std::filesystem::file_size(d.file));
    const auto check_set = [&](hid_t set, const std::string& name) {
      const std::string what = where() + ": dataset '" + name + "'";
      H5Id plist(H5Dget_create_plist(set), H5Pclose);
      H5Id space(H5Dget_space(set), H5Sclose);
      const int rank = H5Sget_simple_extent_ndims(space.get());
      if (!plist.valid() || !space.valid() || rank < 1 || rank > 8)
        throw FormatError(what + ": unreadable layout or shape (damaged file?)");
      std::vector<hsize_t> dims(static_cast<std::size_t>(rank));
      H5Sget_simple_extent_dims(space.get(), dims.data(), nullptr);
      const H5D_layout_t kind = H5Pget_layout(plist.get());
      // Whatever the layout, the bytes stored are in the file.
      if (H5Dget_storage_size(set) > file_bytes)
        throw FormatError(what + ": claims " + std::to_string(H5Dget_storage_size(set)) +
                          " bytes of samples in a file of " + std::to_string(file_bytes) +
                          " (damaged file?)");
      if (kind == H5D_CONTIGUOUS) {
        const haddr_t offset = H5Dget_offset(set);
        const hsize_t stored = H5Dget_storage_size(set);
        if (offset != HADDR_UNDEF && (offset > file_bytes || stored > file_bytes - offset))
          throw FormatError(what + ": its samples lie past the end of the file (damaged file?)");
        return;
      }
      if (kind != H5D_CHUNKED) return;  // compact data lives in the object header HDF5 parsed
      std::vector<hsize_t> chunk(dims.size());
      if (H5Pget_chunk(plist.get(), rank, chunk.data()) != rank)
        throw FormatError(what + ": unreadable chunk shape (damaged file?)");
      H5Id type(H5Dget_type(set), H5Tclose);
      hsize_t chunk_bytes = type.valid() ? H5Tget_size(type.get()) : 0;
      for (const hsize_t n : chunk) chunk_bytes *= n;
      const bool unfiltered = H5Pget_nfilters(plist.get()) == 0;
      std::vector<hsize_t> counts(dims.size()), at(dims.size(), 0);
      std::uint64_t total = 1;
      for (std::size_t a = 0; a < dims.size(); ++a) {
        if (chunk[a] == 0) throw FormatError(what + ": chunk of size 0 (damaged file?)");
        counts[a] = (dims[a] + chunk[a] - 1) / chunk[a];
        total *= std::max<hsize_t>(counts[a], 1);
        if (total > (std::uint64_t{1} << 26))
          throw FormatError(what + ": more than 2^26 chunks (damaged file?)");
      }
      // HDF5 1.10 finds a chunk by coordinate with a linear scan of its index, so a walk of every
      // chunk is quadratic in their number (tens of thousands of chunks take seconds). Up to
      // 2,048 chunks all are checked; beyond, 256 spread evenly over the index, first and last
      // included.
      constexpr std::uint64_t kAll = 2048, kSample = 256;
      const std::uint64_t checks = total <= kAll ? total : kSample;
      for (std::uint64_t k = 0; k < checks; ++k) {
        const std::uint64_t c = checks == total ? k : k * (total - 1) / (kSample - 1);
        std::uint64_t rest = c;
        for (std::size_t a = dims.size(); a-- > 0;) {
          at[a] = rest % std::max<hsize_t>(counts[a], 1) * chunk[a];
          rest /= std::max<hsize_t>(counts[a], 1);
        }
        unsigned mask = 0;
        haddr_t address = HADDR_UNDEF;
        hsize_t bytes = 0;
        if (H5Dget_chunk_info_by_coord(set, at.data(), &mask, &address, &bytes) < 0)
          throw FormatError(what + ": unreadable chunk index (damaged file?)");
        if (address != HADDR_UNDEF && (address > file_bytes || bytes > file_bytes - address))
          throw FormatError(what + ": a chunk lies past the end of the file (damaged file?)");
        // Unfiltered chunks are stored at their exact size; HDF5 copies that many bytes out of
        // a buffer of the stored size.
        if (address != HADDR_UNDEF && unfiltered && bytes != chunk_bytes)
          throw FormatError(what + ": a chunk of " + std::to_string(bytes) + " bytes where " +
                            std::to_string(chunk_bytes) + " are stored (damaged file?)");
      }
    };
    if (d.storage == Hdf5Storage::per_step) {
      for (std::size_t s = 0; s < d.step_count(); ++s) {
        // A missing step is reported when it is read (the surface stops there), not at open.
        if (std::find(d.missing_steps.begin(), d.missing_steps.end(), s) != d.missing_steps.end())
          continue;
        H5Id holder;
        check_set(step_dataset(s, holder), detail::child_path(d.dataset, step_name(s)));
      }
    } else {
      check_set(dataset.get(), d.dataset);
    }
  }

  void read_times(const std::string& times_path) {
    H5Id set(H5Dopen2(group.get(), "times", H5P_DEFAULT), H5Dclose);
    if (!set.valid()) throw FormatError(where() + ": '" + times_path + "' is not a dataset");
    const auto shape = dataset_shape(set.get());
    if (shape.size() != 1)
      throw FormatError(where() + ": dataset '" + times_path + "' has shape " + shape_text(shape) +
                        "; expected one dimension");
    if (shape[0] == 0)
      throw FormatError(where() + ": dataset '" + times_path +
                        "' is empty: a time series needs at least one step");
    d.times.resize(shape[0]);
    if (H5Dread(set.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, d.times.data()) < 0)
      throw FormatError(where() + ": cannot read dataset '" + times_path + "'");
    for (std::size_t i = 0; i < d.times.size(); ++i) {
      if (!std::isfinite(d.times[i]))
        throw FormatError(where() + ": dataset '" + times_path + "': times[" + std::to_string(i) +
                          "] = " + number(d.times[i]) + " is not finite");
      if (i > 0 && !(d.times[i] > d.times[i - 1]))
        throw FormatError(where() + ": dataset '" + times_path +
                          "' is not strictly increasing: times[" + std::to_string(i) +
                          "] = " + number(d.times[i]) + " after times[" + std::to_string(i - 1) +
                          "] = " + number(d.times[i - 1]));
    }
  }

  void read_geometry(const std::string& group_where, const std::string& shape_path) {
    GridGeometry& g = d.geometry;
    const int n = g.dimension;
    if (link_exists(group.get(), "x")) {
      for (int a = 0; a < 3; ++a) {
        const std::string name(1, static_cast<char>('x' + a));
        const std::string path_a = detail::child_path(d.group, name);
        auto& axis = g.axes[static_cast<std::size_t>(a)];
        if (a == 2 && n == 2 && !link_exists(group.get(), name)) {
          axis = {0.0};
          continue;
        }
        if (!link_exists(group.get(), name))
          throw FormatError(where() + ": rectilinear grid without dataset '" + path_a + "'");
        H5Id set(H5Dopen2(group.get(), name.c_str(), H5P_DEFAULT), H5Dclose);
        const auto shape = set.valid() ? dataset_shape(set.get()) : std::vector<hsize_t>{};
        const auto expected = static_cast<hsize_t>(g.size[static_cast<std::size_t>(a)]);
        if (shape.size() != 1 || shape[0] != expected)
          throw FormatError(where() + ": dataset '" + path_a + "' has shape " + shape_text(shape) +
                            " but '" + shape_path + "' has " + std::to_string(expected) +
                            " samples along " + name);
        axis.resize(expected);
        if (H5Dread(set.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, axis.data()) < 0)
          throw FormatError(where() + ": cannot read dataset '" + path_a + "'");
        for (std::size_t i = 0; i < axis.size(); ++i)
          if (!std::isfinite(axis[i]) || (i > 0 && !(axis[i] > axis[i - 1])))
            throw FormatError(where() + ": dataset '" + path_a +
                              "' must be finite and strictly increasing; entry " +
                              std::to_string(i) + " is " + number(axis[i]));
      }
      return;
    }
    const auto origin = detail::read_doubles_attribute(group.get(), "origin", group_where);
    if (!origin)
      throw FormatError(group_where +
                        " has no attribute 'origin' (uniform grid) nor datasets "
                        "'x', 'y', 'z' (rectilinear grid)");
    const auto spacing = detail::read_doubles_attribute(group.get(), "spacing", group_where);
    if (!spacing) throw FormatError(group_where + " has no attribute 'spacing'");
    const auto check_count = [&](const std::vector<double>& values, const char* name) {
      if (values.size() != 3 && !(n == 2 && values.size() == 2))
        throw FormatError(group_where + ": attribute '" + name + "' has " +
                          std::to_string(values.size()) + " values; expected " +
                          (n == 2 ? "2 or 3" : "3"));
    };
    check_count(*origin, "origin");
    check_count(*spacing, "spacing");
    for (int a = 0; a < 3; ++a) {
      const auto ua = static_cast<std::size_t>(a);
      g.origin[a] = ua < origin->size() ? (*origin)[ua] : 0.0;
      g.spacing[a] = ua < spacing->size() ? (*spacing)[ua] : 1.0;
      if (!std::isfinite(g.origin[a]))
        throw FormatError(group_where + ": attribute 'origin' has a non-finite value " +
                          number(g.origin[a]));
      if (a < n && (!std::isfinite(g.spacing[a]) || !(g.spacing[a] > 0)))
        throw FormatError(group_where + ": attribute 'spacing' must be finite and positive; " +
                          std::string(1, static_cast<char>('x' + a)) + " spacing is " +
                          number(g.spacing[a]));
    }
  }

  hid_t step_dataset(std::size_t step, H5Id& holder) const {
    if (d.storage != Hdf5Storage::per_step) return dataset.get();
    if (!link_exists(steps.get(), step_name(step)))
      throw FormatError(where() + ": no dataset '" + detail::child_path(d.dataset, step_name(step)) +
                        "' (step " + std::to_string(step) + " of " + std::to_string(d.times.size()) +
                        ")");
    holder = H5Id(H5Dopen2(steps.get(), step_name(step).c_str(), H5P_DEFAULT), H5Dclose);
    if (!holder.valid()) throw FormatError(step_where(step) + ": cannot open the dataset");
    return holder.get();
  }

  RawStep read_plain(std::size_t step, hid_t set) const {
    RawStep out{step, {}, false};
    const auto shape = detail::step_shape(d.geometry, d.components);
    reserve_huge_pages(out.bytes, d.step_bytes());
    out.bytes.resize(d.step_bytes());
    H5Id memory(H5Screate_simple(static_cast<int>(shape.size()), shape.data(), nullptr), H5Sclose);
    H5Id file_space(H5Dget_space(set), H5Sclose);
    if (has_step_axis(d.storage)) {
      std::vector<hsize_t> start(shape.size() + 1, 0), count{1};
      start[0] = step;
      count.insert(count.end(), shape.begin(), shape.end());
      H5Sselect_hyperslab(file_space.get(), H5S_SELECT_SET, start.data(), nullptr, count.data(),
                          nullptr);
    }
    if (H5Dread(set, H5T_NATIVE_FLOAT, memory.get(), file_space.get(), H5P_DEFAULT,
                out.bytes.data()) < 0)
      throw FormatError(step_where(step) + ": cannot read the samples (damaged file?)");
    return out;
  }

  RawStep read_raw(std::size_t step) const {
    if (step >= d.step_count())
      throw InvalidArgument(where() + ": step " + std::to_string(step) + " requested, the " +
                            "series has " + std::to_string(d.step_count()));
    H5Id holder;
    const hid_t set = step_dataset(step, holder);
    if (!raw || d.storage == Hdf5Storage::bricked) return read_plain(step, set);
    const std::int64_t chunks = layout.chunk_count();
    const bool series_axis = has_step_axis(d.storage);
    const std::size_t rank =
        detail::step_shape(d.geometry, d.components).size() + (series_axis ? 1 : 0);
    std::vector<ChunkRecord> records(static_cast<std::size_t>(chunks));
    std::vector<std::vector<hsize_t>> offsets;
    std::size_t payload = 0;
    for (std::int64_t c = 0; c < chunks; ++c) {
      std::vector<hsize_t> offset(rank, 0);
      if (series_axis) offset[0] = step;
      offset[series_axis ? 1 : 0] = static_cast<hsize_t>(c * layout.chunk_slices);
      const hsize_t bytes = stored_chunk_bytes(set, offset.data());
      if (bytes == 0) return read_plain(step, set);  // a chunk never written: HDF5 fills it
      ChunkRecord& r = records[static_cast<std::size_t>(c)];
      r.first_slice = static_cast<std::uint64_t>(c * layout.chunk_slices);
      r.slices = static_cast<std::uint64_t>(
          std::min(layout.chunk_slices, layout.slices - c * layout.chunk_slices));
      r.bytes = bytes;
      payload += bytes;
      offsets.push_back(std::move(offset));
    }
    RawStep out{step, {}, true};
    const std::size_t header = sizeof(std::uint64_t) + records.size() * sizeof(ChunkRecord);
    reserve_huge_pages(out.bytes, header + payload);
    out.bytes.resize(header + payload);
    std::size_t at = header;
    for (std::size_t c = 0; c < records.size(); ++c) {
      std::uint32_t mask = 0;
      if (H5Dread_chunk(set, H5P_DEFAULT, offsets[c].data(), &mask, out.bytes.data() + at) < 0)
        throw FormatError(step_where(step) + ": cannot read chunk " + std::to_string(c));
      records[c].filter_mask = mask;
      at += records[c].bytes;
    }
    const std::uint64_t count = records.size();
    std::memcpy(out.bytes.data(), &count, sizeof count);
    std::memcpy(out.bytes.data() + sizeof count, records.data(),
                records.size() * sizeof(ChunkRecord));
    return out;
  }

  // Undo the filters of one chunk (reverse pipeline order, skipping those the mask marks) into
  // `out`, which holds exactly the chunk's decoded bytes.
  void decode_chunk(const std::byte* data, std::size_t size, std::uint32_t mask,
                    std::span<std::byte> out, const std::string& context) const {
    std::vector<H5Z_filter_t> applied;
    for (std::size_t i = filters.size(); i-- > 0;)
      if ((mask & (1u << i)) == 0) applied.push_back(filters[i]);
    std::vector<std::byte> buffers[2];
    for (std::size_t k = 0; k < applied.size(); ++k) {
      const bool last = k + 1 == applied.size();
      std::vector<std::byte>& scratch = buffers[k % 2];
      std::byte* target = out.data();
      if (!last) {
        reserve_huge_pages(scratch, out.size());
        scratch.resize(out.size());
        target = scratch.data();
      }
      if (applied[k] == H5Z_FILTER_DEFLATE) {
        uLongf produced = static_cast<uLongf>(out.size());
        const int rc = uncompress(reinterpret_cast<Bytef*>(target), &produced,
                                  reinterpret_cast<const Bytef*>(data), static_cast<uLong>(size));
        if (rc != Z_OK || produced != out.size())
          throw FormatError(
              context + ": damaged deflate data (zlib: " +
              (rc == Z_OK ? "wrong length " + std::to_string(produced) : std::string(zError(rc))) +
              ")");
      } else if (applied[k] == kBloscFilterId) {
        detail::blosc_decode(data, size, {target, out.size()}, context);
      } else {  // shuffle
        if (size != out.size())
          throw FormatError(context + ": shuffled chunk of " + std::to_string(size) +
                            " bytes, expected " + std::to_string(out.size()));
        detail::unshuffle4(data, size, target);
      }
      data = target;
      size = out.size();
    }
    if (applied.empty()) {
      if (size != out.size())
        throw FormatError(context + ": unfiltered chunk of " + std::to_string(size) +
                          " bytes, expected " + std::to_string(out.size()));
      std::memcpy(out.data(), data, size);
    }
  }

  void decode(const RawStep& raw_step, std::span<float> values) const {
    if (values.size() * sizeof(float) != d.step_bytes())
      throw InvalidArgument(where() + ": decode needs a buffer of " +
                            std::to_string(d.step_bytes() / sizeof(float)) + " floats, got " +
                            std::to_string(values.size()));
    const std::string context = step_where(raw_step.step);
    if (!raw_step.encoded) {
      if (raw_step.bytes.size() != d.step_bytes())
        throw FormatError(context + ": " + std::to_string(raw_step.bytes.size()) +
                          " bytes read, expected " + std::to_string(d.step_bytes()));
      std::memcpy(values.data(), raw_step.bytes.data(), d.step_bytes());
    } else {
      std::uint64_t count = 0;
      const std::byte* base = raw_step.bytes.data();
      const std::size_t total = raw_step.bytes.size();
      if (total < sizeof count) throw FormatError(context + ": truncated raw step");
      std::memcpy(&count, base, sizeof count);
      const std::size_t header = sizeof count + count * sizeof(ChunkRecord);
      if (count != static_cast<std::uint64_t>(layout.chunk_count()) || total < header)
        throw FormatError(context + ": raw step with " + std::to_string(count) +
                          " chunks, expected " + std::to_string(layout.chunk_count()));
      std::vector<ChunkRecord> records(count);
      std::memcpy(records.data(), base + sizeof count, count * sizeof(ChunkRecord));
      std::vector<std::size_t> starts(count);
      std::size_t at = header;
      for (std::size_t c = 0; c < count; ++c) {
        starts[c] = at;
        at += records[c].bytes;
        if (at > total ||
            records[c].first_slice + records[c].slices > static_cast<std::uint64_t>(layout.slices))
          throw FormatError(context + ": raw step inconsistent at chunk " + std::to_string(c));
      }
      const std::size_t slice_bytes = layout.slice_floats * sizeof(float);
      auto* out = reinterpret_cast<std::byte*>(values.data());
      // HDF5 stores edge chunks at full size (padded past the last slice): decode those into a
      // scratch buffer and keep the slices that exist.
      const std::size_t chunk_bytes = static_cast<std::size_t>(layout.chunk_slices) * slice_bytes;
      tbb::parallel_for(std::size_t{0}, static_cast<std::size_t>(count), [&](std::size_t c) {
        const ChunkRecord& r = records[c];
        std::byte* target = out + r.first_slice * slice_bytes;
        const std::string chunk_context = context + ", chunk " + std::to_string(c);
        if (r.slices * slice_bytes == chunk_bytes) {
          decode_chunk(base + starts[c], r.bytes, r.filter_mask, {target, chunk_bytes},
                       chunk_context);
        } else {
          std::vector<std::byte> full(chunk_bytes);
          decode_chunk(base + starts[c], r.bytes, r.filter_mask, full, chunk_context);
          std::memcpy(target, full.data(), r.slices * slice_bytes);
        }
      });
    }
    if (d.fill_value && !std::isnan(*d.fill_value)) {
      const float fill = *d.fill_value;
      const float nan = std::numeric_limits<float>::quiet_NaN();
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, values.size(), 1 << 16),
                        [&](const tbb::blocked_range<std::size_t>& r) {
                          for (std::size_t i = r.begin(); i != r.end(); ++i)
                            if (values[i] == fill) values[i] = nan;
                        });
    }
  }

  std::string brick_where(std::size_t step, std::size_t brick) const {
    return step_where(step) + ", brick " + std::to_string(brick);
  }

  // Offset of a brick's chunk in the dataset: [step][k0][j0][i0][0] (2D: [step][j0][i0][0]).
  std::vector<hsize_t> brick_offset(std::size_t step, std::size_t brick) const {
    const auto b = static_cast<std::int64_t>(brick);
    const std::int64_t bi = b % bricks.count[0], bj = (b / bricks.count[0]) % bricks.count[1],
                       bk = b / (bricks.count[0] * bricks.count[1]);
    std::vector<hsize_t> offset(d.geometry.dimension == 3 ? 5 : 4, 0);
    offset[0] = step;
    const std::size_t n = offset.size();
    offset[n - 2] = static_cast<hsize_t>(bi * bricks.size[0]);
    offset[n - 3] = static_cast<hsize_t>(bj * bricks.size[1]);
    if (d.geometry.dimension == 3) offset[n - 4] = static_cast<hsize_t>(bk * bricks.size[2]);
    return offset;
  }

  std::size_t brick_bytes() const {
    return bricks.brick_points() * static_cast<std::size_t>(d.components) * sizeof(float);
  }

  RawStep read_raw_brick(std::size_t step, std::size_t brick) const {
    if (d.storage != Hdf5Storage::bricked) {
      RawStep whole = read_raw(step);
      whole.brick = brick;
      return whole;
    }
    if (step >= d.step_count() || brick >= bricks.bricks())
      throw InvalidArgument(where() + ": brick " + std::to_string(brick) + " of step " +
                            std::to_string(step) + " requested; the series has " +
                            std::to_string(d.step_count()) + " steps of " +
                            std::to_string(bricks.bricks()) + " bricks");
    const std::vector<hsize_t> offset = brick_offset(step, brick);
    RawStep out{step, {}, raw, brick, 0};
    // A chunk never written reads as HDF5's fill values, as the whole-step read does.
    const hsize_t bytes = raw ? stored_chunk_bytes(dataset.get(), offset.data()) : 0;
    const bool written = bytes > 0;
    if (!written) {  // HDF5 decodes: read the brick's region into a padded brick
      out.encoded = false;
      out.bytes.assign(brick_bytes(), std::byte{0});
      std::vector<hsize_t> count(offset.size(), 1);
      std::vector<hsize_t> memory_dims(offset.size(), 1);
      const std::size_t n = offset.size();
      const GridGeometry& g = d.geometry;
      for (std::size_t a = 0; a < static_cast<std::size_t>(g.dimension); ++a) {
        count[n - 2 - a] = static_cast<hsize_t>(
            std::min<std::int64_t>(bricks.size[a], g.size[a] - static_cast<std::int64_t>(offset[n - 2 - a])));
        memory_dims[n - 2 - a] = static_cast<hsize_t>(bricks.size[a]);
      }
      count[n - 1] = memory_dims[n - 1] = static_cast<hsize_t>(d.components);
      H5Id file_space(H5Dget_space(dataset.get()), H5Sclose);
      H5Sselect_hyperslab(file_space.get(), H5S_SELECT_SET, offset.data(), nullptr, count.data(),
                          nullptr);
      H5Id memory(H5Screate_simple(static_cast<int>(n), memory_dims.data(), nullptr), H5Sclose);
      const std::vector<hsize_t> zero(n, 0);
      H5Sselect_hyperslab(memory.get(), H5S_SELECT_SET, zero.data(), nullptr, count.data(),
                          nullptr);
      if (H5Dread(dataset.get(), H5T_NATIVE_FLOAT, memory.get(), file_space.get(), H5P_DEFAULT,
                  out.bytes.data()) < 0)
        throw FormatError(brick_where(step, brick) + ": cannot read the samples (damaged file?)");
      return out;
    }
    // A stored chunk is at most its decoded size plus a codec's overhead: refuse anything larger
    // before allocating (a damaged index could claim gigabytes).
    if (bytes > brick_bytes() + (std::size_t{1} << 16))
      throw FormatError(brick_where(step, brick) + ": stored chunk of " + std::to_string(bytes) +
                        " bytes for a brick of " + std::to_string(brick_bytes()) +
                        " bytes (damaged file?)");
    out.bytes.resize(bytes);
    std::uint32_t mask = 0;
    if (H5Dread_chunk(dataset.get(), H5P_DEFAULT, offset.data(), &mask, out.bytes.data()) < 0)
      throw FormatError(brick_where(step, brick) + ": cannot read the chunk (damaged file?)");
    out.filter_mask = mask;
    return out;
  }

  void decode_brick(const RawStep& raw_brick, std::span<float> values) const {
    if (d.storage != Hdf5Storage::bricked) return decode(raw_brick, values);
    if (values.size() * sizeof(float) != brick_bytes())
      throw InvalidArgument(where() + ": decode_brick needs a buffer of " +
                            std::to_string(brick_bytes() / sizeof(float)) + " floats, got " +
                            std::to_string(values.size()));
    const std::string context = brick_where(raw_brick.step, raw_brick.brick);
    std::span<std::byte> out(reinterpret_cast<std::byte*>(values.data()), brick_bytes());
    if (!raw_brick.encoded) {
      if (raw_brick.bytes.size() != out.size())
        throw FormatError(context + ": " + std::to_string(raw_brick.bytes.size()) +
                          " bytes read, expected " + std::to_string(out.size()));
      std::memcpy(out.data(), raw_brick.bytes.data(), out.size());
    } else {
      decode_chunk(raw_brick.bytes.data(), raw_brick.bytes.size(), raw_brick.filter_mask, out,
                   context);
    }
    if (d.fill_value && !std::isnan(*d.fill_value)) {
      const float fill = *d.fill_value;
      for (float& v : values)
        if (v == fill) v = std::numeric_limits<float>::quiet_NaN();
    }
  }
};

Hdf5TimeSeries::Hdf5TimeSeries(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Hdf5TimeSeries::~Hdf5TimeSeries() = default;
std::size_t Hdf5TimeSeries::step_count() const {
  return impl_->d.step_count();
}
double Hdf5TimeSeries::time(std::size_t step) const {
  return impl_->d.storage == Hdf5Storage::steady ? 0.0 : impl_->d.times.at(step);
}
const GridGeometry& Hdf5TimeSeries::geometry() const {
  return impl_->d.geometry;
}
int Hdf5TimeSeries::components() const {
  return impl_->d.components;
}
const Hdf5Description& Hdf5TimeSeries::description() const {
  return impl_->d;
}

std::string Hdf5TimeSeries::describe() const {
  const Hdf5Description& d = impl_->d;
  std::string text = d.file.string() + ":" + d.dataset + " (" + to_string(d.storage) + ", " +
                     std::to_string(d.step_count()) +
                     (d.step_count() == 1 ? " step, " : " steps, ") +
                     std::to_string(d.geometry.size[0]) + "x" + std::to_string(d.geometry.size[1]);
  if (d.geometry.dimension == 3) text += "x" + std::to_string(d.geometry.size[2]);
  text += ", " + std::to_string(d.components) + " components";
  for (const std::string& f : d.filters) text += ", " + f;
  if (impl_->raw) text += ", raw chunk reads";
  return text + ")";
}

RawStep Hdf5TimeSeries::read_raw(std::size_t step) const {
  return impl_->read_raw(step);
}
BrickLayout Hdf5TimeSeries::bricks() const { return impl_->bricks; }
RawStep Hdf5TimeSeries::read_raw_brick(std::size_t step, std::size_t brick) const {
  return impl_->read_raw_brick(step, brick);
}
void Hdf5TimeSeries::decode_brick(const RawStep& raw, std::span<float> values) const {
  impl_->decode_brick(raw, values);
}
bool Hdf5TimeSeries::zero_is_no_data() const { return impl_->d.zero_is_no_data; }

void Hdf5TimeSeries::decode(const RawStep& raw, std::span<float> values) const {
  impl_->decode(raw, values);
}

std::unique_ptr<Hdf5TimeSeries> open_hdf5_series(const std::filesystem::path& file,
                                                 const std::string& group,
                                                 const Hdf5ReadOptions& options) {
  auto impl = std::make_unique<Hdf5TimeSeries::Impl>(file, group, options);
  if (impl->d.storage == Hdf5Storage::steady && !options.steady_as_single_step)
    throw FormatError(file.string() + ": '" + impl->d.dataset +
                      "' is a steady field, not a time series (no dataset '" +
                      detail::child_path(impl->d.group, "times") + "')");
  return std::unique_ptr<Hdf5TimeSeries>(new Hdf5TimeSeries(std::move(impl)));
}

Hdf5Description describe_hdf5(const std::filesystem::path& file, const std::string& group) {
  Hdf5ReadOptions options;
  options.steady_as_single_step = true;
  return open_hdf5_series(file, group, options)->description();
}

VectorGrid read_hdf5_grid(const std::filesystem::path& file, const std::string& group,
                          std::size_t step) {
  Hdf5ReadOptions options;
  options.steady_as_single_step = true;
  const auto series = open_hdf5_series(file, group, options);
  VectorGrid grid;
  grid.geometry = series->geometry();
  grid.components = series->components();
  reserve_huge_pages(grid.values, series->step_floats());
  grid.values.resize(series->step_floats());
  series->read(step, grid.values);
  return grid;
}

namespace {

/// libhdf5 trusts a file's metadata: fuzzing found heap overflows in H5Aexists and in H5Dread
/// (H5VM_memcpyvv) on damaged files. Each file is opened first in a child process under limits
/// (io/child_read.h), once per file version and group: the child reads the description, walks
/// every dataset's storage (check_storage) and makes HDF5's reads of the first and last steps the
/// way this process will. Later steps' chunk contents are decoded by the project's own bounded decoders.
void vet_hdf5_file(const std::filesystem::path& path, const std::string& group,
                   const Hdf5ReadOptions& options) {
  if (files_trusted()) return;
  // Each file version is vetted once; a refusal is remembered too (a hang costs its time limit).
  static std::mutex mutex;
  static std::map<std::string, std::optional<std::string>> vetted;  // key -> the refusal, if any
  std::error_code ec;
  const auto bytes = std::filesystem::file_size(path, ec);
  const auto stamp = std::filesystem::last_write_time(path, ec).time_since_epoch().count();
  const std::string key = std::filesystem::absolute(path).string() + '\n' + group + '\n' +
                          std::to_string(bytes) + '\n' + std::to_string(stamp) +
                          (options.raw_chunks ? "\nraw" : "\nhdf5");
  {
    const std::lock_guard<std::mutex> lock(mutex);
    const auto known = vetted.find(key);
    if (known != vetted.end()) {
      if (!known->second) return;
      throw FormatError(*known->second);
    }
  }
  ChildReadLimits limits;
  limits.memory_bytes = (std::size_t{1} << 30) + 4 * static_cast<std::size_t>(ec ? 0 : bytes);
  limits.seconds = child_read_seconds(ec ? 0 : bytes);
  std::optional<std::string> refusal;
  try {
    read_in_child(path.string(), "HDF5",
                  [&] {
                    vetting_child = true;
                    Hdf5ReadOptions o = options;
                    o.steady_as_single_step = true;
                    const auto series = open_hdf5_series(path, group, o);
                    // HDF5's reads only: decoding raw chunks is the project's own bounded code,
                    // and runs on oneTBB, which a forked child must not use (its workers stay in
                    // the parent).
                    const auto& missing = series->description().missing_steps;
                    for (const std::size_t step : {std::size_t{0}, series->step_count() - 1}) {
                      if (std::find(missing.begin(), missing.end(), step) == missing.end())
                        (void)series->read_raw(step);
                    }
                  },
                  limits);
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

bool is_hdf5_file(const std::filesystem::path& file) {
  detail::silence_hdf5();
  std::error_code error;
  return std::filesystem::is_regular_file(file, error) && H5Fis_hdf5(file.c_str()) > 0;
}

}  // namespace orthofront::io
