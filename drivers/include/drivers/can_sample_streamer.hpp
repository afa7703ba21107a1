#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <thread>

#include "core/imu_sample.hpp"
#include "drivers/can_signal_map.hpp"
#include "drivers/can_transport.hpp"

namespace calstand::drivers {

/// The CAN end of a simulated IMU: each sample pushed is encoded by the signal map
/// (encode_sample) and sent on a CAN transport (vcan0 in a rehearsal, a socket pair in tests)
/// that a CanImu reads. push() is called by the world as samples are produced and never
/// blocks; a writer thread sends the frames. As on a bus, what cannot be sent is lost: beyond
/// `max_queued_frames` the oldest frames are dropped (counted), and a frame the transport
/// refuses within its timeout is dropped too; the receiver sees incomplete samples and gaps.
class CanSampleStreamer {
 public:
  /// `transport` must be open (its owner's choice of interface). Starts the writer.
  CanSampleStreamer(std::unique_ptr<CanTransport> transport, CanSignalMap map,
                    std::size_t max_queued_frames = 100000);
  ~CanSampleStreamer();
  CanSampleStreamer(const CanSampleStreamer&) = delete;
  CanSampleStreamer& operator=(const CanSampleStreamer&) = delete;

  void push(const core::ImuSample& sample);
  /// Stops sending (samples pushed meanwhile are dropped, as from an IMU that stopped
  /// talking) or resumes.
  void set_silent(bool silent) { silent_ = silent; }
  /// Sends `frame` as it is (fault rehearsal: unknown ids, short frames, stale sequences).
  void inject(const can_frame& frame);
  std::uint64_t frames_sent() const { return sent_.load(); }
  std::uint64_t frames_dropped() const { return dropped_.load(); }

 private:
  void loop();

  std::unique_ptr<CanTransport> transport_;
  CanSignalMap map_;
  std::size_t max_queued_;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<can_frame> queue_;
  std::atomic<bool> silent_{false};
  std::atomic<bool> running_{true};
  std::atomic<std::uint64_t> sent_{0};
  std::atomic<std::uint64_t> dropped_{0};
  std::thread thread_;  // last: starts once everything above exists
};

}  // namespace calstand::drivers
