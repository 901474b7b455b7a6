#include "orthofront/io/vdb_module.h"

#include <dlfcn.h>

#include "orthofront/io/error.h"

namespace orthofront::io {

namespace {

constexpr const char* kModuleFile = "liborthofront_vdb.so";

/// Any object of this library: dladdr() names the file it was loaded from.
const int kAnchor = 0;

const VdbModule* load_module() {
  std::string tried;
  void* handle = nullptr;
  Dl_info self{};
  if (dladdr(&kAnchor, &self) != 0 && self.dli_fname != nullptr) {
    const std::filesystem::path beside =
        std::filesystem::path(self.dli_fname).parent_path() / kModuleFile;
    handle = dlopen(beside.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (handle == nullptr) tried = dlerror();
  }
  if (handle == nullptr) handle = dlopen(kModuleFile, RTLD_NOW | RTLD_LOCAL);
  if (handle == nullptr) {
    const std::string error = dlerror();
    throw IoError("OpenVDB files need " + std::string(kModuleFile) + ", which did not load: " +
                  (tried.empty() ? error : tried + "; " + error));
  }
  void* entry = dlsym(handle, "orthofront_vdb_module");
  if (entry == nullptr)
    throw IoError(std::string(kModuleFile) + " has no orthofront_vdb_module: " + dlerror());
  const auto module = reinterpret_cast<const VdbModule* (*)()>(entry);
  return module();
}

}  // namespace

const VdbModule& vdb_module() {
  static const VdbModule* const module = load_module();  // (a throw is retried next call)
  return *module;
}

void initialize_openvdb() { vdb_module().initialize(); }

std::vector<VdbGridInfo> list_vdb_grids(const std::filesystem::path& path) {
  return vdb_module().list_grids(path);
}

VectorGrid read_vdb_grid(const std::filesystem::path& path, const std::string& selector) {
  return vdb_module().read_grid(path, selector);
}

VectorGrid parse_vdb_grid(std::string_view content, const std::string& file,
                          const std::string& selector) {
  return vdb_module().parse_grid(content, file, selector);
}

VdbFileWriter::VdbFileWriter(std::filesystem::path path)
    : impl_(vdb_module().open_writer(path)) {}

VdbFileWriter::~VdbFileWriter() = default;

void VdbFileWriter::add(const std::string& name, const VectorGrid& grid,
                        std::optional<double> time) {
  impl_->add(name, grid, time);
}

std::size_t VdbFileWriter::grids() const { return impl_->grids(); }

void VdbFileWriter::commit() { impl_->commit(); }

void write_vdb(const std::filesystem::path& path, const std::vector<VdbOutputGrid>& grids) {
  VdbFileWriter writer(path);
  for (const VdbOutputGrid& entry : grids) {
    if (entry.grid == nullptr) throw InvalidArgument("write_vdb: grid '" + entry.name + "' is null");
    writer.add(entry.name, *entry.grid, entry.time);
  }
  writer.commit();
}

void write_vdb(const VectorGrid& grid, const std::filesystem::path& path, const std::string& name) {
  write_vdb(path, {VdbOutputGrid{name, &grid, std::nullopt}});
}

std::unique_ptr<TimeSeries> open_vdb_series(std::vector<VdbStep> steps, std::vector<double> times) {
  return vdb_module().open_series(std::move(steps), std::move(times));
}

std::unique_ptr<TimeSeries> open_vdb_file_series(const std::filesystem::path& path) {
  return vdb_module().open_file_series(path);
}

std::unique_ptr<VdbField> VdbField::open(const std::filesystem::path& path,
                                         const std::string& selector) {
  return vdb_module().open_field(path, selector);
}

std::unique_ptr<VdbField> VdbField::from_grid(const VectorGrid& grid, const std::string& name) {
  return vdb_module().field_from_grid(grid, name);
}

}  // namespace orthofront::io
