#pragma once

// Decoder of the STIM300 normal-mode datagrams (docs/protocols.md, "Sensonor STIM300").

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "drivers/frame_hunt.hpp"
#include "drivers/imu_frame.hpp"
#include "drivers/stim300_options.hpp"

namespace calstand::drivers::stim300 {

/// Counters of a Stim300Decoder. Every byte fed is in exactly one of a datagram (normal or
/// start-up, with its CR LF), garbage_bytes, start_bytes or buffered().
struct Stim300Counters {
  std::uint64_t bytes_fed = 0;             ///< [bytes]
  std::uint64_t frames = 0;                ///< valid normal-mode datagrams (one sample each)
  std::uint64_t frame_bytes = 0;           ///< bytes of valid datagrams incl. start-up ones [bytes]
  std::uint64_t crc_errors = 0;            ///< identifier matched, CRC-32 did not
  std::uint64_t length_errors = 0;         ///< CRC matched but the configured CR LF was missing
  std::uint64_t garbage_bytes = 0;         ///< discarded while hunting [bytes]
  std::uint64_t resyncs = 0;               ///< runs of discarded bytes
  std::uint64_t sequence_gaps = 0;         ///< datagrams whose counter was not last + 1 (mod 256)
  std::uint64_t start_bytes = 0;           ///< dropped before the first datagram after restart()
  std::uint64_t startup_datagrams = 0;     ///< part/serial/configuration datagrams (unit start)
  std::uint64_t status_flags = 0;          ///< datagrams with a status bit set
  std::uint64_t terminated_datagrams = 0;  ///< datagrams followed by CR LF
};

/// Hunts for a datagram identifier, checks the CRC-32 (and CR LF when configured); a bad
/// candidate costs one byte. Samples: gyro [deg/s] and accelerometer (the inclinometer when the
/// datagram has no accelerometer) [m/s^2] in the unit's axes; temperature: mean of the gyro
/// temperatures; sequence: the 8-bit counter unwrapped to 32 bits; device time: the unwrapped
/// counter / sample rate minus the latency. A start-up datagram (part number, serial number,
/// configuration: the unit was powered or reset) starts the count afresh, so device time goes
/// back, and is reported; so is every change of a status byte to a flagged value.
class Stim300Decoder final : public FrameDecoder {
 public:
  Stim300Decoder(Stim300Options options, double sample_rate_hz);

  std::size_t feed(std::span<const std::uint8_t> bytes, std::vector<core::ImuSample>& out) override;
  std::map<std::string, std::uint64_t> counters() const override;
  void restart() override;
  std::vector<std::string> take_device_reports() override;

  const Stim300Counters& stats() const { return stats_; }
  std::size_t buffered() const { return hunt_.buffered(); }
  /// The identifier the decoder reads (the configured one, or the first that arrived).
  std::optional<std::uint8_t> datagram_id() const { return locked_id_; }

 private:
  void discard(std::size_t count);
  void consume(std::size_t count);
  bool is_candidate(std::uint8_t byte) const;
  core::ImuSample to_sample(const Datagram& d, const DatagramLayout& layout);
  void check_status(const Datagram& d, const DatagramLayout& layout);
  void on_startup_datagram(std::span<const std::uint8_t> datagram);

  Stim300Options options_;
  double sample_rate_hz_;
  std::optional<std::uint8_t> locked_id_;
  FrameHunt hunt_;
  bool after_datagram_ = false;  // a CR LF here ends the previous datagram (termination unset)
  bool have_counter_ = false;
  bool count_afresh_ = false;  // the unit restarted: the next counter starts the count
  bool gap_free_ = false;      // the next counter after restart() is not a gap
  std::uint8_t last_counter_ = 0;
  std::uint32_t unwrapped_ = 0;
  std::array<std::uint8_t, 3> last_status_{};
  std::array<std::uint8_t, 3> last_temp_status_{};
  std::vector<std::string> reports_;
  Stim300Counters stats_;
};

}  // namespace calstand::drivers::stim300
