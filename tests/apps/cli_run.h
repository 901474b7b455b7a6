#pragma once
// Runs the built `orthofront` binary from a command-line test and captures what it printed.
#include <sys/wait.h>

#include <catch2/catch.hpp>
#include <cstdio>
#include <string>

namespace cli_test {

struct Run {
  int status = -1;
  std::string output;  // stdout and stderr together
};

/// Runs the binary with `arguments` (a shell fragment).
inline Run run(const std::string& arguments) {
  Run r;
  const std::string command = std::string("'") + ORTHOFRONT_BINARY + "' " + arguments + " 2>&1";
  FILE* pipe = ::popen(command.c_str(), "r");
  REQUIRE(pipe != nullptr);
  char buffer[4096];
  while (std::fgets(buffer, sizeof buffer, pipe) != nullptr) r.output += buffer;
  const int status = ::pclose(pipe);
  r.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

}  // namespace cli_test
