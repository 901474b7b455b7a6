#include "orthofront/io/input_files.h"

#include <sys/stat.h>

#include <mutex>
#include <vector>

namespace orthofront::io {
namespace {

struct Input {
  dev_t device;
  ino_t inode;
  std::filesystem::path path;
};

// A file is known by its device and inode: names, hard links and symbolic links all lead there.
struct Inputs {
  std::mutex mutex;
  int scopes = 0;
  std::vector<Input> files;
};

Inputs& inputs() {
  static Inputs registry;
  return registry;
}

}  // namespace

InputScope::InputScope() {
  Inputs& r = inputs();
  const std::lock_guard<std::mutex> hold(r.mutex);
  ++r.scopes;
}

InputScope::~InputScope() {
  Inputs& r = inputs();
  const std::lock_guard<std::mutex> hold(r.mutex);
  if (--r.scopes == 0) r.files.clear();
}

void note_input(const std::filesystem::path& path) {
  struct stat s {};
  if (::stat(path.c_str(), &s) != 0) return;
  Inputs& r = inputs();
  const std::lock_guard<std::mutex> hold(r.mutex);
  if (r.scopes == 0) return;
  for (const Input& i : r.files)
    if (i.device == s.st_dev && i.inode == s.st_ino) return;
  r.files.push_back({s.st_dev, s.st_ino, path});
}

std::vector<std::filesystem::path> noted_inputs() {
  Inputs& r = inputs();
  const std::lock_guard<std::mutex> hold(r.mutex);
  std::vector<std::filesystem::path> paths;
  for (const Input& i : r.files) paths.push_back(i.path);
  return paths;
}

std::optional<std::filesystem::path> input_named_by(const std::filesystem::path& path) {
  struct stat s {};
  if (::stat(path.c_str(), &s) != 0) return std::nullopt;
  Inputs& r = inputs();
  const std::lock_guard<std::mutex> hold(r.mutex);
  for (const Input& i : r.files)
    if (i.device == s.st_dev && i.inode == s.st_ino) return i.path;
  return std::nullopt;
}

}  // namespace orthofront::io
