#include "orthofront/io/hdf5_detail.h"
#include "orthofront/io/xml_text.h"

#include <blosc.h>

#include <cstdio>
#include <cstring>
#include <mutex>

#include "orthofront/io/error.h"

namespace orthofront::io::detail {

std::string hdf5_error_cause() {
  std::string cause;
  // Entries are walked from the innermost call (H5E_WALK_UPWARD): the first one says what failed.
  H5Ewalk2(
      H5E_DEFAULT, H5E_WALK_UPWARD,
      [](unsigned n, const H5E_error2_t* error, void* data) -> herr_t {
        auto* text = static_cast<std::string*>(data);
        if (n == 0 && error != nullptr && error->desc != nullptr) *text = error->desc;
        return 0;
      },
      &cause);
  return cause;
}

void silence_hdf5() {
  // A thread-safe HDF5 keeps the automatic printing setting per thread: readers run on pipeline
  // and TBB threads too.
  thread_local bool silenced = false;
  if (silenced) return;
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  silenced = true;
}

namespace {

// HDF5 filter callback (hdf5-blosc's conventions): forward compresses, reverse decompresses;
// returns the new size, 0 on failure (HDF5 then reports the chunk as unreadable).
std::size_t blosc_filter(unsigned flags, std::size_t cd_count, const unsigned cd[],
                         std::size_t bytes, std::size_t* buffer_size, void** buffer) {
  if ((flags & H5Z_FLAG_REVERSE) != 0) {
    std::size_t decoded = 0;
    if (blosc_cbuffer_validate(*buffer, bytes, &decoded) != 0) return 0;
    // A damaged header could claim any size: a chunk decodes to at most its declared size.
    const std::size_t limit = cd_count > 3 && cd[3] > 0 ? cd[3] : std::size_t{1} << 30;
    if (decoded > limit) return 0;
    void* out = H5allocate_memory(std::max<std::size_t>(decoded, 1), false);
    if (out == nullptr) return 0;
    const int n = blosc_decompress_ctx(*buffer, out, decoded, 1);
    if (n < 0 || static_cast<std::size_t>(n) != decoded) {
      H5free_memory(out);
      return 0;
    }
    H5free_memory(*buffer);
    *buffer = out;
    *buffer_size = decoded;
    return decoded;
  }
  const int level = cd_count > 4 ? static_cast<int>(cd[4]) : 5;
  const int shuffle = cd_count > 5 ? static_cast<int>(cd[5]) : 1;
  const std::size_t type_size = cd_count > 2 && cd[2] > 0 ? cd[2] : 4;
  const char* name = "lz4";
  if (cd_count > 6) blosc_compcode_to_compname(static_cast<int>(cd[6]), &name);
  const std::size_t capacity = bytes + BLOSC_MAX_OVERHEAD;
  void* out = H5allocate_memory(capacity, false);
  if (out == nullptr) return 0;
  const int n = blosc_compress_ctx(level, shuffle, type_size, bytes, *buffer, out, capacity, name,
                                   0, 1);
  if (n <= 0) {
    H5free_memory(out);
    return 0;
  }
  H5free_memory(*buffer);
  *buffer = out;
  *buffer_size = capacity;
  return static_cast<std::size_t>(n);
}

}  // namespace

void register_blosc_filter() {
  static std::once_flag once;
  std::call_once(once, [] {
    if (H5Zfilter_avail(kBloscFilterId) > 0) return;  // a plugin already provides it
    static const H5Z_class2_t filter = {H5Z_CLASS_T_VERS, kBloscFilterId, 1, 1, "blosc",
                                        nullptr, nullptr, blosc_filter};
    H5Zregister(&filter);
  });
}

const char* blosc_compressor(Hdf5Codec codec) { return codec == Hdf5Codec::zstd ? "zstd" : "lz4"; }

int default_level(Hdf5Codec codec) {
  switch (codec) {
    case Hdf5Codec::gzip:
      return 1;
    case Hdf5Codec::lz4:
      return 5;
    case Hdf5Codec::zstd:
      return 1;
    case Hdf5Codec::none:
      break;
  }
  return 0;
}

std::vector<unsigned> blosc_parameters(Hdf5Codec codec, int level, std::size_t chunk_bytes) {
  return {2u,
          static_cast<unsigned>(BLOSC_VERSION_FORMAT),
          4u,
          static_cast<unsigned>(chunk_bytes),
          static_cast<unsigned>(level),
          1u,
          static_cast<unsigned>(codec == Hdf5Codec::zstd ? BLOSC_ZSTD : BLOSC_LZ4)};
}

std::vector<std::byte> blosc_encode(const std::byte* data, std::size_t bytes, Hdf5Codec codec,
                                    int level) {
  std::vector<std::byte> out(bytes + BLOSC_MAX_OVERHEAD);
  const int n = blosc_compress_ctx(level, BLOSC_SHUFFLE, 4, bytes, data, out.data(), out.size(),
                                   blosc_compressor(codec), 0, 1);
  if (n <= 0)
    throw IoError(std::string("Blosc (") + blosc_compressor(codec) + ") failed to compress " +
                  std::to_string(bytes) + " bytes");
  out.resize(static_cast<std::size_t>(n));
  return out;
}

void blosc_decode(const std::byte* data, std::size_t size, std::span<std::byte> out,
                  const std::string& context) {
  std::size_t decoded = 0;
  if (blosc_cbuffer_validate(data, size, &decoded) != 0 || decoded != out.size())
    throw FormatError(context + ": damaged Blosc data (" + std::to_string(size) +
                      " bytes, header says " + std::to_string(decoded) + " decoded, expected " +
                      std::to_string(out.size()) + ")");
  const int n = blosc_decompress_ctx(data, out.data(), out.size(), 1);
  if (n < 0 || static_cast<std::size_t>(n) != out.size())
    throw FormatError(context + ": damaged Blosc data (decompression returned " +
                      std::to_string(n) + ")");
}

std::string normalize_group(const std::string& group) {
  std::string g = group;
  while (g.size() > 1 && g.back() == '/') g.pop_back();
  if (g.empty() || g.front() != '/') g.insert(g.begin(), '/');
  return g;
}

std::string child_path(const std::string& group, const std::string& name) {
  return group == "/" ? "/" + name : group + "/" + name;
}

// --- attributes ------------------------------------------------------------------------------

bool has_attribute(hid_t object, const char* name) {
  return H5Aexists(object, name) > 0;
}

namespace {

[[noreturn]] void write_failed(const char* name) {
  throw IoError(std::string("cannot write HDF5 attribute '") + name + "'");
}

void write_attribute(hid_t object, const char* name, hid_t file_type, hid_t memory_type,
                     const std::vector<hsize_t>& dims, const void* data) {
  if (has_attribute(object, name)) H5Adelete(object, name);
  H5Id space(dims.empty() ? H5Screate(H5S_SCALAR)
                          : H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr),
             H5Sclose);
  H5Id attribute(H5Acreate2(object, name, file_type, space.get(), H5P_DEFAULT, H5P_DEFAULT),
                 H5Aclose);
  if (!attribute.valid() || H5Awrite(attribute.get(), memory_type, data) < 0) write_failed(name);
}

}  // namespace

void write_string_attribute(hid_t object, const char* name, const std::string& value) {
  H5Id type(H5Tcopy(H5T_C_S1), H5Tclose);
  H5Tset_size(type.get(), std::max<std::size_t>(value.size(), 1));
  H5Tset_strpad(type.get(), H5T_STR_NULLPAD);
  H5Tset_cset(type.get(), H5T_CSET_UTF8);
  std::string padded = value;
  if (padded.empty()) padded.push_back('\0');
  write_attribute(object, name, type.get(), type.get(), {}, padded.data());
}

void write_int_attribute(hid_t object, const char* name, int value) {
  write_attribute(object, name, H5T_STD_I32LE, H5T_NATIVE_INT, {}, &value);
}

void write_float_attribute(hid_t object, const char* name, float value) {
  write_attribute(object, name, H5T_IEEE_F32LE, H5T_NATIVE_FLOAT, {}, &value);
}

void write_doubles_attribute(hid_t object, const char* name, std::span<const double> values) {
  write_attribute(object, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, {values.size()}, values.data());
}

std::optional<std::string> read_string_attribute(hid_t object, const char* name,
                                                 const std::string& where) {
  if (!has_attribute(object, name)) return std::nullopt;
  H5Id attribute(H5Aopen(object, name, H5P_DEFAULT), H5Aclose);
  H5Id type(H5Aget_type(attribute.get()), H5Tclose);
  if (H5Tget_class(type.get()) != H5T_STRING)
    throw FormatError(where + ": attribute '" + name + "' is not a string");
  H5Id space(H5Aget_space(attribute.get()), H5Sclose);
  if (H5Sget_simple_extent_npoints(space.get()) != 1)
    throw FormatError(where + ": attribute '" + name + "' is not a single string");
  if (H5Tis_variable_str(type.get()) > 0) {
    H5Id memory(H5Tcopy(H5T_C_S1), H5Tclose);
    H5Tset_size(memory.get(), H5T_VARIABLE);
    char* text = nullptr;
    if (H5Aread(attribute.get(), memory.get(), &text) < 0 || text == nullptr)
      throw FormatError(where + ": cannot read attribute '" + name + "'");
    std::string value(text);
    H5free_memory(text);
    return value;
  }
  const std::size_t size = H5Tget_size(type.get());
  std::string value(size, '\0');
  if (H5Aread(attribute.get(), type.get(), value.data()) < 0)
    throw FormatError(where + ": cannot read attribute '" + name + "'");
  value.resize(value.find('\0') == std::string::npos ? size : value.find('\0'));
  while (!value.empty() && value.back() == ' ') value.pop_back();  // space-padded strings
  return value;
}

std::optional<std::vector<double>> read_doubles_attribute(hid_t object, const char* name,
                                                          const std::string& where) {
  if (!has_attribute(object, name)) return std::nullopt;
  H5Id attribute(H5Aopen(object, name, H5P_DEFAULT), H5Aclose);
  H5Id type(H5Aget_type(attribute.get()), H5Tclose);
  const H5T_class_t type_class = H5Tget_class(type.get());
  if (type_class != H5T_FLOAT && type_class != H5T_INTEGER)
    throw FormatError(where + ": attribute '" + name + "' is not numeric");
  H5Id space(H5Aget_space(attribute.get()), H5Sclose);
  const hssize_t count = H5Sget_simple_extent_npoints(space.get());
  std::vector<double> values(static_cast<std::size_t>(std::max<hssize_t>(count, 0)));
  if (count < 1 || H5Aread(attribute.get(), H5T_NATIVE_DOUBLE, values.data()) < 0)
    throw FormatError(where + ": cannot read attribute '" + name + "'");
  return values;
}

// --- chunk encoding ----------------------------------------------------------------------------

void shuffle4(const std::byte* in, std::size_t bytes, std::byte* out) {
  const std::size_t n = bytes / 4;
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t b = 0; b < 4; ++b) out[b * n + i] = in[4 * i + b];
  for (std::size_t r = 4 * n; r < bytes; ++r) out[r] = in[r];  // HDF5 leaves a tail as is
}

void unshuffle4(const std::byte* in, std::size_t bytes, std::byte* out) {
  const std::size_t n = bytes / 4;
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t b = 0; b < 4; ++b) out[4 * i + b] = in[b * n + i];
  for (std::size_t r = 4 * n; r < bytes; ++r) out[r] = in[r];
}

SliceLayout slice_layout(const GridGeometry& geometry, int components,
                         std::size_t max_chunk_bytes) {
  SliceLayout layout;
  const bool three_d = geometry.dimension == 3;
  layout.slices = three_d ? geometry.size[2] : geometry.size[1];
  layout.slice_floats = static_cast<std::size_t>(geometry.size[0]) *
                        static_cast<std::size_t>(three_d ? geometry.size[1] : 1) *
                        static_cast<std::size_t>(components);
  // HDF5 refuses chunks of 4 GiB or more.
  const std::size_t limit = std::min<std::size_t>(max_chunk_bytes, (std::size_t{1} << 32) - 1);
  const std::size_t slice_bytes = layout.slice_floats * sizeof(float);
  const auto fit = static_cast<std::int64_t>(limit / std::max<std::size_t>(slice_bytes, 1));
  if (fit < 1)
    throw InvalidArgument("one slice of the grid (" + std::to_string(slice_bytes) +
                          " bytes) exceeds the chunk limit of " + std::to_string(limit) + " bytes");
  // As few chunks as the limit allows, of equal size: the padding of the last chunk (HDF5 stores
  // whole chunks) stays below one slice per chunk.
  const std::int64_t chunks = (layout.slices + fit - 1) / fit;
  layout.chunk_slices = (layout.slices + chunks - 1) / chunks;
  return layout;
}

std::vector<hsize_t> step_shape(const GridGeometry& geometry, int components) {
  std::vector<hsize_t> shape;
  if (geometry.dimension == 3) shape.push_back(static_cast<hsize_t>(geometry.size[2]));
  shape.push_back(static_cast<hsize_t>(geometry.size[1]));
  shape.push_back(static_cast<hsize_t>(geometry.size[0]));
  shape.push_back(static_cast<hsize_t>(components));
  return shape;
}

// --- XDMF ---------------------------------------------------------------------------------------

namespace {

std::string number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.17g", value);
  return text;
}


// "nz ny nx" (2D: "ny nx"): XDMF lists dimensions slowest first.
std::string point_dims(const GridGeometry& g) {
  std::string dims;
  if (g.dimension == 3) dims = std::to_string(g.size[2]) + " ";
  return dims + std::to_string(g.size[1]) + " " + std::to_string(g.size[0]);
}

// The grid's points as the sidecar declares them: always three axes, slowest first. ParaView's
// XDMF reader puts a 2D mesh in the x = 0 plane (its two axes taken as y and z); declared as
// one z layer it lies in z = 0, where the data's x and y are.
std::string xdmf_point_dims(const GridGeometry& g) {
  return (g.dimension == 3 ? "" : "1 ") + point_dims(g);
}

std::string topology_and_geometry(const Hdf5Description& d, const std::string& h5,
                                  const std::string& indent) {
  const GridGeometry& g = d.geometry;
  const bool three_d = g.dimension == 3;
  std::string out;
  if (!g.rectilinear()) {
    out += indent + "<Topology TopologyType=\"3DCoRectMesh\" Dimensions=\"" +
           xdmf_point_dims(g) + "\"/>\n";
    out += indent + "<Geometry GeometryType=\"ORIGIN_DXDYDZ\">\n";
    // Slowest axis first, as the topology; a 2D grid's z layer at 0 (its spacing is unused).
    std::string origin = three_d ? "" : "0 ", spacing = three_d ? "" : "1 ";
    for (int a = (three_d ? 2 : 1); a >= 0; --a) {
      origin += number(g.origin[a]) + (a > 0 ? " " : "");
      spacing += number(g.spacing[a]) + (a > 0 ? " " : "");
    }
    out += indent +
           "  <DataItem Name=\"Origin\" Dimensions=\"3\" NumberType=\"Float\" Precision=\"8\" "
           "Format=\"XML\">" + origin + "</DataItem>\n";
    out += indent +
           "  <DataItem Name=\"Spacing\" Dimensions=\"3\" NumberType=\"Float\" Precision=\"8\" "
           "Format=\"XML\">" + spacing + "</DataItem>\n";
    out += indent + "</Geometry>\n";
  } else {
    out += indent + "<Topology TopologyType=\"3DRectMesh\" Dimensions=\"" + xdmf_point_dims(g) +
           "\"/>\n";
    out += indent + "<Geometry GeometryType=\"VXVYVZ\">\n";
    for (int a = 0; a < (three_d ? 3 : 2); ++a) {
      const std::string name(1, static_cast<char>('x' + a));
      out += indent + "  <DataItem Dimensions=\"" +
             std::to_string(g.size[static_cast<std::size_t>(a)]) +
             "\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">" + h5 + ":" +
             xml_escaped(child_path(d.group, name)) + "</DataItem>\n";
    }
    if (!three_d)
      out += indent +
             "  <DataItem Dimensions=\"1\" NumberType=\"Float\" Precision=\"8\" "
             "Format=\"XML\">0</DataItem>\n";
    out += indent + "</Geometry>\n";
  }
  return out;
}

std::string step_attribute(const Hdf5Description& d, const std::string& h5, std::size_t step,
                           const std::string& indent) {
  const std::string dims = point_dims(d.geometry) + " " + std::to_string(d.components);
  const std::string declared = xdmf_point_dims(d.geometry) + " " + std::to_string(d.components);
  const std::string type = "NumberType=\"Float\" Precision=\"4\" Format=\"HDF\"";
  std::string out =
      indent + "<Attribute Name=\"velocity\" AttributeType=\"Vector\" Center=\"Node\">\n";
  if (has_step_axis(d.storage)) {
    const std::size_t rank = d.geometry.dimension == 3 ? 5 : 4;
    std::string start = std::to_string(step), stride = "1", count = "1";
    for (std::size_t i = 1; i < rank; ++i) {
      start += " 0";
      stride += " 1";
    }
    count += " " + dims;
    out += indent + "  <DataItem ItemType=\"HyperSlab\" Dimensions=\"" + declared +
           "\" Type=\"HyperSlab\">\n";
    out += indent + "    <DataItem Dimensions=\"3 " + std::to_string(rank) + "\" Format=\"XML\">" +
           start + " " + stride + " " + count + "</DataItem>\n";
    out += indent + "    <DataItem Dimensions=\"" + std::to_string(d.times.size()) + " " + dims +
           "\" " + type + ">" + h5 + ":" + xml_escaped(d.dataset) + "</DataItem>\n";
    out += indent + "  </DataItem>\n";
  } else {
    char name[32];
    std::snprintf(name, sizeof name, "%06zu", step);
    const std::string path =
        d.storage == Hdf5Storage::per_step ? child_path(d.dataset, name) : d.dataset;
    out += indent + "  <DataItem Dimensions=\"" + declared + "\" " + type + ">" + h5 + ":" +
           xml_escaped(path) + "</DataItem>\n";
  }
  return out + indent + "</Attribute>\n";
}

}  // namespace

std::string xdmf_text(const Hdf5Description& d, const std::string& h5_name) {
  const std::string h5 = xml_escaped(h5_name);
  std::string out =
      "<?xml version=\"1.0\" ?>\n<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n"
      "<Xdmf Version=\"2.0\">\n  <Domain>\n";
  if (d.storage == Hdf5Storage::steady) {
    out += "    <Grid Name=\"velocity\" GridType=\"Uniform\">\n";
    out += topology_and_geometry(d, h5, "      ");
    out += step_attribute(d, h5, 0, "      ");
    out += "    </Grid>\n";
  } else {
    out += "    <Grid Name=\"velocity\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
    for (std::size_t s = 0; s < d.times.size(); ++s) {
      out += "      <Grid Name=\"step " + std::to_string(s) + "\" GridType=\"Uniform\">\n";
      out += "        <Time Value=\"" + number(d.times[s]) + "\"/>\n";
      out += topology_and_geometry(d, h5, "        ");
      out += step_attribute(d, h5, s, "        ");
      out += "      </Grid>\n";
    }
    out += "    </Grid>\n";
  }
  return out + "  </Domain>\n</Xdmf>\n";
}

}  // namespace orthofront::io::detail
