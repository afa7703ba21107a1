#pragma once

// Shared by the Modbus driver tests: a simulated world advanced on an accelerated clock, a
// child Python process with line I/O, and polling helpers.

#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <functional>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "core/clock.hpp"
#include "core/station_config.hpp"
#include "sim/sim_world.hpp"

extern char** environ;

namespace calstand::drivers::test {

using namespace std::chrono_literals;

/// A station with a quick chamber and no IMUs (nothing to sample): the chamber follows within
/// seconds of station time, so tests run in well under a second of wall time per step.
inline core::StationConfig quick_chamber_station() {
  auto config = sim::default_station();
  config.imus.clear();
  config.chamber.min_c = -40.0;
  config.chamber.max_c = 120.0;
  config.chamber.max_ramp_c_per_min = 60.0;
  config.chamber.ambient_c = 23.0;
  config.chamber.air_time_constant_s = 2.0;
  config.chamber.control_noise_c = 0.0;
  return config;
}

/// A SimWorld advanced by a background thread to keep up with `clock` (station time), under
/// `mutex`, as `calstand sim-station` does.
class RunningWorld {
 public:
  explicit RunningWorld(const core::StationConfig& config, double time_scale)
      : clock(time_scale), world(config) {
    thread_ = std::thread([this] {
      while (!stop_) {
        {
          std::lock_guard lock(mutex);
          world.advance_to(clock.now_s());
        }
        std::this_thread::sleep_for(2ms);
      }
    });
  }
  ~RunningWorld() {
    stop_ = true;
    thread_.join();
  }
  core::ChamberState chamber() {
    std::lock_guard lock(mutex);
    return world.chamber_state();
  }

  core::SteadyClock clock;
  std::mutex mutex;
  sim::SimWorld world;

 private:
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

/// Polls `condition` every 10 ms until it holds or `timeout` (wall) passes.
inline bool eventually(const std::function<bool()>& condition,
                       std::chrono::milliseconds timeout = 5000ms) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < deadline) {
    if (condition()) return true;
    std::this_thread::sleep_for(10ms);
  }
  return condition();
}

constexpr const char* kPython = "/usr/bin/python3";

inline std::string script_path(const std::string& name) {
  return std::string(CALSTAND_SOURCE_DIR) + "/tests/unit/drivers/modbus/" + name;
}

/// A child process with its stdin and stdout on pipes. Ends it (SIGTERM, then SIGKILL after a
/// second) and reaps it on destruction.
class ChildProcess {
 public:
  explicit ChildProcess(const std::vector<std::string>& argv) {
    // A child that died must fail the test through its missing output, not kill the test
    // binary with SIGPIPE when we write to its stdin.
    ::signal(SIGPIPE, SIG_IGN);
    int in[2], out[2];
    if (::pipe(in) != 0 || ::pipe(out) != 0) return;
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, in[0], 0);
    posix_spawn_file_actions_adddup2(&actions, out[1], 1);
    posix_spawn_file_actions_addclose(&actions, in[1]);
    posix_spawn_file_actions_addclose(&actions, out[0]);
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    if (posix_spawn(&pid_, args[0], &actions, nullptr, args.data(), environ) != 0) pid_ = -1;
    posix_spawn_file_actions_destroy(&actions);
    ::close(in[0]);
    ::close(out[1]);
    stdin_ = in[1];
    stdout_ = out[0];
  }
  ~ChildProcess() {
    if (stdin_ >= 0) ::close(stdin_);
    if (pid_ > 0) {
      int status = 0;
      for (int i = 0; i < 100 && ::waitpid(pid_, &status, WNOHANG) == 0; ++i) {
        if (i == 50) ::kill(pid_, SIGTERM);
        std::this_thread::sleep_for(20ms);
      }
      if (::waitpid(pid_, &status, WNOHANG) == 0) {
        ::kill(pid_, SIGKILL);
        ::waitpid(pid_, &status, 0);
      }
    }
    if (stdout_ >= 0) ::close(stdout_);
  }
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  bool started() const { return pid_ > 0; }

  /// The next line of its stdout (without the newline); nullopt on timeout or end of output.
  std::optional<std::string> read_line(std::chrono::milliseconds timeout = 5000ms) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    for (;;) {
      if (const auto nl = buffer_.find('\n'); nl != std::string::npos) {
        auto line = buffer_.substr(0, nl);
        buffer_.erase(0, nl + 1);
        return line;
      }
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
          deadline - std::chrono::steady_clock::now());
      if (left.count() <= 0) return std::nullopt;
      pollfd p{stdout_, POLLIN, 0};
      if (::poll(&p, 1, static_cast<int>(left.count())) <= 0) continue;
      char chunk[4096];
      const auto n = ::read(stdout_, chunk, sizeof chunk);
      if (n <= 0) return std::nullopt;
      buffer_.append(chunk, static_cast<std::size_t>(n));
    }
  }

  /// The JSON objects it printed until it is quiet for `quiet` (other lines are skipped).
  std::vector<nlohmann::json> json_lines(std::chrono::milliseconds quiet = 300ms) {
    std::vector<nlohmann::json> out;
    while (auto line = read_line(quiet)) {
      auto j = nlohmann::json::parse(*line, nullptr, false);
      if (j.is_object()) out.push_back(std::move(j));
    }
    return out;
  }

  void send_line(const std::string& line) {
    const std::string text = line + "\n";
    [[maybe_unused]] const auto n = ::write(stdin_, text.data(), text.size());
  }

 private:
  pid_t pid_ = -1;
  int stdin_ = -1;
  int stdout_ = -1;
  std::string buffer_;
};

/// Why pymodbus cannot be used here, or "" when it can: the system interpreter is needed (the
/// python3 on PATH may be a different one without pymodbus).
inline std::string pymodbus_missing() {
  if (::access(kPython, X_OK) != 0) return std::string(kPython) + " not found";
  ChildProcess probe({kPython, "-c", "import pymodbus; print('ok')"});
  const auto line = probe.read_line(10000ms);
  if (!line || *line != "ok") return std::string("pymodbus is not importable by ") + kPython;
  return {};
}

}  // namespace calstand::drivers::test
