#pragma once

#include <cstdint>
#include <map>
#include <span>
#include <string>
#include <vector>

#include "drivers/frame_hunt.hpp"
#include "drivers/imu_frame.hpp"
#include "drivers/xsens_protocol.hpp"

namespace calstand::drivers::xsens {

/// Counters of an XsensDecoder. Invariant: bytes_fed == message_bytes + garbage_bytes +
/// start_bytes + buffered().
struct DecoderCounters {
  std::uint64_t bytes_fed = 0;           ///< [bytes]
  std::uint64_t message_bytes = 0;       ///< bytes in valid messages of any kind [bytes]
  std::uint64_t frames = 0;              ///< MTData2 packets that gave a sample
  std::uint64_t messages = 0;            ///< valid messages other than MTData2 (acks, Error...)
  std::uint64_t crc_errors = 0;          ///< candidates whose checksum did not sum to 0
  std::uint64_t length_errors = 0;       ///< extended length beyond 2048 bytes
  std::uint64_t packet_errors = 0;       ///< MTData2 whose items overran the packet
  std::uint64_t incomplete_packets = 0;  ///< MTData2 without counter, time, accel or gyro
  std::uint64_t garbage_bytes = 0;       ///< discarded while hunting [bytes]
  std::uint64_t resyncs = 0;             ///< runs of discarded bytes
  std::uint64_t sequence_gaps = 0;       ///< PacketCounter not last + 1 (mod 65536)
  std::uint64_t start_bytes = 0;         ///< dropped before the first message after restart()
  std::uint64_t device_errors = 0;       ///< Error messages received
  std::uint64_t device_restarts = 0;     ///< WakeUp, or SampleTimeFine going back
  /// Packets held back at the start of the stream because no temperature had come yet.
  std::uint64_t awaiting_temperature = 0;
  std::uint64_t invalid_samples = 0;  ///< packets with a NaN or infinite value, dropped
};

/// Decoder of an MTi's output: Xbus messages carrying MTData2 packets (MT0101P). Hunts for the
/// preamble 0xFA followed by BID 0xFF; a candidate with a bad checksum or an impossible length
/// costs one byte. Values are read in whatever precision each XDI's format bits say; the axes
/// are passed on as the unit outputs them (its configured coordinate system). Rate of turn
/// comes in rad/s and leaves in deg/s. SampleTimeFine (10 kHz, u32) is unwrapped into
/// device_time_s; PacketCounter (u16) is the sequence. Packets without a temperature carry the
/// latest one; those before the first temperature give no sample (awaiting_temperature). Error
/// and WakeUp messages become device reports.
class XsensDecoder final : public FrameDecoder {
 public:
  XsensDecoder();
  std::size_t feed(std::span<const std::uint8_t> bytes, std::vector<core::ImuSample>& out) override;
  std::map<std::string, std::uint64_t> counters() const override;
  void restart() override;
  std::vector<std::string> take_device_reports() override;

  const DecoderCounters& stats() const { return stats_; }
  std::size_t buffered() const { return hunt_.buffered(); }

 private:
  void on_message(const Message& message, std::vector<core::ImuSample>& out);
  bool on_mtdata2(std::span<const std::uint8_t> data, core::ImuSample& sample);
  double unwrap_time(std::uint32_t ticks);
  void device_restarted(const std::string& why);

  FrameHunt hunt_;
  bool have_sequence_ = false;
  std::uint16_t last_sequence_ = 0;
  bool have_time_ = false;
  std::uint32_t last_ticks_ = 0;
  std::uint64_t epoch_ticks_ = 0;  // 2^32 per wrap of SampleTimeFine
  double temperature_c_;           // the latest temperature [degC]; NaN until one came
  std::vector<std::string> reports_;
  DecoderCounters stats_;
};

}  // namespace calstand::drivers::xsens
