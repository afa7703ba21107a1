#include "drivers/imu_frame_streamer.hpp"

#include <chrono>

#include "drivers/imu_frame.hpp"

namespace calstand::drivers {

ImuFrameStreamer::ImuFrameStreamer(std::size_t max_queued_frames)
    : max_queued_(max_queued_frames), thread_([this] { loop(); }) {}

ImuFrameStreamer::~ImuFrameStreamer() {
  running_ = false;
  wake_.notify_all();
  thread_.join();
}

void ImuFrameStreamer::push(const core::ImuSample& sample) {
  if (silent_) {
    ++dropped_;
    return;
  }
  if (const double offset = clock_offset_s_.load(); offset != 0.0) {
    core::ImuSample shifted = sample;
    shifted.device_time_s += offset;
    inject(encode_imu_frame(shifted));
    return;
  }
  inject(encode_imu_frame(sample));
}

void ImuFrameStreamer::inject(std::vector<std::uint8_t> bytes) {
  {
    std::lock_guard lock(mutex_);
    if (queue_.size() >= max_queued_) {
      queue_.pop_front();
      ++dropped_;
    }
    queue_.push_back(std::move(bytes));
  }
  wake_.notify_one();
}

void ImuFrameStreamer::loop() {
  using namespace std::chrono_literals;
  std::vector<std::uint8_t> batch;
  while (running_) {
    std::size_t frames = 0;
    {
      std::unique_lock lock(mutex_);
      wake_.wait_for(lock, 50ms, [&] { return (!queue_.empty() && !held_) || !running_; });
      if (held_) continue;
      // Batch what is queued into one write: a few syscalls per millisecond, not per frame.
      batch.clear();
      while (!queue_.empty() && batch.size() < 64 * 1024) {
        batch.insert(batch.end(), queue_.front().begin(), queue_.front().end());
        queue_.pop_front();
        ++frames;
      }
    }
    if (batch.empty()) continue;
    // A reader that keeps up takes this at once. One that stalls briefly (scheduling) is waited
    // for, as a UART's buffers would; one that stops reading makes the write time out and the
    // frames that did not fit are lost, as on a real line (the receiver resynchronises).
    const auto r = pty_.write(batch, 1000ms);
    if (r.ok()) {
      sent_ += frames;
    } else {
      dropped_ += frames;
    }
  }
}

}  // namespace calstand::drivers
