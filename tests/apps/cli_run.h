#pragma once
// Runs the built `orthofront` binary from a command-line test and captures what it printed.
#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

namespace cli_test {

struct Run {
  int status = -1;
  std::string output;  // stdout and stderr together
};

/// `p` in single quotes, as one shell word (test paths hold no quote).
inline std::string quoted(const std::filesystem::path& p) {
  return "'" + p.string() + "'";
}

/// Runs a shell command line (stderr joins stdout).
inline Run run_shell(const std::string& command_line) {
  Run r;
  const std::string command = command_line + " 2>&1";
  FILE* pipe = ::popen(command.c_str(), "r");
  REQUIRE(pipe != nullptr);
  char buffer[4096];
  while (std::fgets(buffer, sizeof buffer, pipe) != nullptr) r.output += buffer;
  const int status = ::pclose(pipe);
  r.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

/// Runs the binary with `arguments` (a shell fragment).
inline Run run(const std::string& arguments) {
  return run_shell(std::string("'") + ORTHOFRONT_BINARY + "' " + arguments);
}

/// Runs the benchmark program with `arguments` (a shell fragment).
inline Run run_bench(const std::string& arguments) {
  return run_shell(std::string("'") + ORTHOFRONT_BENCH_BINARY + "' " + arguments);
}

/// Starts the binary with `args` in the background, its stdout and stderr in `log` and no stdin;
/// returns its pid (for tests that signal it).
inline pid_t start(const std::vector<std::string>& args, const std::string& log) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    std::freopen(log.c_str(), "w", stdout);
    std::freopen(log.c_str(), "a", stderr);
    std::freopen("/dev/null", "r", stdin);
    std::vector<char*> argv{const_cast<char*>(ORTHOFRONT_BINARY)};
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    ::execv(ORTHOFRONT_BINARY, argv.data());
    ::_exit(127);
  }
  return pid;
}

}  // namespace cli_test
