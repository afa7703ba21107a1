#include "daemon/service/event_hub.hpp"

namespace calstand::daemon::service {

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
