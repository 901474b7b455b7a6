// Outputs are regular files and never an input: every writer refuses a symbolic link, a pipe or
// a file this process reads from, and leaves it as it was; a collection has one writer at a time.
#include <sys/stat.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <string>

#include "orthofront/io/atomic_file.h"
#include "orthofront/io/error.h"
#include "orthofront/io/input_files.h"
#include "orthofront/io/mesh_series.h"
#include "orthofront/io/open_field.h"
#include "orthofront/io/readable_file.h"
#include "orthofront/mesh/mesh.h"
#include "temp_dir.h"

namespace fs = std::filesystem;
using orthofront::io::AtomicFileSet;
using orthofront::io::IoError;
using orthofront::io::write_atomically;
using test_support::read_text;
using test_support::TempDir;

namespace {

void write_text(const fs::path& p, const std::string& text) { std::ofstream(p) << text; }


const auto hello = [](std::ofstream& out) { out << "new"; };

}  // namespace

TEST_CASE("outputs refuse a symbolic link and a pipe, and leave them as they were", "[io][output]") {
  const TempDir dir("output-kinds");
  const fs::path target = dir / "target.json", link = dir / "link.json", fifo = dir / "fifo";
  write_text(target, "old");
  fs::create_symlink(target, link);
  REQUIRE(::mkfifo(fifo.c_str(), 0600) == 0);
  CHECK_THROWS_WITH(write_atomically(link, hello), Catch::Contains("symbolic link") &&
                                                       Catch::Contains(link.string()));
  CHECK_THROWS_WITH(write_atomically(fifo, hello), Catch::Contains("not a regular file"));
  CHECK_THROWS_AS(orthofront::io::check_writable(fifo), IoError);
  {
    AtomicFileSet set;
    CHECK_THROWS_WITH(set.add(link, hello), Catch::Contains("symbolic link"));
  }
  CHECK(fs::is_symlink(link));
  CHECK(read_text(target) == "old");
  CHECK(fs::is_fifo(fifo));
  // A plain file is replaced as ever.
  const fs::path plain = dir / "plain.json";
  write_text(plain, "old");
  write_atomically(plain, hello);
  CHECK(read_text(plain) == "new");
}

TEST_CASE("outputs refuse a file this process reads from by any of its names", "[io][output]") {
  const TempDir dir("output-inputs");
  const fs::path input = dir / "input.vti", hard = dir / "hard.vti";
  write_text(input, "data");
  fs::create_hard_link(input, hard);
  fs::create_directories(dir / "real");
  fs::create_directory_symlink(dir / ".", dir / "alias");
  // Outside a job nothing is noted: a program may read a file and write it anew.
  orthofront::io::note_input(input);
  CHECK_FALSE(orthofront::io::input_named_by(input));
  const orthofront::io::InputScope job;
  orthofront::io::note_input(input);
  REQUIRE(orthofront::io::input_named_by(hard));
  CHECK_THROWS_WITH(write_atomically(input, hello), Catch::Contains("an input of this run"));
  CHECK_THROWS_WITH(write_atomically(hard, hello),
                    Catch::Contains("an input of this run (" + input.string() + ")"));
  CHECK_THROWS_WITH(write_atomically(dir / "alias" / "input.vti", hello),
                    Catch::Contains("an input of this run"));
  {
    // A set with an input in it replaces nothing, not even the files added before.
    const fs::path mesh = dir / "mesh.vtp";
    write_text(mesh, "old mesh");
    AtomicFileSet set;
    set.add(mesh, hello);
    CHECK_THROWS_WITH(set.add(hard, hello), Catch::Contains("an input of this run"));
    CHECK(read_text(mesh) == "old mesh");
  }
  CHECK(read_text(input) == "data");
}

TEST_CASE("a collection has one writer: a second is refused while the first writes",
          "[io][output]") {
  const TempDir dir("output-series");
  const fs::path pvd = dir / "streak.pvd";
  orthofront::Mesh mesh;
  mesh.add_vertex(orthofront::Vec3(0, 0, 0), 0, 0, 0, 0, 0, 0);
  mesh.add_vertex(orthofront::Vec3(1, 0, 0), 0, 0, 0, 0, 0, 0);
  mesh.add_vertex(orthofront::Vec3(0, 1, 0), 0, 0, 0, 0, 0, 0);
  mesh.add_triangle(0, 1, 2);
  {
    orthofront::io::MeshSeriesWriter first(pvd);
    first.add_frame(mesh, 1);
    CHECK_THROWS_WITH(orthofront::io::MeshSeriesWriter(pvd),
                      Catch::Contains("another run is writing") && Catch::Contains(pvd.string()));
    first.add_frame(mesh, 2);
    CHECK(first.frames() == 2);
  }
  // Once the first is done, the collection may be written again.
  orthofront::io::MeshSeriesWriter again(pvd);
  again.add_frame(mesh, 1);
  CHECK(again.frames() == 1);
}

TEST_CASE("inputs that are not files are named for what they are", "[io][input]") {
  const TempDir dir("input-kinds");
  using orthofront::io::why_unreadable;
  fs::create_directories(dir / "folder.nc");
  fs::create_symlink(dir / "loop.vdb", dir / "loop.vdb");
  fs::create_symlink(dir / "nowhere.h5", dir / "dangling.h5");
  REQUIRE(::mkfifo((dir / "fifo.vti").c_str(), 0600) == 0);
  write_text(dir / "plain.vec", "x");
  CHECK(why_unreadable(dir / "folder.nc") == "it is a directory");
  CHECK(why_unreadable(dir / "loop.vdb") == "a loop of symbolic links");
  CHECK(why_unreadable(dir / "dangling.h5") == "a dangling symbolic link");
  CHECK(why_unreadable(dir / "fifo.vti") == "not a regular file (a device, a FIFO or a socket)");
  CHECK(why_unreadable(dir / "none.nrrd") == "no such file");
  CHECK(why_unreadable(dir / "plain.vec").empty());
  // Every reader says so, naming the file.
  for (const auto& [name, reason] :
       {std::pair<const char*, const char*>{"folder.nc", "it is a directory"},
        {"loop.vdb", "a loop of symbolic links"},
        {"dangling.h5", "a dangling symbolic link"},
        {"fifo.vti", "not a regular file"}}) {
    INFO(name);
    CHECK_THROWS_WITH(orthofront::io::open_field((dir / name).string()),
                      Catch::Contains((dir / name).string()) && Catch::Contains(reason));
  }
}
