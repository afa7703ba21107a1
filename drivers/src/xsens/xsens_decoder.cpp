// Decoder of the Xsens MTi output stream (drivers/xsens_decoder.hpp), from MT0101P, "MT
// Low-Level Communication Protocol Documentation" (Xbus message structure; MTData2 and XDI).
#include "drivers/xsens_decoder.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <utility>

namespace calstand::drivers::xsens {
namespace {

// SampleTimeFine wraps at 2^32 ticks (119.3 h at 10 kHz). A step back is a wrap only when the
// forward step across the wrap is short; otherwise the device restarted (its time began at 0).
constexpr std::uint64_t kXsensTickWrap = std::uint64_t{1} << 32;
constexpr std::uint64_t kXsensMaxWrapStepTicks = 10 * 10000;  // 10 s at 10 kHz

std::uint64_t xsens_read_be(const std::uint8_t* p, std::size_t size_bytes) {
  std::uint64_t v = 0;
  for (std::size_t i = 0; i < size_bytes; ++i) v = (v << 8) | p[i];
  return v;
}

}  // namespace

XsensDecoder::XsensDecoder() : temperature_c_(std::numeric_limits<double>::quiet_NaN()) {}

void XsensDecoder::restart() {
  hunt_.restart();
  copy_hunt_counters(hunt_, stats_);
  have_sequence_ = false;
  // Device time and the latest temperature survive: a flush of the line does not restart the
  // device, and its clock goes on.
}

std::vector<std::string> XsensDecoder::take_device_reports() { return std::exchange(reports_, {}); }

void XsensDecoder::device_restarted(const std::string& why) {
  ++stats_.device_restarts;
  reports_.push_back(why);
  have_time_ = false;
  epoch_ticks_ = 0;
  have_sequence_ = false;  // a new run of the counter, not a gap
}

double XsensDecoder::unwrap_time(std::uint32_t ticks) {
  if (have_time_ && ticks < last_ticks_) {
    const std::uint64_t forward = kXsensTickWrap - last_ticks_ + ticks;
    if (forward <= kXsensMaxWrapStepTicks) {
      epoch_ticks_ += kXsensTickWrap;
    } else {
      const double before_s = static_cast<double>(epoch_ticks_ + last_ticks_) / kSampleTimeFineHz;
      device_restarted(
          fmt::format("device restarted: SampleTimeFine went back from {:.4f} s to {:.4f} s",
                      before_s, static_cast<double>(ticks) / kSampleTimeFineHz));
    }
  }
  have_time_ = true;
  last_ticks_ = ticks;
  return static_cast<double>(epoch_ticks_ + ticks) / kSampleTimeFineHz;
}

bool XsensDecoder::on_mtdata2(std::span<const std::uint8_t> data, core::ImuSample& sample) {
  bool have_counter = false, have_time = false, have_accel = false, have_gyro = false;
  std::uint16_t counter = 0;
  std::uint32_t ticks = 0;
  std::size_t at = 0;
  // An MTData2 packet is a run of items: XDI (u16), size (u8), data (MT0101P, "MTData2").
  while (at < data.size()) {
    if (data.size() - at < 3) {
      ++stats_.packet_errors;
      return false;
    }
    const auto id = static_cast<std::uint16_t>(xsens_read_be(data.data() + at, 2));
    const std::size_t size = data[at + 2];
    const std::uint8_t* value = data.data() + at + 3;
    if (data.size() - at - 3 < size) {
      ++stats_.packet_errors;
      return false;
    }
    at += 3 + size;
    const auto precision = static_cast<Precision>(id & xdi::kPrecisionMask);
    const std::size_t one = value_size(precision);
    switch (id & xdi::kTypeMask) {
      case xdi::kPacketCounter:
        if (size != 2) break;
        counter = static_cast<std::uint16_t>(xsens_read_be(value, 2));
        have_counter = true;
        break;
      case xdi::kSampleTimeFine:
        if (size != 4) break;
        ticks = static_cast<std::uint32_t>(xsens_read_be(value, 4));
        have_time = true;
        break;
      case xdi::kAcceleration& xdi::kTypeMask:
        if (size != 3 * one) break;
        for (int i = 0; i < 3; ++i) {
          sample.accel_mps2[i] = get_value(value + one * static_cast<std::size_t>(i), precision);
        }
        have_accel = true;
        break;
      case xdi::kRateOfTurn& xdi::kTypeMask:
        if (size != 3 * one) break;
        for (int i = 0; i < 3; ++i) {
          // The wire carries rad/s (MT0101P, XDI 0x8020); the station wants deg/s.
          sample.gyro_dps[i] = get_value(value + one * static_cast<std::size_t>(i), precision) *
                               (180.0 / std::numbers::pi);
        }
        have_gyro = true;
        break;
      case xdi::kTemperature& xdi::kTypeMask:
        if (size != one) break;
        temperature_c_ = get_value(value, precision);
        break;
      default:
        break;  // other outputs a unit may have been left with: not ours, skipped
    }
  }
  if (!(have_counter && have_time && have_accel && have_gyro)) {
    ++stats_.incomplete_packets;
    return false;
  }
  if (!sample.gyro_dps.allFinite() || !sample.accel_mps2.allFinite() ||
      std::isinf(temperature_c_)) {
    ++stats_.invalid_samples;  // a float the device should never send: no sample to trust
    return false;
  }
  if (std::isnan(temperature_c_)) {
    // Temperature comes at a lower rate: the packets before the first one have none to carry.
    // They are held back (counted) rather than delivered with a NaN that would poison every
    // mean taken over them; this happens only at the start of a stream.
    ++stats_.awaiting_temperature;
    return false;
  }
  sample.sequence = counter;
  sample.device_time_s = unwrap_time(ticks);
  sample.temperature_c = temperature_c_;
  if (have_sequence_ && counter != static_cast<std::uint16_t>(last_sequence_ + 1)) {
    ++stats_.sequence_gaps;
  }
  have_sequence_ = true;
  last_sequence_ = counter;
  return true;
}

void XsensDecoder::on_message(const Message& message, std::vector<core::ImuSample>& out) {
  switch (message.mid) {
    case mid::kMtData2: {
      core::ImuSample sample;
      if (on_mtdata2(message.data, sample)) {
        out.push_back(sample);
        ++stats_.frames;
      }
      return;
    }
    case mid::kError:
      ++stats_.messages;
      ++stats_.device_errors;
      reports_.push_back(error_text(message.data));
      return;
    case mid::kWakeUp:
      ++stats_.messages;
      device_restarted("device restarted: WakeUp (power-on)");
      return;
    default:
      ++stats_.messages;  // acks and replies of a dialogue: not measurements
      return;
  }
}

std::size_t XsensDecoder::feed(std::span<const std::uint8_t> bytes,
                               std::vector<core::ImuSample>& out) {
  hunt_.append(bytes);

  const std::size_t before = out.size();
  while (hunt_.buffered() > 0) {
    const std::uint8_t* p = hunt_.bytes().data();
    const std::size_t avail = hunt_.buffered();
    if (hunt_.discard_until([](std::uint8_t b) { return b == kPreamble; })) continue;
    Scan scan = scan_message({p, avail});
    if (scan.status == ScanStatus::kIncomplete) break;
    if (scan.status != ScanStatus::kMessage) {
      // Drop only the preamble: a real message may begin inside this bad candidate.
      if (!hunt_.quiet()) {
        if (scan.status == ScanStatus::kBadChecksum) ++stats_.crc_errors;
        if (scan.status == ScanStatus::kBadLength) ++stats_.length_errors;
      }
      hunt_.discard(1);
      continue;
    }
    hunt_.consume(scan.size);
    stats_.message_bytes += scan.size;
    on_message(scan.message, out);
  }
  copy_hunt_counters(hunt_, stats_);
  return out.size() - before;
}

std::map<std::string, std::uint64_t> XsensDecoder::counters() const {
  auto out = frame_decoder_counters(stats_);
  out.insert({{"messages", stats_.messages},
              {"packet_errors", stats_.packet_errors},
              {"incomplete_packets", stats_.incomplete_packets},
              {"device_errors", stats_.device_errors},
              {"device_restarts", stats_.device_restarts},
              {"awaiting_temperature", stats_.awaiting_temperature},
              {"invalid_samples", stats_.invalid_samples}});
  return out;
}

}  // namespace calstand::drivers::xsens
