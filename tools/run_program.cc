#include "tools/run_program.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <stdexcept>

extern char** environ;

namespace ecrf {
namespace tools {
namespace {

bool IsExecutableFile(const std::string& path) {
  struct stat st;
  return stat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode) && access(path.c_str(), X_OK) == 0;
}

// Closes a descriptor once, however the function leaves.
class Descriptor {
 public:
  explicit Descriptor(int fd = -1) : fd_(fd) {}
  ~Descriptor() { Close(); }
  Descriptor(const Descriptor&) = delete;
  Descriptor& operator=(const Descriptor&) = delete;
  int get() const { return fd_; }
  void Close() {
    if (fd_ >= 0) close(fd_);
    fd_ = -1;
  }

 private:
  int fd_;
};

// Frees posix_spawn's argument objects on every path out.
struct SpawnSetup {
  posix_spawn_file_actions_t actions;
  SpawnSetup() { posix_spawn_file_actions_init(&actions); }
  ~SpawnSetup() { posix_spawn_file_actions_destroy(&actions); }
};

}  // namespace

std::string FindExecutable(const std::string& name) {
  if (name.empty()) return "";
  if (name.find('/') != std::string::npos) return IsExecutableFile(name) ? name : "";
  const char* path = std::getenv("PATH");
  // POSIX leaves an unset PATH to the implementation; an empty one finds nothing, which is what
  // the tests use to stand for a machine without the program.
  const std::string dirs = path ? path : "/usr/local/bin:/usr/bin:/bin";
  size_t start = 0;
  while (start <= dirs.size() && !dirs.empty()) {
    const size_t colon = dirs.find(':', start);
    std::string dir = dirs.substr(start, colon == std::string::npos ? colon : colon - start);
    if (dir.empty()) dir = ".";  // an empty entry is the current directory
    const std::string candidate = dir + "/" + name;
    if (IsExecutableFile(candidate)) return candidate;
    if (colon == std::string::npos) break;
    start = colon + 1;
  }
  return "";
}

std::string ProgramResult::Status() const {
  return exited ? "exit status " + std::to_string(exit_status)
                : "killed by signal " + std::to_string(signal);
}

ProgramResult RunProgram(const std::vector<std::string>& argv,
                         const std::function<void(const std::string&)>& on_line) {
  if (argv.empty()) throw std::invalid_argument("RunProgram: empty argv");
  int fds[2];
  if (pipe2(fds, O_CLOEXEC) != 0) {
    throw std::runtime_error("cannot run " + argv[0] + ": pipe: " + std::strerror(errno));
  }
  Descriptor read_end(fds[0]), write_end(fds[1]);
  SpawnSetup setup;
  posix_spawn_file_actions_addopen(&setup.actions, 0, "/dev/null", O_RDONLY, 0);
  if (on_line) {
    posix_spawn_file_actions_adddup2(&setup.actions, write_end.get(), 1);
  } else {
    posix_spawn_file_actions_addopen(&setup.actions, 1, "/dev/null", O_WRONLY, 0);
  }
  // dup2 clears close-on-exec on the copy, so the child keeps stderr and nothing else of ours.
  posix_spawn_file_actions_adddup2(&setup.actions, write_end.get(), 2);
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  pid_t pid = 0;
  const int error =
      posix_spawn(&pid, argv[0].c_str(), &setup.actions, nullptr, args.data(), environ);
  if (error != 0) {
    throw std::runtime_error("cannot run " + argv[0] + ": " + std::strerror(error));
  }
  write_end.Close();  // else the read below never sees end-of-file
  ProgramResult result;
  char buffer[4096];
  std::string line;  // the unfinished line for on_line
  for (;;) {
    const ssize_t n = read(read_end.get(), buffer, sizeof(buffer));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    if (on_line) {
      for (ssize_t k = 0; k < n; ++k) {
        if (buffer[k] == '\n' || buffer[k] == '\r') {
          if (!line.empty()) on_line(line);
          line.clear();
        } else if (line.size() < kErrorTailBytes) {
          line += buffer[k];
        }
      }
    }
    result.error_tail.append(buffer, size_t(n));
    if (result.error_tail.size() > 2 * kErrorTailBytes) {
      result.error_tail.erase(0, result.error_tail.size() - kErrorTailBytes);
    }
  }
  if (on_line && !line.empty()) on_line(line);
  if (result.error_tail.size() > kErrorTailBytes) {
    result.error_tail.erase(0, result.error_tail.size() - kErrorTailBytes);
  }
  int status = 0;
  while (waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) {
      throw std::runtime_error("cannot wait for " + argv[0] + ": " + std::strerror(errno));
    }
  }
  result.exited = WIFEXITED(status);
  result.exit_status = result.exited ? WEXITSTATUS(status) : -1;
  result.signal = WIFSIGNALED(status) ? WTERMSIG(status) : 0;
  return result;
}

std::string ShellCommandLine(const std::vector<std::string>& argv) {
  std::string line;
  for (const std::string& word : argv) {
    bool plain = !word.empty();
    for (char c : word) {
      plain = plain && (std::isalnum(static_cast<unsigned char>(c)) ||
                        (c != '\0' && std::strchr("-_./%+:=,@", c) != nullptr));
    }
    if (!line.empty()) line += ' ';
    if (plain) {
      line += word;
      continue;
    }
    line += '\'';
    for (char c : word) line += c == '\'' ? std::string("'\\''") : std::string(1, c);
    line += '\'';
  }
  return line;
}

// ffmpeg reads "-x.mp4" as an option and "a:b.mp4" as protocol "a": a relative path gets "./".
std::string FfmpegFileName(const std::string& path) {
  if (path.empty() || path[0] == '/' || path.rfind("./", 0) == 0) return path;
  if (path[0] == '-' || path.find(':') != std::string::npos) return "./" + path;
  return path;
}

// The last `lines` lines of text, for error messages (ffmpeg puts the cause at the end).
std::string TailLines(const std::string& text, int lines) {
  const size_t end = text.find_last_not_of("\n\r \t");
  if (end == std::string::npos) return "";
  size_t start = end + 1;
  for (int n = 0; n < lines && start > 0; ++n) {
    const size_t newline = text.rfind('\n', start - 1);
    start = newline == std::string::npos ? 0 : newline;
  }
  if (text[start] == '\n') ++start;
  return text.substr(start, end + 1 - start);
}

}  // namespace tools
}  // namespace ecrf
