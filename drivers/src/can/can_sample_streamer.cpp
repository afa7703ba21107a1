#include "drivers/can_sample_streamer.hpp"

#include <chrono>
#include <vector>

namespace calstand::drivers {
namespace {

using namespace std::chrono_literals;

// How long one frame may wait for room in the transmit queue before it is lost [ms].
constexpr auto kWriteTimeout = 200ms;

}  // namespace

CanSampleStreamer::CanSampleStreamer(std::unique_ptr<CanTransport> transport, CanSignalMap map,
                                     std::size_t max_queued_frames)
    : transport_(std::move(transport)),
      map_(std::move(map)),
      max_queued_(max_queued_frames > 0 ? max_queued_frames : 1),
      thread_([this] { loop(); }) {}

CanSampleStreamer::~CanSampleStreamer() {
  running_ = false;
  wake_.notify_all();
  thread_.join();
}

void CanSampleStreamer::push(const core::ImuSample& sample) {
  if (silent_) {
    dropped_ += map_.frames.size();
    return;
  }
  for (const auto& frame : encode_sample(map_, sample)) inject(frame);
}

void CanSampleStreamer::inject(const can_frame& frame) {
  {
    std::lock_guard lock(mutex_);
    if (queue_.size() >= max_queued_) {
      queue_.pop_front();
      ++dropped_;
    }
    queue_.push_back(frame);
  }
  wake_.notify_one();
}

void CanSampleStreamer::loop() {
  std::vector<can_frame> batch;
  while (running_) {
    {
      std::unique_lock lock(mutex_);
      wake_.wait_for(lock, 50ms, [&] { return !queue_.empty() || !running_; });
      batch.assign(queue_.begin(), queue_.end());
      queue_.clear();
    }
    // Sent outside the lock so that push() never waits for the bus.
    for (const auto& frame : batch) {
      if (transport_->write(frame, kWriteTimeout).empty()) {
        ++sent_;
      } else {
        ++dropped_;
      }
    }
  }
}

}  // namespace calstand::drivers
