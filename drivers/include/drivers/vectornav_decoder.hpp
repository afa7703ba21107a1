#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <span>
#include <string>
#include <vector>

#include "drivers/frame_hunt.hpp"
#include "drivers/imu_frame.hpp"
#include "drivers/vectornav_protocol.hpp"

namespace calstand::drivers::vectornav {

/// Counters of a VectornavDecoder. Invariant: bytes_fed == frame_bytes + ascii_bytes +
/// garbage_bytes + start_bytes + buffered().
struct DecoderCounters {
  std::uint64_t bytes_fed = 0;          ///< [bytes]
  std::uint64_t frames = 0;             ///< binary messages with a good CRC
  std::uint64_t frame_bytes = 0;        ///< bytes of those messages [bytes]
  std::uint64_t crc_errors = 0;         ///< binary candidates whose CRC failed
  std::uint64_t length_errors = 0;      ///< binary candidates whose header cannot be measured
  std::uint64_t garbage_bytes = 0;      ///< [bytes]
  std::uint64_t resyncs = 0;            ///< runs of garbage
  std::uint64_t sequence_gaps = 0;      ///< samples whose derived sequence was not last + 1
  std::uint64_t start_bytes = 0;        ///< dropped before the first message after restart()
  std::uint64_t ascii_messages = 0;     ///< good ASCII messages (replies, async output, errors)
  std::uint64_t ascii_bytes = 0;        ///< [bytes]
  std::uint64_t device_errors = 0;      ///< `$VNERR` messages
  std::uint64_t device_restarts = 0;    ///< TimeStartup went back
  std::uint64_t incomplete_frames = 0;  ///< good messages without time, gyro or accel
};

/// Decoder of the VN-100 binary output message [UM001 §4.3], with the ASCII messages the unit
/// may interleave (`$VNERR` becomes a device report). Hunts for the sync byte 0xFA (or '$'); a
/// candidate whose header cannot be measured or whose CRC fails costs one byte.
///
/// The groups have no message counter, so the sequence is derived from TimeStartup (u64 ns):
/// round(TimeStartup * sample_rate_hz), modulo 2^32; a step other than +1 is a gap. TimeStartup
/// going back is a device restart: reported, and the sequence starts afresh.
class VectornavDecoder final : public FrameDecoder {
 public:
  /// `sample_rate_hz`: the configured output rate (the period the sequence counts).
  VectornavDecoder(double sample_rate_hz, bool prefer_compensated);

  std::size_t feed(std::span<const std::uint8_t> bytes, std::vector<core::ImuSample>& out) override;
  std::map<std::string, std::uint64_t> counters() const override;
  void restart() override;
  std::vector<std::string> take_device_reports() override;

  const DecoderCounters& stats() const { return stats_; }
  std::size_t buffered() const { return hunt_.buffered(); }

 private:
  void on_ascii(const AsciiMessage& message);
  bool on_binary(const BinaryFields& fields, std::vector<core::ImuSample>& out);

  double sample_rate_hz_;
  bool prefer_compensated_;
  FrameHunt hunt_;
  bool have_time_ = false;
  std::uint64_t last_time_ns_ = 0;
  std::uint32_t last_sequence_ = 0;
  std::vector<std::string> reports_;
  DecoderCounters stats_;
};

}  // namespace calstand::drivers::vectornav
