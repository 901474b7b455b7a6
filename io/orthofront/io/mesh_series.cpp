#include "orthofront/io/mesh_series.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <system_error>

#include "orthofront/error.h"
#include "orthofront/io/atomic_file.h"
#include "orthofront/io/error.h"
#include "orthofront/io/mesh_io.h"
#include "orthofront/io/xml_text.h"

namespace orthofront::io {

MeshSeriesWriter::MeshSeriesWriter(std::filesystem::path pvd) : pvd_(std::move(pvd)) {
  if (pvd_.extension() != ".pvd")
    throw InvalidArgument("output '" + pvd_.string() +
                          "' must be a ParaView collection (.pvd): the frames go beside it");
  check_writable(pvd_);
  name_ = pvd_.stem().string();
  folder_ = pvd_.parent_path() / name_;
  std::error_code ec;
  made_folder_ = std::filesystem::create_directories(folder_, ec);
  if (ec) throw IoError("cannot create the frame folder " + folder_.string() + ": " + ec.message());
  lock_ = ::open(folder_.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (lock_ >= 0 && ::flock(lock_, LOCK_EX | LOCK_NB) != 0) {
    const int err = errno;
    ::close(lock_);
    lock_ = -1;
    // Without locks (a file system that refuses them) the frames are still each written whole.
    if (err == EWOULDBLOCK) {
      if (made_folder_) {
        std::error_code ignored;
        std::filesystem::remove(folder_, ignored);
      }
      throw IoError("cannot write " + pvd_.string() + ": another run is writing this collection "
                    "(its frame folder " + folder_.string() + " is locked); wait for it to end "
                    "or write elsewhere");
    }
  }
}

MeshSeriesWriter::~MeshSeriesWriter() {
  // A run that wrote no frame (bad input found later) leaves no folder it made.
  if (entries_.empty() && made_folder_) {
    std::error_code ignored;
    std::filesystem::remove(folder_, ignored);  // only while empty
  }
  if (lock_ >= 0) ::close(lock_);  // closing releases the lock
}

std::filesystem::path MeshSeriesWriter::add_frame(const Mesh& mesh, double time) {
  if (!entries_.empty() && !(time > entries_.back().time))
    throw InvalidArgument("frame times must increase: " + std::to_string(time) + " after " +
                          std::to_string(entries_.back().time));
  std::error_code ec;
  std::filesystem::create_directories(folder_, ec);
  if (ec) throw IoError("cannot create the frame folder " + folder_.string() + ": " + ec.message());
  char file[64];
  std::snprintf(file, sizeof file, "%s_%04zu.vtp", "", entries_.size());
  const std::string relative = name_ + "/" + name_ + file;
  const std::filesystem::path path = pvd_.parent_path() / relative;
  if (notes_.empty() || !mesh.notes.empty()) {
    write_mesh(mesh, path);
  } else {
    Mesh noted = mesh;
    noted.notes = notes_;
    write_mesh(noted, path);
  }
  entries_.push_back({time, relative});
  try {
    write_collection();
  } catch (...) {
    entries_.pop_back();  // the .pvd on disk still lists the frames before this one
    throw;
  }
  return path;
}

void MeshSeriesWriter::write_collection() const {
  write_atomically(pvd_, [&](std::ofstream& out) {
    out << "<?xml version=\"1.0\"?>\n"
           "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
           "  <Collection>\n";
    char time[64];
    for (const Entry& e : entries_) {
      std::snprintf(time, sizeof time, "%.17g", e.time);
      out << "    <DataSet timestep=\"" << time << "\" group=\"\" part=\"0\" file=\""
          << xml_escaped(e.file) << "\"/>\n";
    }
    out << "  </Collection>\n</VTKFile>\n";
  });
}

}  // namespace orthofront::io
