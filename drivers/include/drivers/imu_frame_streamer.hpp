#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "core/imu_sample.hpp"
#include "drivers/imu_wire_format.hpp"
#include "drivers/pseudo_terminal.hpp"

namespace calstand::drivers {

/// The serial end of a simulated IMU: a device emulator (imu_wire_format.hpp; the calstand
/// frame unless another format is given) on a pseudo-terminal whose slave path a SerialImu
/// opens. The host's bytes (configuration, identity requests) are answered by the emulator;
/// push() is called by the world as samples are produced and never blocks; a writer thread
/// sends what the emulator makes of them. As on a real line, what nobody reads is lost: a write
/// nobody takes within a second drops every frame queued, and from then until a write is taken
/// again only the newest frame is kept (a client opening the line later does not get the frames
/// of before as its first); beyond `max_queued_frames` (a held burst) the oldest frames are
/// dropped (counted), and the receiver sees a sequence gap.
class ImuFrameStreamer {
 public:
  explicit ImuFrameStreamer(std::unique_ptr<ImuDeviceEmulator> emulator,
                            std::size_t max_queued_frames = 100000);
  ~ImuFrameStreamer();
  ImuFrameStreamer(const ImuFrameStreamer&) = delete;
  ImuFrameStreamer& operator=(const ImuFrameStreamer&) = delete;

  const std::string& path() const { return pty_.slave_path(); }
  void push(const core::ImuSample& sample);
  /// Stops sending and answering (frames pushed meanwhile are dropped, as from an IMU that
  /// stopped talking) or resumes.
  void set_silent(bool silent) { silent_ = silent; }
  /// Writes `bytes` on the line as they are (fault rehearsal: garbage, corrupted frames).
  void inject(std::vector<std::uint8_t> bytes);
  /// Holds the frames back (they queue, up to the queue's limit) or lets them go, all at once:
  /// a burst, as from a USB adapter or a gateway that buffers (fault rehearsal).
  void set_held(bool held) {
    held_ = held;
    wake_.notify_all();
  }
  /// Moves the IMU's own clock by `seconds` from now on (a restart, a wrap, a time set: fault
  /// rehearsal); the frames' device time stamps jump, the samples do not.
  void jump_clock(double seconds) { clock_offset_s_ = clock_offset_s_.load() + seconds; }
  std::uint64_t frames_sent() const { return sent_.load(); }
  std::uint64_t frames_dropped() const { return dropped_.load(); }

 private:
  void loop();
  void host_loop();
  void queue(std::vector<std::uint8_t> bytes, bool is_frame);
  /// Drops the frames queued (not the replies): the line was not read.
  void drop_queued_frames();

  PseudoTerminal pty_;
  std::mutex emulator_mutex_;  // the world's thread (push) and the host thread share it
  std::unique_ptr<ImuDeviceEmulator> emulator_;
  std::size_t max_queued_;
  std::mutex mutex_;
  std::condition_variable wake_;
  struct Queued {
    std::vector<std::uint8_t> bytes;
    bool is_frame;  // a sample's frame (counted as sent or dropped), not a reply
  };
  std::deque<Queued> queue_;
  std::atomic<bool> silent_{false};
  std::atomic<bool> held_{false};
  std::atomic<double> clock_offset_s_{0.0};  ///< added to the device time stamps [s]
  std::atomic<bool> running_{true};
  std::atomic<std::uint64_t> sent_{0};
  std::atomic<std::uint64_t> dropped_{0};
  std::thread thread_;
  std::thread host_thread_;
};

}  // namespace calstand::drivers
