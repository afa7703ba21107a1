#include "daemon/service/event_hub.hpp"

#include <charconv>

namespace calstand::daemon::service {
namespace {

std::string wall_clock_epoch() {
  const auto ms = std::chrono::duration_cast<std::chrono::milliseconds>(
      std::chrono::system_clock::now().time_since_epoch());
  return std::to_string(ms.count());
}

}  // namespace

EventHub::EventHub(std::size_t capacity, std::string epoch)
    : capacity_(capacity), epoch_(epoch.empty() ? wall_clock_epoch() : std::move(epoch)) {}

std::string EventHub::event_id(std::uint64_t seq) const {
  return epoch_ + "-" + std::to_string(seq);
}

std::optional<EventHub::Replay> EventHub::replay_after(const std::string& last_event_id) const {
  const auto dash = last_event_id.rfind('-');
  if (dash == std::string::npos || dash == 0) return std::nullopt;
  std::uint64_t seq = 0;
  const char* first = last_event_id.data() + dash + 1;
  const char* last = last_event_id.data() + last_event_id.size();
  const auto [end, ec] = std::from_chars(first, last, seq);
  if (ec != std::errc() || end != last || first == last) return std::nullopt;
  const std::string epoch = last_event_id.substr(0, dash);
  if (epoch != epoch_) {
    // Digits only: an epoch of ours, from before a restart; anything else is not our id.
    if (epoch.find_first_not_of("0123456789") != std::string::npos) return std::nullopt;
    return Replay{0, true};
  }
  if (seq > last_seq()) return std::nullopt;
  return Replay{seq, false};
}

void EventHub::publish(std::string type, nlohmann::json data) {
  {
    std::lock_guard lock(mutex_);
    kept_.push_back({++last_seq_, std::move(type), std::move(data)});
    while (kept_.size() > capacity_) kept_.pop_front();
  }
  changed_.notify_all();
}

std::vector<LiveEvent> EventHub::wait_after(std::uint64_t after_seq,
                                            std::chrono::milliseconds timeout) {
  std::unique_lock lock(mutex_);
  changed_.wait_for(lock, timeout, [&] { return closed_ || last_seq_ > after_seq; });
  std::vector<LiveEvent> out;
  if (closed_) return out;
  for (const auto& e : kept_) {
    if (e.seq > after_seq) out.push_back(e);
  }
  return out;
}

std::uint64_t EventHub::last_seq() const {
  std::lock_guard lock(mutex_);
  return last_seq_;
}

void EventHub::close() {
  {
    std::lock_guard lock(mutex_);
    closed_ = true;
  }
  changed_.notify_all();
}

bool EventHub::closed() const {
  std::lock_guard lock(mutex_);
  return closed_;
}

}  // namespace calstand::daemon::service
