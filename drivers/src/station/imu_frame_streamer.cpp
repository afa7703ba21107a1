#include "drivers/imu_frame_streamer.hpp"

#include <array>
#include <chrono>

namespace calstand::drivers {

ImuFrameStreamer::ImuFrameStreamer(std::unique_ptr<ImuDeviceEmulator> emulator,
                                   std::size_t max_queued_frames)
    : emulator_(std::move(emulator)),
      max_queued_(max_queued_frames),
      thread_([this] { loop(); }),
      host_thread_([this] { host_loop(); }) {}

ImuFrameStreamer::~ImuFrameStreamer() {
  running_ = false;
  wake_.notify_all();
  thread_.join();
  host_thread_.join();
}

void ImuFrameStreamer::push(const core::ImuSample& sample) {
  if (silent_) {
    ++dropped_;
    return;
  }
  core::ImuSample shifted = sample;
  shifted.device_time_s += clock_offset_s_.load();
  std::vector<std::uint8_t> bytes;
  {
    std::lock_guard lock(emulator_mutex_);
    bytes = emulator_->on_sample(shifted);
  }
  if (!bytes.empty()) queue(std::move(bytes), true);
}

void ImuFrameStreamer::inject(std::vector<std::uint8_t> bytes) { queue(std::move(bytes), false); }

void ImuFrameStreamer::queue(std::vector<std::uint8_t> bytes, bool is_frame) {
  {
    std::lock_guard lock(mutex_);
    if (queue_.size() >= max_queued_) {
      if (queue_.front().is_frame) ++dropped_;
      queue_.pop_front();
    }
    queue_.push_back({std::move(bytes), is_frame});
  }
  wake_.notify_one();
}

void ImuFrameStreamer::drop_queued_frames() {
  std::lock_guard lock(mutex_);
  const auto stale = std::erase_if(queue_, [](const Queued& q) { return q.is_frame; });
  dropped_ += stale;
}

void ImuFrameStreamer::host_loop() {
  using namespace std::chrono_literals;
  std::array<std::uint8_t, 1024> chunk{};
  while (running_) {
    const IoResult r = pty_.read(chunk, 50ms);
    if (!r.ok() || r.bytes == 0) {
      // No client has the line open (the master reads an error then): wait for one.
      if (!r.ok()) std::this_thread::sleep_for(20ms);
      continue;
    }
    if (silent_) continue;  // a unit that stopped talking does not answer either
    std::vector<std::uint8_t> reply;
    {
      std::lock_guard lock(emulator_mutex_);
      reply = emulator_->on_host_bytes(std::span(chunk.data(), r.bytes));
    }
    if (!reply.empty()) queue(std::move(reply), false);
  }
}

void ImuFrameStreamer::loop() {
  using namespace std::chrono_literals;
  std::vector<std::uint8_t> batch;
  // Nobody has read the line since a write timed out (no client has it open, or one stopped
  // reading). A real unit's frames are then lost as they are sent; queued here, and held up for
  // the second a write may wait, they went to the next client that opened the line, after its
  // flush, as the first frames it saw: seconds of the world's time before it (at --time-scale
  // 20, a second of wall time is 20 s of frames), which it stamped as they arrived. While the
  // line is unread only the newest frame is offered, with a short wait.
  bool unread = false;
  while (running_) {
    std::size_t frames = 0;
    {
      std::unique_lock lock(mutex_);
      wake_.wait_for(lock, 50ms, [&] { return (!queue_.empty() && !held_) || !running_; });
      if (held_) continue;
      if (unread) {
        std::size_t frames_queued = 0;
        for (const Queued& q : queue_) frames_queued += q.is_frame ? 1 : 0;
        for (auto it = queue_.begin(); it != queue_.end() && frames_queued > 1;) {
          if (!it->is_frame) {
            ++it;
            continue;
          }
          ++dropped_;
          --frames_queued;
          it = queue_.erase(it);
        }
      }
      // Batch what is queued into one write: a few syscalls per millisecond, not per frame.
      batch.clear();
      while (!queue_.empty() && batch.size() < 64 * 1024) {
        batch.insert(batch.end(), queue_.front().bytes.begin(), queue_.front().bytes.end());
        if (queue_.front().is_frame) ++frames;
        queue_.pop_front();
      }
    }
    if (batch.empty()) continue;
    // A reader that keeps up takes this at once. One that stalls briefly (scheduling) is waited
    // for, as a UART's buffers would; one that stops reading (or a line nobody has open) makes
    // the write time out, and what did not fit is lost with everything queued behind it, as on
    // a real line (the receiver resynchronises). Kept, the queue would hand the next client
    // seconds of stale frames ahead of the reply to its first request.
    const auto r = pty_.write(batch, unread ? 20ms : 1000ms);
    if (r.ok()) {
      sent_ += frames;
      unread = false;
    } else {
      dropped_ += frames;
      drop_queued_frames();
      unread = true;
    }
  }
}

}  // namespace calstand::drivers
