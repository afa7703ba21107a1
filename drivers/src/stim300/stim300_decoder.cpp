// STIM300 datagrams to samples (stim300_decoder.hpp).
#include "drivers/stim300_decoder.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <utility>

namespace calstand::drivers::stim300 {
namespace {

const char* stim300_group_name(Group group) {
  switch (group) {
    case Group::kGyro:
      return "gyro";
    case Group::kAcc:
      return "accelerometer";
    default:
      return "inclinometer";
  }
}

}  // namespace

Stim300Decoder::Stim300Decoder(Stim300Options options, double sample_rate_hz)
    : options_(options),
      sample_rate_hz_(sample_rate_hz > 0.0 ? sample_rate_hz : 2000.0),
      locked_id_(options.datagram) {}

void Stim300Decoder::restart() {
  // What was held back belongs to the line before the flush: dropped, as start bytes.
  hunt_.restart();
  copy_hunt_counters(hunt_, stats_);
  after_datagram_ = false;
  gap_free_ = true;
}

std::vector<std::string> Stim300Decoder::take_device_reports() {
  return std::exchange(reports_, {});
}

void Stim300Decoder::discard(std::size_t count) {
  hunt_.discard(count);
  after_datagram_ = false;  // a CR LF after garbage ends no datagram
}

void Stim300Decoder::consume(std::size_t count) {
  // A terminator or start-up datagram does not end the quiet state after restart(): only a
  // normal datagram (feed() calls hunt_.consume() for those) proves the stream is in step.
  hunt_.pass(count);
  stats_.frame_bytes += count;
}

bool Stim300Decoder::is_candidate(std::uint8_t byte) const {
  if (is_startup_id(byte)) return true;
  if (locked_id_) return byte == *locked_id_;
  return datagram_layout(byte).has_value();
}

void Stim300Decoder::on_startup_datagram(std::span<const std::uint8_t> datagram) {
  ++stats_.startup_datagrams;
  // Before the first datagram after restart(): a reply of the configuration dialogue (N, I, C)
  // left on the line, not a restart of the unit.
  if (hunt_.quiet()) return;
  // The unit sends these after power-on or reset: its counter starts again.
  count_afresh_ = true;
  if (kPartNumber.matches(datagram[0])) {
    reports_.push_back(
        fmt::format("restart: the unit sent its part number datagram ({})", digits_of(datagram)));
  }
}

void Stim300Decoder::check_status(const Datagram& d, const DatagramLayout& layout) {
  const std::array<bool, 3> present{true, layout.acc, layout.incl};
  bool flagged = false;
  for (std::size_t g = 0; g < 3; ++g) {
    if (!present[g]) continue;
    const auto group = static_cast<Group>(g);
    if (d.status[g] != 0) flagged = true;
    if (d.status[g] != last_status_[g]) {
      for (auto& line : status_text(group, false, d.status[g])) reports_.push_back(line);
      if (d.status[g] == 0) {
        reports_.push_back(fmt::format("{}: status clear", stim300_group_name(group)));
      }
      last_status_[g] = d.status[g];
    }
    if (!layout.temp) continue;
    if (d.temp_status[g] != 0) flagged = true;
    if (d.temp_status[g] != last_temp_status_[g]) {
      for (auto& line : status_text(group, true, d.temp_status[g])) reports_.push_back(line);
      last_temp_status_[g] = d.temp_status[g];
    }
  }
  if (flagged) ++stats_.status_flags;
}

core::ImuSample Stim300Decoder::to_sample(const Datagram& d, const DatagramLayout& layout) {
  // Sequence and device time: the 8-bit counter, one step per datagram, unwrapped.
  if (!have_counter_ || count_afresh_) {
    unwrapped_ = d.counter;
  } else {
    const auto step = static_cast<std::uint8_t>(d.counter - last_counter_);
    if (step != 1 && !gap_free_) ++stats_.sequence_gaps;
    unwrapped_ += step == 0 ? 256u : step;
  }
  have_counter_ = true;
  count_afresh_ = false;
  gap_free_ = false;
  last_counter_ = d.counter;

  core::ImuSample s;
  s.sequence = unwrapped_;
  s.device_time_s = static_cast<double>(unwrapped_) / sample_rate_hz_ - d.latency_us * 1e-6;
  // Increments are per sample: rate = increment * sample rate.
  const double gyro_scale =
      (options_.gyro_output == GyroOutput::kAngularRate ? 1.0 : sample_rate_hz_) /
      gyro_counts_per_unit(options_.gyro_output);
  const bool acceleration = options_.accel_output == AccelOutput::kAcceleration;
  const double per_unit = acceleration ? kStandardGravity : sample_rate_hz_;
  std::size_t accel_group = layout.acc ? 1 : (layout.incl ? 2 : 3);
  const double accel_scale =
      accel_group == 1
          ? per_unit / accel_counts_per_unit(options_.accel_range_g, options_.accel_output)
      : accel_group == 2 ? per_unit / incl_counts_per_unit(options_.accel_output)
                         : 0.0;
  for (std::size_t a = 0; a < 3; ++a) {
    s.gyro_dps[static_cast<Eigen::Index>(a)] = d.value[0][a] * gyro_scale;
    if (accel_group < 3) {
      s.accel_mps2[static_cast<Eigen::Index>(a)] = d.value[accel_group][a] * accel_scale;
    }
  }
  if (layout.temp) {
    s.temperature_c = (d.temp[0][0] + d.temp[0][1] + d.temp[0][2]) / (3.0 * kTempCountsPerDegC);
  }
  return s;
}

std::size_t Stim300Decoder::feed(std::span<const std::uint8_t> bytes,
                                 std::vector<core::ImuSample>& out) {
  hunt_.append(bytes);
  std::size_t decoded = 0;
  const bool require_crlf = options_.termination.value_or(false);
  while (hunt_.buffered() > 0) {
    const std::span<const std::uint8_t> rest = hunt_.bytes();
    const std::uint8_t* p = rest.data();
    const std::size_t avail = rest.size();
    // CR LF after a datagram when the termination is left open (either way is accepted).
    if (after_datagram_ && !options_.termination.has_value() && p[0] == kCr) {
      if (avail < 2) break;
      if (p[1] == kLf) {
        consume(2);
        ++stats_.terminated_datagrams;
        after_datagram_ = false;
        continue;
      }
    }
    if (hunt_.discard_until([this](std::uint8_t b) { return is_candidate(b); })) {
      after_datagram_ = false;  // as discard() does: a CR LF after garbage ends no datagram
      continue;
    }
    if (is_startup_id(p[0])) {
      const auto scan = scan_reply_at(rest);
      if (scan.result == ScanResult::kNeedMore) break;
      if (scan.result == ScanResult::kNone) {
        discard(1);
        continue;
      }
      std::size_t size = scan.size;
      if (require_crlf) {
        if (avail < size + 2) break;
        if (p[size] == kCr && p[size + 1] == kLf) size += 2;
      }
      on_startup_datagram(rest.first(scan.size));
      consume(size);
      after_datagram_ = !require_crlf;
      continue;
    }
    const auto layout = datagram_layout(p[0]);
    const std::size_t size = layout->size();
    if (avail < size) break;
    if (!crc_matches(rest, size)) {
      if (!hunt_.quiet()) ++stats_.crc_errors;
      discard(1);  // a real datagram may begin inside this bad candidate
      continue;
    }
    std::size_t total = size;
    if (require_crlf) {
      if (avail < size + 2) break;
      if (p[size] != kCr || p[size + 1] != kLf) {
        if (!hunt_.quiet()) ++stats_.length_errors;
        discard(1);
        continue;
      }
      total += 2;
      ++stats_.terminated_datagrams;
    }
    const Datagram d = parse_datagram(rest, *layout);
    locked_id_ = d.id;
    check_status(d, *layout);
    out.push_back(to_sample(d, *layout));
    ++decoded;
    ++stats_.frames;
    hunt_.consume(total);
    stats_.frame_bytes += total;
    after_datagram_ = !require_crlf;
  }
  copy_hunt_counters(hunt_, stats_);
  return decoded;
}

std::map<std::string, std::uint64_t> Stim300Decoder::counters() const {
  auto out = frame_decoder_counters(stats_);
  out.insert(
      {{"startup_datagrams", stats_.startup_datagrams}, {"status_flags", stats_.status_flags}});
  return out;
}

}  // namespace calstand::drivers::stim300
