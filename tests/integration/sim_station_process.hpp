#pragma once
// `calstand sim-station` as a child process for the integration tests: started with pipes on
// stdin (fault commands) and stdout (the endpoints line, then one answer per command).

#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "test_time.hpp"

namespace calstand::testing {

class SimStationProcess {
 public:
  /// Starts `calstand sim-station` with `args`; waits for and parses its endpoints line.
  explicit SimStationProcess(const std::vector<std::string>& args) {
    // A child that died must fail the test that talks to it, not kill the test binary.
    ::signal(SIGPIPE, SIG_IGN);
    int to_child[2], from_child[2];
    if (::pipe(to_child) != 0 || ::pipe(from_child) != 0) throw std::runtime_error("pipe");
    const pid_t parent = ::getpid();
    pid_ = ::fork();
    if (pid_ < 0) throw std::runtime_error("fork");
    if (pid_ == 0) {
      die_with_parent(parent);
      ::dup2(to_child[0], STDIN_FILENO);
      ::dup2(from_child[1], STDOUT_FILENO);
      ::close(to_child[1]);
      ::close(from_child[0]);
      std::vector<char*> argv{const_cast<char*>(CALSTAND_BIN), const_cast<char*>("sim-station")};
      for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
      argv.push_back(nullptr);
      ::execv(CALSTAND_BIN, argv.data());
      ::_exit(127);
    }
    ::close(to_child[0]);
    ::close(from_child[1]);
    in_ = ::fdopen(to_child[1], "w");
    out_ = ::fdopen(from_child[0], "r");
    std::setvbuf(out_, nullptr, _IONBF, 0);  // unbuffered: poll() then sees every byte waiting
    endpoints_ = nlohmann::json::parse(line());
  }
  ~SimStationProcess() {
    if (in_) {
      std::fputs("quit\n", in_);
      std::fclose(in_);
    }
    int status = 0;
    for (int i = 0; i < 50; ++i) {  // up to 5 s for a clean exit, then kill
      if (::waitpid(pid_, &status, WNOHANG) == pid_) {
        pid_ = -1;
        break;
      }
      ::usleep(100'000);
    }
    if (pid_ > 0) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, &status, 0);
    }
    if (out_) std::fclose(out_);
  }
  SimStationProcess(const SimStationProcess&) = delete;
  SimStationProcess& operator=(const SimStationProcess&) = delete;

  const nlohmann::json& endpoints() const { return endpoints_; }

  /// Sends one fault command; returns its answer.
  nlohmann::json command(const std::string& text) {
    std::fputs((text + "\n").c_str(), in_);
    std::fflush(in_);
    return nlohmann::json::parse(line());
  }

 private:
  /// One line of the child's output, waiting at most 20 s for it (a hung sim-station fails the
  /// test instead of hanging it).
  std::string line() {
    std::string s;
    for (;;) {
      pollfd pfd{::fileno(out_), POLLIN, 0};
      if (::poll(&pfd, 1, 20'000) <= 0) {
        throw std::runtime_error("sim-station gave no answer within 20 s");
      }
      const int c = std::fgetc(out_);
      if (c == EOF || c == '\n') break;
      s.push_back(static_cast<char>(c));
    }
    if (s.empty()) throw std::runtime_error("sim-station said nothing (did it start?)");
    return s;
  }

  pid_t pid_ = -1;
  FILE* in_ = nullptr;
  FILE* out_ = nullptr;
  nlohmann::json endpoints_;
};

}  // namespace calstand::testing
