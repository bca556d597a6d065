// Running a helper program (ffmpeg for `ecrf render --video`) without a shell: the arguments go
// to the program as an argv array, so file names with spaces, quotes or '$' need no escaping and
// cannot run anything else.
#ifndef ECRF_TOOLS_RUN_PROGRAM_H_
#define ECRF_TOOLS_RUN_PROGRAM_H_

#include <functional>
#include <string>
#include <vector>

namespace ecrf {
namespace tools {

// The file `name` runs as: a name with a '/' is taken as it is, any other is looked up in the
// directories of $PATH as a shell would. "" when there is no such executable file.
std::string FindExecutable(const std::string& name);

struct ProgramResult {
  bool exited = false;     // false: killed by a signal (signal holds it)
  int exit_status = -1;    // the program's exit status when exited
  int signal = 0;          //
  std::string error_tail;  // the last lines it wrote to stderr (at most kErrorTailBytes)
  bool Succeeded() const { return exited && exit_status == 0; }
  // "exit status 1" or "killed by signal 9", for messages.
  std::string Status() const;
};
inline constexpr size_t kErrorTailBytes = 4096;

// Runs argv[0] (a path, as FindExecutable returns) with argv, stdin and stdout on /dev/null,
// stderr captured, and waits for it. Throws std::runtime_error when it cannot be started.
// With on_line, stdout is captured too and each line of either stream (without its newline, in
// the order the program wrote them) goes to on_line as it arrives: progress for a long run.
ProgramResult RunProgram(const std::vector<std::string>& argv,
                         const std::function<void(const std::string&)>& on_line = nullptr);

// argv as one line a user can paste into a POSIX shell: each word single-quoted when it holds
// anything but letters, digits and -_./%+:=,@.
std::string ShellCommandLine(const std::vector<std::string>& argv);

// A file name ffmpeg takes as a file: it reads "-x.mp4" as an option and "a:b.mp4" as protocol
// "a", so a relative path that starts with '-' or holds ':' gets "./".
std::string FfmpegFileName(const std::string& path);

// The last `lines` lines of text, for error messages (programs put the cause at the end).
std::string TailLines(const std::string& text, int lines);

}  // namespace tools
}  // namespace ecrf

#endif  // ECRF_TOOLS_RUN_PROGRAM_H_
