#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <span>
#include <string>
#include <vector>

#include "core/imu_sample.hpp"
#include "drivers/frame_hunt.hpp"
#include "drivers/imu.hpp"

namespace calstand::drivers {

/// The calstand binary IMU frame (documented in docs/protocols.md, "IMU serial frame").
/// All multi-byte fields are little-endian; floats are IEEE 754.
///
///   offset size field
///   0      1    sync 0xA5
///   1      1    sync 0x5A
///   2      1    payload length [bytes], always 40 in this version
///   3      4    u32 sequence counter (wraps at 2^32 unless the device says otherwise)
///   7      8    f64 device time [s]
///   15     12   3 x f32 gyro x, y, z [deg/s]
///   27     12   3 x f32 accel x, y, z [m/s^2]
///   39     4    f32 temperature [degC]
///   43     2    u16 CRC-16/CCITT-FALSE over bytes 2..42 (length byte and payload)
///
/// The CRC covers the length byte so that a corrupted length cannot pass as a valid frame of
/// another size; it does not cover the sync bytes, which are checked by matching instead.
namespace imu_frame {
inline constexpr std::uint8_t kSync0 = 0xA5;
inline constexpr std::uint8_t kSync1 = 0x5A;
inline constexpr std::size_t kHeaderSize = 3;    ///< sync, sync, length [bytes]
inline constexpr std::size_t kPayloadSize = 40;  ///< [bytes]
inline constexpr std::size_t kCrcSize = 2;       ///< [bytes]
inline constexpr std::size_t kFrameSize = kHeaderSize + kPayloadSize + kCrcSize;  ///< 45 bytes
}  // namespace imu_frame

/// CRC-16 with polynomial 0x1021, no input or output reflection and no final XOR, starting
/// from `initial`: the family the calstand frame (0xFFFF) and VectorNav (0) both use.
std::uint16_t crc16_ccitt(std::span<const std::uint8_t> bytes, std::uint16_t initial);

/// CRC-16/CCITT-FALSE: polynomial 0x1021, initial value 0xFFFF, no input or output
/// reflection, no final XOR. Check value over ASCII "123456789" is 0x29B1.
inline std::uint16_t crc16_ccitt_false(std::span<const std::uint8_t> bytes) {
  return crc16_ccitt(bytes, 0xFFFF);
}

/// One calstand frame for `sample` (kFrameSize bytes). Gyro, accel and temperature are narrowed
/// to f32, as the device sends them; receive_time_s is not sent (the receiver stamps it).
std::vector<std::uint8_t> encode_imu_frame(const core::ImuSample& sample);

/// Turns a byte stream from an IMU into samples. One decoder per stream; not thread safe.
/// Implementations for other devices' frame formats plug in behind this interface.
class FrameDecoder {
 public:
  virtual ~FrameDecoder() = default;
  /// Consumes `bytes` (any split: a frame may straddle calls) and appends every complete,
  /// valid frame's sample to `out`, oldest first. Never throws on bad input: faults are counted.
  /// Returns the number of samples appended. receive_time_s is left 0 for the caller to stamp.
  virtual std::size_t feed(std::span<const std::uint8_t> bytes,
                           std::vector<core::ImuSample>& out) = 0;
  /// Named counters since construction (e.g. "frames", "crc_errors", "sequence_gaps").
  virtual std::map<std::string, std::uint64_t> counters() const = 0;
  /// The reader (re)starts after the line's input was flushed: the bytes before the next good
  /// frame are the tail of a frame cut by the flush, not garbage. They are counted as
  /// start_bytes (not a fault), and the sequence starts afresh (no gap against the last run's
  /// last frame).
  virtual void restart() = 0;
  /// What the device said about itself since the last call, in its own words: an error
  /// message, a status word flagging a sensor fault ("gyro x out of range"), a restart. Each
  /// becomes a fault event of the IMU.
  virtual std::vector<std::string> take_device_reports() { return {}; }
  /// The unit said who it is in its configuration dialogue (SerialImu calls this after each
  /// ImuConfigurator::configure()): a format whose scale factors depend on the model (Epson)
  /// learns it here.
  virtual void identified(const UnitIdentity& /*unit*/) {}
};

/// Counters of a CalstandFrameDecoder. Invariant: every byte fed is in exactly one of a good
/// frame, garbage_bytes, start_bytes, or buffered(): bytes_fed == frames * kFrameSize +
/// garbage_bytes + start_bytes + buffered.
struct ImuFrameCounters {
  std::uint64_t bytes_fed = 0;      ///< bytes given to feed() [bytes]
  std::uint64_t frames = 0;         ///< valid frames decoded (one sample each)
  std::uint64_t crc_errors = 0;     ///< frames whose sync and length matched but CRC did not
  std::uint64_t length_errors = 0;  ///< sync matched but the length byte was impossible
  std::uint64_t garbage_bytes = 0;  ///< bytes discarded while hunting for a frame [bytes]
  std::uint64_t resyncs = 0;        ///< runs of discarded bytes (each loss of frame lock)
  std::uint64_t sequence_gaps = 0;  ///< decoded frames whose sequence was not last + 1
  std::uint64_t start_bytes = 0;    ///< dropped before the first frame after restart() [bytes]
};

/// Decoder of the calstand frame. Hunts for the sync bytes; a candidate with an impossible
/// length or a bad CRC costs exactly one byte before the hunt resumes, so a valid frame that
/// follows (even one starting inside the bad candidate) is never skipped.
class CalstandFrameDecoder final : public FrameDecoder {
 public:
  /// `sequence_modulus`: the device's counter wraps to 0 at this value (2^32 by default), so
  /// the step from modulus - 1 to 0 is not a gap.
  explicit CalstandFrameDecoder(std::uint64_t sequence_modulus = std::uint64_t{1} << 32);

  std::size_t feed(std::span<const std::uint8_t> bytes, std::vector<core::ImuSample>& out) override;
  std::map<std::string, std::uint64_t> counters() const override;
  void restart() override;

  const ImuFrameCounters& stats() const { return stats_; }
  /// Bytes held back waiting for the rest of a frame [bytes].
  std::size_t buffered() const { return hunt_.buffered(); }

 private:
  void check_sequence(std::uint32_t sequence);

  std::uint64_t sequence_modulus_;
  FrameHunt hunt_;
  bool have_sequence_ = false;
  std::uint32_t last_sequence_ = 0;
  ImuFrameCounters stats_;
};

}  // namespace calstand::drivers
