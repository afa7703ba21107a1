#include "drivers/device_support.hpp"

#include <fmt/format.h>

namespace calstand::drivers {

Result Lifecycle::require_active(const std::string& device) const {
  const auto s = state();
  if (s == DeviceState::kActive) return Result::success();
  return Result::failure(fmt::format("{} is {}, not active", device, to_string(s)));
}

Result Lifecycle::activate() {
  if (state() == DeviceState::kUnconfigured) return Result::failure("not configured");
  state_ = DeviceState::kActive;
  return Result::success();
}

void Lifecycle::deactivate() {
  auto expected = DeviceState::kActive;
  state_.compare_exchange_strong(expected, DeviceState::kInactive);
}

FaultCounters::FaultCounters(std::initializer_list<std::string_view> names) {
  for (auto n : names) counts_.emplace(std::string(n), 0);
}

void FaultCounters::add(std::string_view name, std::uint64_t count) {
  std::lock_guard lock(mutex_);
  auto it = counts_.find(name);
  if (it == counts_.end()) it = counts_.emplace(std::string(name), 0).first;
  it->second += count;
}

void FaultCounters::set(std::string_view name, std::uint64_t value) {
  std::lock_guard lock(mutex_);
  auto it = counts_.find(name);
  if (it == counts_.end()) it = counts_.emplace(std::string(name), 0).first;
  it->second = value;
}

std::uint64_t FaultCounters::get(std::string_view name) const {
  std::lock_guard lock(mutex_);
  const auto it = counts_.find(name);
  return it == counts_.end() ? 0 : it->second;
}

std::map<std::string, std::uint64_t> FaultCounters::snapshot() const {
  std::lock_guard lock(mutex_);
  return {counts_.begin(), counts_.end()};
}

void EventQueue::push(double time_s, bool fault, std::string message) {
  std::lock_guard lock(mutex_);
  if (events_.size() >= capacity_) {
    events_.erase(events_.begin());
    ++dropped_;
  }
  events_.push_back({time_s, fault, std::move(message)});
}

std::vector<DeviceEvent> EventQueue::take() {
  std::lock_guard lock(mutex_);
  std::vector<DeviceEvent> out;
  if (dropped_ > 0) {
    const double t = events_.empty() ? 0.0 : events_.front().time_s;
    out.push_back({t, true, fmt::format("{} events dropped (nobody drained the queue)", dropped_)});
    dropped_ = 0;
  }
  out.insert(out.end(), std::make_move_iterator(events_.begin()),
             std::make_move_iterator(events_.end()));
  events_.clear();
  return out;
}

}  // namespace calstand::drivers
