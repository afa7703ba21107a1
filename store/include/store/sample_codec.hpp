#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "core/imu_sample.hpp"

namespace calstand::store {

/// Binary layout of a sample chunk (the `data` blob of table sample_chunks).
///
/// All numbers little-endian, no padding, IEEE-754 floats.
///
///     header, 32 bytes:
///       0  char[4]  magic "CSMP"
///       4  u8       layout version = 1
///       5  u8       encoding: 1 = compact (float32), 2 = exact (float64)
///       6  u16      reserved, 0
///       8  u32      count: samples in the chunk (> 0)
///      12  u32      first_sequence: sequence counter of the first sample
///      16  f64      first_receive_time_s: station clock of the first sample [s]
///      24  f64      first_device_time_s: device clock of the first sample [s]
///     then `count` samples of the encoding's layout:
///
///     compact (1), 38 bytes per sample ("<ffH7f" in Python's struct):
///       0  f32  receive_time_s - first_receive_time_s [s]
///       4  f32  device_time_s - first_device_time_s [s]
///       8  u16  sequence - first_sequence (modulo 2^32)
///      10  f32  gyro x, y, z [deg/s]
///      22  f32  accel x, y, z [m/s^2]
///      34  f32  temperature [degC]
///
///     exact (2), 76 bytes per sample ("<ddI7d"), used by import so export is bit-exact:
///       0  f64  receive_time_s [s]
///       8  f64  device_time_s [s]
///      16  u32  sequence
///      20  f64  gyro x, y, z [deg/s]
///      44  f64  accel x, y, z [m/s^2]
///      68  f64  temperature [degC]
///
/// Why compact suffices: float32 keeps 24 bits, i.e. 6e-6 deg/s (0.02 deg/h) at 100 deg/s and
/// 6e-7 m/s^2 at 1 g, below any IMU's noise per sample, and step means are computed from the
/// full-precision samples anyway (table step_means). Time offsets stay within
/// ChunkLimits::max_span_s (60 s: float32 resolution 4 us) and sequence offsets within u16;
/// a sample that would break either starts a new chunk.
enum class SampleEncoding : std::uint8_t {
  kCompact = 1,  ///< float32 values, time and sequence offsets (38 bytes per sample)
  kExact = 2,    ///< float64 values, absolute times (76 bytes per sample)
};

inline constexpr std::size_t kChunkHeaderBytes = 32;
inline constexpr std::size_t kCompactSampleBytes = 38;
inline constexpr std::size_t kExactSampleBytes = 76;
inline constexpr std::uint8_t kChunkLayoutVersion = 1;

/// Bytes per sample of `encoding`.
std::size_t sample_bytes(SampleEncoding encoding);

/// When a chunk is closed and a new one started.
struct ChunkLimits {
  std::uint32_t max_samples = 4096;  ///< samples per chunk
  double max_span_s = 60.0;          ///< largest |time - first time| in a compact chunk [s]
};

/// Builds one chunk blob sample by sample. Not thread safe; cheap to reuse (clear() keeps the
/// buffer).
class ChunkEncoder {
 public:
  explicit ChunkEncoder(SampleEncoding encoding, ChunkLimits limits = {});

  /// True when `s` can join this chunk: always for an empty chunk; otherwise when the chunk
  /// has room and, for compact, the time and sequence offsets of `s` fit.
  bool fits(const core::ImuSample& s) const;
  /// Appends `s`. Precondition: fits(s) (checked; std::logic_error otherwise).
  void append(const core::ImuSample& s);

  std::uint32_t count() const { return count_; }
  bool empty() const { return count_ == 0; }
  SampleEncoding encoding() const { return encoding_; }
  double first_receive_time_s() const { return first_receive_s_; }
  double last_receive_time_s() const { return last_receive_s_; }

  /// The chunk so far, header included (valid until the next append or clear).
  std::span<const std::uint8_t> bytes() const;
  /// Empties the chunk for reuse.
  void clear();

 private:
  SampleEncoding encoding_;
  ChunkLimits limits_;
  // Sized for a full chunk once; append() writes in place. The header is written by bytes(),
  // not per sample.
  mutable std::vector<std::uint8_t> bytes_;
  std::size_t size_ = kChunkHeaderBytes;
  std::uint32_t count_ = 0;
  std::uint32_t first_sequence_ = 0;
  double first_receive_s_ = 0.0;
  double first_device_s_ = 0.0;
  double last_receive_s_ = 0.0;
};

/// Header fields of a chunk blob.
struct ChunkHeader {
  SampleEncoding encoding = SampleEncoding::kCompact;
  std::uint32_t count = 0;
  std::uint32_t first_sequence = 0;
  double first_receive_time_s = 0.0;
  double first_device_time_s = 0.0;
};

/// Reads and checks the header of `blob`. Throws StoreError ("decode sample chunk") on a wrong
/// magic, an unknown version or encoding, or a size that does not match the count.
ChunkHeader read_chunk_header(std::span<const std::uint8_t> blob);

/// Appends the samples of `blob` to `out`; throws as read_chunk_header().
void decode_chunk(std::span<const std::uint8_t> blob, std::vector<core::ImuSample>& out);

/// The samples of `blob`; throws as read_chunk_header().
std::vector<core::ImuSample> decode_chunk(std::span<const std::uint8_t> blob);

/// Encodes `samples` as one chunk. Throws std::invalid_argument when they do not fit one chunk
/// under `limits` (empty input included).
std::vector<std::uint8_t> encode_chunk(std::span<const core::ImuSample> samples,
                                       SampleEncoding encoding, ChunkLimits limits = {});

}  // namespace calstand::store
