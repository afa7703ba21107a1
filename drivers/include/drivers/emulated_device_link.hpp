#pragma once

#include <chrono>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <span>
#include <vector>

#include "drivers/imu_wire_format.hpp"
#include "drivers/serial_port.hpp"

namespace calstand::drivers {

/// A device emulator behind an in-memory link, as a host sees a unit on its serial line: what
/// the host writes is answered at once, and samples given to the device come out as its frames.
/// For tests and benchmarks of a whole wire format (dialogue, then stream) without a terminal.
/// Not thread safe.
class EmulatedDeviceLink final : public ByteTransport {
 public:
  explicit EmulatedDeviceLink(std::unique_ptr<ImuDeviceEmulator> device)
      : device_(std::move(device)) {}

  /// The device samples: its frame (if it sends one now) waits on the line for read().
  void sample(const core::ImuSample& s) {
    const auto bytes = device_->on_sample(s);
    line_.insert(line_.end(), bytes.begin(), bytes.end());
  }
  /// Bytes waiting on the line [bytes].
  std::size_t pending() const { return line_.size(); }
  /// The unit samples on its own whenever the host reads an empty line (one sample of `next`
  /// per read), as a unit streaming in real time does during a dialogue that watches the
  /// stream (STIM300); an empty function stops it.
  void free_run(std::function<core::ImuSample()> next) { free_run_ = std::move(next); }

  IoResult read(std::span<std::uint8_t> buffer, std::chrono::milliseconds /*timeout*/) override {
    if (line_.empty() && free_run_) sample(free_run_());
    // Nothing waits in memory: a timeout is immediate (the dialogue's retries stay fast).
    const std::size_t n = std::min(buffer.size(), line_.size());
    std::copy_n(line_.begin(), n, buffer.begin());
    line_.erase(line_.begin(), line_.begin() + static_cast<std::ptrdiff_t>(n));
    return {n, {}};
  }
  IoResult write(std::span<const std::uint8_t> bytes,
                 std::chrono::milliseconds /*timeout*/) override {
    const auto reply = device_->on_host_bytes(bytes);
    line_.insert(line_.end(), reply.begin(), reply.end());
    return {bytes.size(), {}};
  }

 private:
  std::unique_ptr<ImuDeviceEmulator> device_;
  std::deque<std::uint8_t> line_;
  std::function<core::ImuSample()> free_run_;
};

}  // namespace calstand::drivers
