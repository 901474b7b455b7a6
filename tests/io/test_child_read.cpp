// The child that reads an untrusted file first: it dies with its parent.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>

#include "orthofront/io/child_read.h"
#include "temp_dir.h"

namespace fs = std::filesystem;

namespace {

bool alive(pid_t pid) {
  // A zombie still answers kill(0): read its state.
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  std::string pid_text, name, state;
  if (!(stat >> pid_text >> name >> state)) return false;
  return state != "Z" && state != "X";
}

}  // namespace

TEST_CASE("child read: the reading child dies when its parent is killed", "[io][child]") {
  test_support::TempDir dir("child-read");
  const fs::path pid_file = dir / "reader.pid";
  // A parent process that starts a read taking 60 s; killed, its reader must not read on.
  const pid_t parent = ::fork();
  REQUIRE(parent >= 0);
  if (parent == 0) {
    orthofront::io::ChildReadLimits limits;
    limits.seconds = 60;
    try {
      orthofront::io::read_in_child("slow.vdb", "OpenVDB", [&] {
        { std::ofstream(pid_file.string() + ".tmp") << ::getpid(); }
        fs::rename(pid_file.string() + ".tmp", pid_file);
        std::this_thread::sleep_for(std::chrono::seconds(60));
      }, limits);
    } catch (...) {
    }
    ::_exit(0);
  }
  pid_t reader = 0;
  for (int i = 0; i < 1000 && reader == 0; ++i) {
    std::ifstream in(pid_file);
    if (!(in >> reader)) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  REQUIRE(reader > 0);
  CHECK(alive(reader));
  ::kill(parent, SIGKILL);
  int status = 0;
  ::waitpid(parent, &status, 0);
  bool gone = false;
  for (int i = 0; i < 500 && !gone; ++i) {
    gone = !alive(reader);
    if (!gone) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  CHECK(gone);
  if (!gone) ::kill(reader, SIGKILL);
}
