#pragma once

// Test doubles shared by the acutrol suite: an in-memory scripted transport and a simulated
// world that advances in its own thread faster than real time.

#include <atomic>
#include <chrono>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "drivers/acutrol_protocol.hpp"
#include "drivers/serial_port.hpp"
#include "sim/sim_world.hpp"

namespace calstand::drivers::test {

/// A ByteTransport whose peer is a function: every command line written is passed to
/// `respond`, whose return (terminator included, or nothing) becomes readable at once.
/// Records the lines written. `fail_io` makes every call fail as a lost link would.
class ScriptedTransport final : public ByteTransport {
 public:
  using Responder = std::function<std::string(const std::string& line)>;
  explicit ScriptedTransport(Responder respond) : respond_(std::move(respond)) {}

  IoResult read(std::span<std::uint8_t> buffer, std::chrono::milliseconds timeout) override {
    if (fail_io) return {0, "scripted: link down"};
    if (pending_.empty()) {
      // Nothing will ever come: wait out the timeout, as a silent peer would.
      std::this_thread::sleep_for(timeout);
      return {};
    }
    const std::size_t n = std::min(buffer.size(), pending_.size());
    std::copy_n(pending_.begin(), n, buffer.begin());
    pending_.erase(0, n);
    return {n, {}};
  }
  IoResult write(std::span<const std::uint8_t> bytes, std::chrono::milliseconds) override {
    if (fail_io) return {0, "scripted: link down"};
    lines_.push(bytes);
    while (auto line = lines_.next()) {
      written.push_back(line->text);
      pending_ += respond_(line->text);
    }
    return {bytes.size(), {}};
  }
  /// Bytes the peer sends unasked (line noise, a late reply).
  void inject(const std::string& bytes) { pending_ += bytes; }

  std::vector<std::string> written;
  bool fail_io = false;

 private:
  Responder respond_;
  acutrol::LineAssembler lines_;
  std::string pending_;
};

/// The embedded default station without IMUs (they would only fill buffers nobody drains).
inline core::StationConfig table_only_station() {
  auto config = sim::default_station();
  config.imus.clear();
  return config;
}

/// A SimWorld advanced by its own thread at `speed` times real time, under `mutex`.
class RunningWorld {
 public:
  explicit RunningWorld(double speed = 20.0) : world_(table_only_station()) {
    thread_ = std::thread([this, speed] {
      constexpr auto kTick = std::chrono::milliseconds(2);
      while (!stop_) {
        std::this_thread::sleep_for(kTick);
        std::lock_guard lock(mutex_);
        world_.advance(speed * std::chrono::duration<double>(kTick).count());
      }
    });
  }
  ~RunningWorld() {
    stop_ = true;
    thread_.join();
  }
  RunningWorld(const RunningWorld&) = delete;
  RunningWorld& operator=(const RunningWorld&) = delete;

  sim::SimWorld& world() { return world_; }
  std::mutex& mutex() { return mutex_; }

 private:
  sim::SimWorld world_;
  std::mutex mutex_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

/// Calls `done` every 10 ms until it returns true or `limit` passes; true if it did.
inline bool eventually(const std::function<bool()>& done,
                       std::chrono::milliseconds limit = std::chrono::milliseconds(5000)) {
  const auto deadline = std::chrono::steady_clock::now() + limit;
  while (std::chrono::steady_clock::now() < deadline) {
    if (done()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return done();
}

}  // namespace calstand::drivers::test
