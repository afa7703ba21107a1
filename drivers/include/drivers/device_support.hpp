#pragma once

#include <atomic>
#include <cstdint>
#include <map>
#include <mutex>
#include <string>
#include <string_view>
#include <vector>

#include "drivers/device.hpp"

namespace calstand::drivers {

/// Lifecycle bookkeeping every driver shares. Thread safe (a driver's reader thread may move
/// it to kError while the engine's thread reads it).
class Lifecycle {
 public:
  DeviceState state() const { return state_.load(); }
  void set(DeviceState s) { state_ = s; }
  /// ok when active; otherwise a failure saying which state `device` is in.
  Result require_active(const std::string& device) const;
  /// kUnconfigured -> refused ("not configured"), otherwise kActive.
  Result activate();
  /// kActive -> kInactive; other states unchanged.
  void deactivate();

 private:
  std::atomic<DeviceState> state_{DeviceState::kUnconfigured};
};

/// Named fault counters (status pages, `calstand device ... status`). Thread safe.
class FaultCounters {
 public:
  /// Declares `names` at zero, so that status lists them before the first fault.
  explicit FaultCounters(std::initializer_list<std::string_view> names = {});
  void add(std::string_view name, std::uint64_t count = 1);
  void set(std::string_view name, std::uint64_t value);
  std::uint64_t get(std::string_view name) const;
  std::map<std::string, std::uint64_t> snapshot() const;

 private:
  mutable std::mutex mutex_;
  std::map<std::string, std::uint64_t, std::less<>> counts_;
};

/// Events waiting for the engine (Device::take_events). Thread safe; bounded so that a device
/// spewing faults with nobody draining cannot grow memory: beyond `capacity` the oldest are
/// dropped and one "N events dropped" event says so.
class EventQueue {
 public:
  explicit EventQueue(std::size_t capacity = 1000) : capacity_(capacity) {}
  void push(double time_s, bool fault, std::string message);
  std::vector<DeviceEvent> take();

 private:
  std::mutex mutex_;
  std::vector<DeviceEvent> events_;
  std::size_t capacity_;
  std::uint64_t dropped_ = 0;
};

}  // namespace calstand::drivers
