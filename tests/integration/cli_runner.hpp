#pragma once
// Runs the calstand binary (CALSTAND_BIN) as a user would, for the command-line tests.

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <string>

namespace calstand::testing {

struct Result {
  int exit_code;
  std::string out;  // stdout and stderr together
};

// Runs calstand with `args`; stderr joins stdout unless `stderr_file` is given.
inline Result run(const std::string& args, const std::string& stderr_file = "") {
  const std::string redirect = stderr_file.empty() ? " 2>&1" : " 2>" + stderr_file;
  const std::string command = std::string(CALSTAND_BIN) + " " + args + redirect;
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) return {-1, ""};
  std::string out;
  std::array<char, 4096> buf{};
  while (std::size_t n = fread(buf.data(), 1, buf.size(), pipe)) out.append(buf.data(), n);
  const int status = pclose(pipe);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

inline std::string read_text(const std::string& path) {
  std::ifstream f(path);
  return std::string(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
}

inline void write_text(const std::string& path, const std::string& text) {
  std::ofstream(path) << text;
}

}  // namespace calstand::testing
