// Decoder of the Epson burst frames (docs/protocols.md, "Epson M-G3xx/G5xx", framing).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <utility>

#include "drivers/epson_wire.hpp"

namespace calstand::drivers::epson {

Decoder::Decoder(Options options)
    : options_(std::move(options)), frame_size_(burst_size(options_.width_bits)) {
  const double rate_hz = options_.rate != nullptr ? options_.rate->rate_hz : kBaseRateHz;
  if (options_.count_step == CountStep::kBase) {
    count_rate_hz_ = kBaseRateHz;
    count_step_ = static_cast<std::uint64_t>(std::llround(kBaseRateHz / rate_hz));
  } else {
    count_rate_hz_ = rate_hz;
    count_step_ = 1;
  }
  for (const char* name : {"bytes_fed", "frames", "crc_errors", "length_errors", "garbage_bytes",
                           "resyncs", "sequence_gaps", "start_bytes", "error_flag_frames",
                           "device_restarts", "frames_without_model"}) {
    stats_[name] = 0;
  }
}

void Decoder::restart() {
  hunt_.restart();
  copy_hunt_counters(hunt_, stats_);
  // The counter keeps its epoch (device time stays continuous over a reconnect); only the
  // gap check skips the first frame.
  check_gap_ = false;
}

std::vector<std::string> Decoder::take_device_reports() { return std::exchange(reports_, {}); }

void Decoder::identified(const UnitIdentity& unit) {
  identified_model_.store(find_model(unit.model));
}

std::map<std::string, std::uint64_t> Decoder::counters() const { return stats_; }

const ModelScale* Decoder::model() {
  if (!options_.model.empty()) return find_model(options_.model);
  return identified_model_.load();
}

void Decoder::note_count_step(std::uint64_t delta) {
  // The data sheets leave open whether COUNT counts output or base-rate samples (count_step);
  // a device whose every step is the other reading says so once, in numbers.
  const std::uint64_t other =
      options_.count_step == CountStep::kBase
          ? 1
          : static_cast<std::uint64_t>(std::llround(kBaseRateHz / (count_rate_hz_)));
  if (other == count_step_ || reported_count_step_) return;
  steps_like_other_ = delta == other ? steps_like_other_ + 1 : 0;
  if (steps_like_other_ >= kStepsBeforeReport) {
    reports_.push_back(fmt::format(
        "COUNT steps by {} per frame, not {}: check the count_step option", other, count_step_));
    reported_count_step_ = true;
  }
}

void Decoder::decode(const BurstFields& f, std::vector<core::ImuSample>& out) {
  // EA is the OR of DIAG_STAT's error bits (M-G365PD FLAG / DIAG_STAT): the burst cannot say
  // which, so the report names the flag and where the detail is.
  if ((f.flags & kFlagEa) != 0) {
    ++stats_["error_flag_frames"];
    if (!error_flag_) {
      reports_.push_back("EA (all error) flag set in the burst FLAG: DIAG_STAT reports an error");
    }
    error_flag_ = true;
  } else if (error_flag_) {
    reports_.push_back("EA (all error) flag cleared");
    error_flag_ = false;
  }

  if (!have_count_) {
    unwrapped_count_ = f.count;
    have_count_ = true;
  } else {
    const auto delta = static_cast<std::uint16_t>(f.count - last_count_);
    if (delta == 0 || delta >= 0x8000u) {
      // COUNT does not go back by itself short of a wrap: the device restarted (power, reset).
      reports_.push_back(
          fmt::format("COUNT went back from {} to {}: device restarted", last_count_, f.count));
      ++stats_["device_restarts"];
      unwrapped_count_ = f.count;
    } else {
      unwrapped_count_ += delta;
      if (check_gap_ && delta != count_step_) ++stats_["sequence_gaps"];
      note_count_step(delta);
    }
  }
  last_count_ = f.count;
  check_gap_ = true;

  const ModelScale* m = model();
  if (m == nullptr) {
    ++stats_["frames_without_model"];
    if (!reported_no_model_) {
      reports_.push_back(
          "model unknown (no \"model\" option and no PROD_ID read yet): frames not scaled");
      reported_no_model_ = true;
    }
    return;
  }
  const int w = options_.width_bits;
  core::ImuSample s;
  s.sequence = static_cast<std::uint32_t>(unwrapped_count_ / count_step_);
  s.device_time_s = static_cast<double>(unwrapped_count_) / count_rate_hz_;
  for (int i = 0; i < 3; ++i) {
    s.gyro_dps[i] = gyro_dps(*m, f.gyro[i], w);
    s.accel_mps2[i] = accel_mps2(*m, f.accel[i], w);
  }
  s.temperature_c = temperature_c(*m, f.temperature, w);
  out.push_back(s);
}

std::size_t Decoder::feed(std::span<const std::uint8_t> bytes, std::vector<core::ImuSample>& out) {
  hunt_.append(bytes);

  const std::size_t before = out.size();
  while (hunt_.buffered() > 0) {
    const std::uint8_t* p = hunt_.bytes().data();
    const std::size_t avail = hunt_.buffered();
    if (hunt_.discard_until([](std::uint8_t b) { return b == kBurstHeader; })) continue;
    if (avail < frame_size_) break;
    if (p[frame_size_ - 1] != kDelimiter) {
      // No end byte where this width puts it: not a frame of the configured length.
      if (!hunt_.quiet()) ++stats_["length_errors"];
      hunt_.discard(1);
      continue;
    }
    const auto fields = parse_burst({p, frame_size_}, options_.width_bits);
    if (!fields) {
      // A real frame may start inside this bad candidate: drop only its header byte.
      if (!hunt_.quiet()) ++stats_["crc_errors"];
      hunt_.discard(1);
      continue;
    }
    ++stats_["frames"];
    hunt_.consume(frame_size_);
    decode(*fields, out);
  }
  copy_hunt_counters(hunt_, stats_);
  return out.size() - before;
}

}  // namespace calstand::drivers::epson
