// Decoder of the VN-100 binary output stream (drivers/include/drivers/vectornav_decoder.hpp).
#include "drivers/vectornav_decoder.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <utility>

namespace calstand::drivers::vectornav {
namespace {

constexpr double kVectornavDecoderDegPerRad = 180.0 / 3.14159265358979323846;

}  // namespace

VectornavDecoder::VectornavDecoder(double sample_rate_hz, bool prefer_compensated)
    : sample_rate_hz_(sample_rate_hz > 0.0 ? sample_rate_hz : 800.0),
      prefer_compensated_(prefer_compensated) {}

void VectornavDecoder::restart() {
  hunt_.restart();
  copy_hunt_counters(hunt_, stats_);
  have_time_ = false;
}

std::vector<std::string> VectornavDecoder::take_device_reports() {
  return std::exchange(reports_, {});
}

void VectornavDecoder::on_ascii(const AsciiMessage& message) {
  ++stats_.ascii_messages;
  if (message.fields.empty() || message.fields[0] != "VNERR") return;
  // An error message, asynchronous or the answer to a command [UM004 §4.5].
  ++stats_.device_errors;
  reports_.push_back(error_text(message.fields.size() > 1 ? message.fields[1] : ""));
}

bool VectornavDecoder::on_binary(const BinaryFields& f, std::vector<core::ImuSample>& out) {
  const auto& gyro = prefer_compensated_ ? (f.gyro_rps ? f.gyro_rps : f.uncomp_gyro_rps)
                                         : (f.uncomp_gyro_rps ? f.uncomp_gyro_rps : f.gyro_rps);
  const auto& accel = prefer_compensated_
                          ? (f.accel_mps2 ? f.accel_mps2 : f.uncomp_accel_mps2)
                          : (f.uncomp_accel_mps2 ? f.uncomp_accel_mps2 : f.accel_mps2);
  if (!f.time_startup_ns || !gyro || !accel) {
    ++stats_.incomplete_frames;  // a good message of another configuration: no sample in it
    return false;
  }
  const std::uint64_t t_ns = *f.time_startup_ns;
  core::ImuSample s;
  s.device_time_s = static_cast<double>(t_ns) * 1e-9;
  // No counter in these groups: the output period counts the samples since start-up.
  const double ticks = std::round(static_cast<double>(t_ns) * 1e-9 * sample_rate_hz_);
  s.sequence = static_cast<std::uint32_t>(std::fmod(ticks, 4294967296.0));
  if (have_time_ && t_ns < last_time_ns_) {
    ++stats_.device_restarts;
    reports_.push_back(
        fmt::format("device restarted: TimeStartup went back from {:.6f} s to {:.6f} s",
                    static_cast<double>(last_time_ns_) * 1e-9, s.device_time_s));
  } else if (have_time_ && s.sequence != static_cast<std::uint32_t>(last_sequence_ + 1u)) {
    ++stats_.sequence_gaps;
  }
  have_time_ = true;
  last_time_ns_ = t_ns;
  last_sequence_ = s.sequence;
  for (std::size_t i = 0; i < 3; ++i) {
    s.gyro_dps[static_cast<Eigen::Index>(i)] =
        static_cast<double>((*gyro)[i]) * kVectornavDecoderDegPerRad;
    s.accel_mps2[static_cast<Eigen::Index>(i)] = static_cast<double>((*accel)[i]);
  }
  s.temperature_c = f.temperature_c ? static_cast<double>(*f.temperature_c) : 0.0;
  out.push_back(s);
  return true;
}

std::size_t VectornavDecoder::feed(std::span<const std::uint8_t> bytes,
                                   std::vector<core::ImuSample>& out) {
  hunt_.append(bytes);

  std::size_t decoded = 0;
  while (hunt_.buffered() > 0) {
    const std::span<const std::uint8_t> rest = hunt_.bytes();
    if (rest[0] == '$') {
      AsciiMessage message;
      const Scan scan = parse_ascii(rest, false, message);
      if (scan == Scan::kIncomplete) break;
      if (scan == Scan::kInvalid) {
        hunt_.discard(1);
        continue;
      }
      stats_.ascii_bytes += message.size;
      hunt_.consume(message.size);
      on_ascii(message);
      continue;
    }
    // Not '$' here: hunt for the next binary sync byte or ASCII message.
    if (hunt_.discard_until([](std::uint8_t b) { return b == kSync || b == '$'; })) continue;
    BinaryHeader header;
    const Scan scan = parse_binary_header(rest, header);
    if (scan == Scan::kIncomplete) break;
    if (scan == Scan::kInvalid) {
      // Checked before waiting for the body: an unmeasurable header must not stall the stream.
      if (!hunt_.quiet()) ++stats_.length_errors;
      hunt_.discard(1);
      continue;
    }
    const std::size_t size = header.message_bytes();
    if (rest.size() < size) break;
    // The CRC over everything after the sync, the CRC included, is 0 for a good message.
    if (crc16(rest.subspan(1, size - 1)) != 0) {
      if (!hunt_.quiet()) ++stats_.crc_errors;
      hunt_.discard(1);
      continue;
    }
    const BinaryFields fields = parse_binary_payload(rest.first(size), header);
    ++stats_.frames;
    stats_.frame_bytes += size;
    hunt_.consume(size);
    if (on_binary(fields, out)) ++decoded;
  }
  copy_hunt_counters(hunt_, stats_);
  return decoded;
}

std::map<std::string, std::uint64_t> VectornavDecoder::counters() const {
  auto out = frame_decoder_counters(stats_);
  out.insert({{"ascii_messages", stats_.ascii_messages},
              {"device_errors", stats_.device_errors},
              {"device_restarts", stats_.device_restarts},
              {"incomplete_frames", stats_.incomplete_frames}});
  return out;
}

}  // namespace calstand::drivers::vectornav
