// Runs the built `dynscope` binary from a test and captures its exit code and output.
#pragma once

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <string>

namespace dynscope::test {

/// Exit status and combined stdout + stderr of one program run.
struct CommandResult {
  int exit_code = -1;  ///< -1 if the program could not be started or was killed by a signal.
  std::string output;
};

/// Runs `command` through the shell, stderr merged into the output.
inline CommandResult run_shell(const std::string& shell_command) {
  const std::string command = shell_command + " 2>&1";
  CommandResult r;
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) return r;
  std::array<char, 4096> buf{};
  size_t n;
  while ((n = std::fread(buf.data(), 1, buf.size(), pipe)) > 0) r.output.append(buf.data(), n);
  const int status = pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

#ifdef DYNSCOPE_BINARY
/// Runs `DYNSCOPE_BINARY args` through the shell (define DYNSCOPE_BINARY as the program path).
inline CommandResult run_dynscope(const std::string& args) {
  return run_shell(std::string(DYNSCOPE_BINARY) + " " + args);
}
#endif

}  // namespace dynscope::test
