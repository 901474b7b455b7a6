#include "orthofront/io/child_read.h"

#include <fcntl.h>
#include <poll.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <new>
#include <string>
#include <thread>

#include "orthofront/error.h"
#include "orthofront/io/error.h"

#if defined(__SANITIZE_ADDRESS__)
#define ORTHOFRONT_CHILD_READ_SANITIZED 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define ORTHOFRONT_CHILD_READ_SANITIZED 1
#endif
#endif
#ifdef ORTHOFRONT_CHILD_READ_SANITIZED
#include <sanitizer/common_interface_defs.h>
#endif

namespace orthofront::io {

namespace {

// Exit codes of the child.
// Codes no library's exit() is likely to use (a sanitizer that finds an error exits with 1).
constexpr int kRead = 0;
constexpr int kError = 71;       // one of the project's errors; its message follows on the pipe
constexpr int kOutOfMemory = 73;
constexpr int kOtherError = 74;  // any other exception; its what() follows

/// The address space this process maps now (VmSize), from /proc/self/statm.
std::size_t mapped_bytes() {
  std::ifstream statm("/proc/self/statm");
  std::size_t pages = 0;
  statm >> pages;
  return pages * static_cast<std::size_t>(::sysconf(_SC_PAGESIZE));
}

void write_all(int fd, const std::string& text) {
  const char* at = text.data();
  std::size_t left = text.size();
  while (left > 0) {
    const ssize_t n = ::write(fd, at, left);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return;
    at += n;
    left -= static_cast<std::size_t>(n);
  }
}

[[noreturn]] void run_child(int fd, const std::function<void()>& read, const ChildReadLimits& limits,
                            std::size_t mapped) {
#ifndef ORTHOFRONT_CHILD_READ_SANITIZED
  if (limits.memory_bytes > 0) {
    const rlimit cap{mapped + limits.memory_bytes, mapped + limits.memory_bytes};
    ::setrlimit(RLIMIT_AS, &cap);
  }
#else
  (void)limits;
  (void)mapped;
#endif
  // What a crashing library prints (glibc's malloc assertions, HDF5's error stack) would bury the
  // one-line message the parent gives; the child's output goes nowhere.
  const int null_fd = ::open("/dev/null", O_WRONLY | O_CLOEXEC);
  if (null_fd >= 0) {
    ::dup2(null_fd, STDOUT_FILENO);
    ::dup2(null_fd, STDERR_FILENO);
  }
  // CPU seconds (SIGXCPU at the limit, SIGKILL a second later); the parent adds a wall-clock limit.
  const auto cpu = static_cast<rlim_t>(std::ceil(limits.seconds));
  const rlimit cpu_cap{cpu, cpu + 1};
  ::setrlimit(RLIMIT_CPU, &cpu_cap);
  // Ctrl-C is the parent's to handle.
  std::signal(SIGINT, SIG_IGN);
  std::signal(SIGTERM, SIG_DFL);
  // A crash ends the child by its signal, which the parent reports; handlers inherited from the
  // parent (a fuzzer's, a sanitizer's death callback) would treat it as the parent's own crash.
  for (const int sig : {SIGSEGV, SIGBUS, SIGABRT, SIGFPE, SIGILL}) std::signal(sig, SIG_DFL);
#ifdef ORTHOFRONT_CHILD_READ_SANITIZED
  __sanitizer_set_death_callback(nullptr);
#endif
  int code = kRead;
  try {
    read();
  } catch (const Error& e) {
    write_all(fd, e.what());
    code = kError;
  } catch (const std::bad_alloc&) {
    code = kOutOfMemory;
  } catch (const std::exception& e) {
    write_all(fd, e.what());
    code = kOtherError;
  } catch (...) {
    code = kOtherError;
  }
  // _exit: no atexit handlers or static destructors of the parent's state run in the child.
  ::_exit(code);
}

std::string mib(std::size_t bytes) { return std::to_string((bytes + (1 << 20) - 1) >> 20) + " MiB"; }

}  // namespace

bool files_trusted() {
  const char* text = std::getenv("ORTHOFRONT_TRUST_FILES");
  return text != nullptr && std::string(text) == "1";
}

double child_read_seconds(std::size_t bytes) {
  if (const char* text = std::getenv("ORTHOFRONT_READ_TIMEOUT")) {
    char* end = nullptr;
    const double seconds = std::strtod(text, &end);
    if (end != text && *end == '\0' && seconds > 0) return seconds;
  }
  return 10 + static_cast<double>(bytes) / 20e6;
}

namespace {

// Whether every other thread of this process is asleep (no 'R' in /proc/self/task/*/stat).
bool other_threads_asleep() {
  const pid_t self = static_cast<pid_t>(::gettid());
  std::error_code ec;
  for (const auto& task : std::filesystem::directory_iterator("/proc/self/task", ec)) {
    const std::string name = task.path().filename().string();
    if (name == std::to_string(self)) continue;
    std::ifstream stat(task.path() / "stat");
    std::string line;
    if (!std::getline(stat, line)) continue;  // the thread has ended
    const auto close = line.rfind(')');
    if (close != std::string::npos && close + 2 < line.size() && line[close + 2] == 'R') return false;
  }
  return true;
}

}  // namespace

void read_in_child(const std::string& file, const std::string& format,
                   const std::function<void()>& read, const ChildReadLimits& limits) {
  // A forked child keeps every lock another thread held at the fork, the allocator's among them
  // (a sanitizer's allocator does not take them around fork() as glibc's does), and would wait on
  // it for ever. Threads that have just started are the risk: OpenVDB's module starts a logging
  // thread pool when it loads, right before its first file is read here. Wait (at most 1 s)
  // until every other thread sleeps.
  for (int wait = 0; wait < 1000 && !other_threads_asleep(); ++wait)
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  int fds[2];
  if (::pipe2(fds, O_CLOEXEC) != 0)
    throw IoError("cannot read " + file + ": pipe: " + std::strerror(errno));
  const std::size_t mapped = mapped_bytes();
  // Buffered output would otherwise be written twice, once by the child.
  std::fflush(nullptr);
  const pid_t parent = ::getpid();
  const pid_t pid = ::fork();
  if (pid < 0) {
    ::close(fds[0]);
    ::close(fds[1]);
    throw IoError("cannot read " + file + ": fork: " + std::strerror(errno));
  }
  if (pid == 0) {
    // The child dies with the thread that forked it (the parent killed, say), instead of
    // reading on for up to its time limit; a parent gone before this line is seen too.
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (::getppid() != parent) ::_exit(3);
    ::close(fds[0]);
    run_child(fds[1], read, limits, mapped);
  }
  ::close(fds[1]);

  // The child's message, until it closes the pipe by exiting, or until the time limit.
  std::string message;
  bool timed_out = false;
  const auto deadline = std::chrono::steady_clock::now() +
                        std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                            std::chrono::duration<double>(10 * limits.seconds));
  for (;;) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) {
      timed_out = true;
      break;
    }
    pollfd p{fds[0], POLLIN, 0};
    const int ready = ::poll(&p, 1, static_cast<int>(std::min<long long>(left.count(), 1000)));
    if (ready < 0 && errno == EINTR) continue;
    if (ready <= 0) continue;
    char buffer[4096];
    const ssize_t n = ::read(fds[0], buffer, sizeof buffer);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    // A message is a line or two; anything beyond is not read into memory.
    if (message.size() < 8192) message.append(buffer, static_cast<std::size_t>(n));
  }
  ::close(fds[0]);
  if (timed_out) ::kill(pid, SIGKILL);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }

  const std::string what = file + ": corrupt or unreadable " + format + " file: ";
  if (timed_out) {
    throw FormatError(what + "reading it did not finish within " +
                      std::to_string(static_cast<long>(std::lround(10 * limits.seconds))) +
                      " s (the reader is blocked, or the file system is very slow)");
  }
  if (WIFSIGNALED(status) && (WTERMSIG(status) == SIGXCPU || WTERMSIG(status) == SIGKILL)) {
    throw FormatError(what + "reading it did not finish within " +
                      std::to_string(static_cast<long>(std::lround(limits.seconds))) +
                      " s of CPU time (a damaged file can make the reader loop)");
  }
  if (WIFSIGNALED(status)) {
    const int sig = WTERMSIG(status);
    throw FormatError(what + "the " + format + " reader crashed on it (signal " + std::to_string(sig) +
                      ", " + ::strsignal(sig) + ")");
  }
  const int code = WIFEXITED(status) ? WEXITSTATUS(status) : kOtherError;
  if (code == kRead) return;
  if (code == kError && !message.empty()) throw FormatError(message);
  if (code == kOutOfMemory) {
    throw FormatError(what + "reading it needs more than " + mib(limits.memory_bytes) +
                      " of memory (sizes in the file that its length cannot hold)");
  }
  throw FormatError(what + (message.empty() ? "the reader failed (exit status " +
                                                  std::to_string(code) + ")"
                                            : message));
}

}  // namespace orthofront::io
