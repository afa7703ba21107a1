#include "drivers/imu_frame.hpp"

#include <algorithm>
#include <bit>

namespace calstand::drivers {
namespace {

using namespace imu_frame;

// Byte-by-byte shifts make the wire order little-endian whatever the host's order is.
void put_u16(std::vector<std::uint8_t>& out, std::uint16_t v) {
  out.push_back(static_cast<std::uint8_t>(v & 0xFFu));
  out.push_back(static_cast<std::uint8_t>(v >> 8));
}

void put_u32(std::vector<std::uint8_t>& out, std::uint32_t v) {
  for (int shift = 0; shift < 32; shift += 8) out.push_back(static_cast<std::uint8_t>(v >> shift));
}

void put_u64(std::vector<std::uint8_t>& out, std::uint64_t v) {
  for (int shift = 0; shift < 64; shift += 8) out.push_back(static_cast<std::uint8_t>(v >> shift));
}

void put_f32(std::vector<std::uint8_t>& out, double v) {
  put_u32(out, std::bit_cast<std::uint32_t>(static_cast<float>(v)));
}

std::uint64_t get_le(const std::uint8_t* p, int size_bytes) {
  std::uint64_t v = 0;
  for (int i = size_bytes - 1; i >= 0; --i) v = (v << 8) | p[i];
  return v;
}

double get_f32(const std::uint8_t* p) {
  return std::bit_cast<float>(static_cast<std::uint32_t>(get_le(p, 4)));
}

}  // namespace

std::uint16_t crc16_ccitt(std::span<const std::uint8_t> bytes, std::uint16_t initial) {
  // Bitwise rather than table-driven: frames of tens of bytes at a few kHz do not need the
  // speed.
  std::uint16_t crc = initial;
  for (std::uint8_t byte : bytes) {
    crc = static_cast<std::uint16_t>(crc ^ (byte << 8));
    for (int bit = 0; bit < 8; ++bit) {
      crc = (crc & 0x8000u) ? static_cast<std::uint16_t>((crc << 1) ^ 0x1021u)
                            : static_cast<std::uint16_t>(crc << 1);
    }
  }
  return crc;
}

std::vector<std::uint8_t> encode_imu_frame(const core::ImuSample& sample) {
  std::vector<std::uint8_t> out;
  out.reserve(kFrameSize);
  out.push_back(kSync0);
  out.push_back(kSync1);
  out.push_back(static_cast<std::uint8_t>(kPayloadSize));
  put_u32(out, sample.sequence);
  put_u64(out, std::bit_cast<std::uint64_t>(sample.device_time_s));
  for (int i = 0; i < 3; ++i) put_f32(out, sample.gyro_dps[i]);
  for (int i = 0; i < 3; ++i) put_f32(out, sample.accel_mps2[i]);
  put_f32(out, sample.temperature_c);
  put_u16(out, crc16_ccitt_false(std::span(out).subspan(2)));
  return out;
}

CalstandFrameDecoder::CalstandFrameDecoder(std::uint64_t sequence_modulus)
    : sequence_modulus_(sequence_modulus == 0 ? std::uint64_t{1} << 32 : sequence_modulus) {}

void CalstandFrameDecoder::restart() {
  hunt_.restart();
  copy_hunt_counters(hunt_, stats_);
  have_sequence_ = false;
}

void CalstandFrameDecoder::check_sequence(std::uint32_t sequence) {
  if (have_sequence_) {
    const auto expected =
        static_cast<std::uint32_t>((std::uint64_t{last_sequence_} + 1) % sequence_modulus_);
    if (sequence != expected) ++stats_.sequence_gaps;
  }
  have_sequence_ = true;
  last_sequence_ = sequence;
}

std::size_t CalstandFrameDecoder::feed(std::span<const std::uint8_t> bytes,
                                       std::vector<core::ImuSample>& out) {
  hunt_.append(bytes);

  std::size_t decoded = 0;
  while (hunt_.buffered() >= 1) {
    const std::uint8_t* p = hunt_.bytes().data();
    const std::size_t avail = hunt_.buffered();

    // Hunt: skip to the next 0xA5 (a lone trailing 0xA5 may be the start of a frame).
    if (hunt_.discard_until([](std::uint8_t b) { return b == kSync0; })) continue;
    if (avail < 2) break;
    if (p[1] != kSync1) {
      hunt_.discard(1);
      continue;
    }
    if (avail < kHeaderSize) break;
    if (p[2] != kPayloadSize) {
      // Checked before waiting for the body: an impossible length must not stall the stream.
      if (!hunt_.quiet()) ++stats_.length_errors;
      hunt_.discard(1);
      continue;
    }
    if (avail < kFrameSize) break;

    const auto sent_crc = static_cast<std::uint16_t>(get_le(p + kHeaderSize + kPayloadSize, 2));
    if (crc16_ccitt_false({p + 2, 1 + kPayloadSize}) != sent_crc) {
      // Drop only the first sync byte: a real frame may begin inside this bad candidate.
      if (!hunt_.quiet()) ++stats_.crc_errors;
      hunt_.discard(1);
      continue;
    }

    const std::uint8_t* q = p + kHeaderSize;
    core::ImuSample s;
    s.sequence = static_cast<std::uint32_t>(get_le(q, 4));
    s.device_time_s = std::bit_cast<double>(get_le(q + 4, 8));
    for (int i = 0; i < 3; ++i) s.gyro_dps[i] = get_f32(q + 12 + 4 * i);
    for (int i = 0; i < 3; ++i) s.accel_mps2[i] = get_f32(q + 24 + 4 * i);
    s.temperature_c = get_f32(q + 36);
    check_sequence(s.sequence);
    out.push_back(s);
    ++decoded;
    ++stats_.frames;
    hunt_.consume(kFrameSize);
  }
  copy_hunt_counters(hunt_, stats_);
  return decoded;
}

std::map<std::string, std::uint64_t> CalstandFrameDecoder::counters() const {
  return frame_decoder_counters(stats_);
}

}  // namespace calstand::drivers
