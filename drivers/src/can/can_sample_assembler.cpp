#include "drivers/can_sample_assembler.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>

namespace calstand::drivers {

CanSampleAssembler::CanSampleAssembler(CanSignalMap map, std::uint64_t sequence_modulus,
                                       double sample_rate_hz)
    : map_(std::move(map)),
      modulus_(std::clamp<std::uint64_t>(sequence_modulus, 2, map_.sequence_wrap())),
      sample_rate_hz_(sample_rate_hz > 0.0 ? sample_rate_hz : 1.0),
      complete_mask_(static_cast<std::uint32_t>((std::uint64_t{1} << map_.frames.size()) - 1)),
      status_last_(map_.status.size(), 0),
      counter_last_(map_.message_counters.size()) {}

void CanSampleAssembler::check_counters(canid_t id, const std::array<std::uint8_t, 8>& payload) {
  for (std::size_t i = 0; i < map_.message_counters.size(); ++i) {
    const CanMessageCounter& c = map_.message_counters[i];
    if (c.id != id) continue;
    const std::uint64_t raw = c.field.extract_raw(std::span<const std::uint8_t, 8>(payload));
    const std::uint64_t wrap = std::uint64_t{1} << c.field.length_bits;
    if (counter_last_[i] && raw != (*counter_last_[i] + 1) % wrap) ++stats_.counter_errors;
    counter_last_[i] = raw;
  }
}

std::vector<std::string> CanSampleAssembler::take_device_faults() {
  std::vector<std::string> out;
  out.swap(device_faults_);
  return out;
}

void CanSampleAssembler::check_status(canid_t id, const std::array<std::uint8_t, 8>& payload) {
  for (std::size_t i = 0; i < map_.status.size(); ++i) {
    const CanStatusSignal& s = map_.status[i];
    if (s.id != id) continue;
    const std::uint64_t raw = s.field.extract_raw(std::span<const std::uint8_t, 8>(payload));
    std::int64_t value = static_cast<std::int64_t>(raw);
    if (s.field.type == FieldType::kSigned && s.field.length_bits < 64) {
      const std::uint64_t sign = std::uint64_t{1} << (s.field.length_bits - 1);
      value = static_cast<std::int64_t>((raw ^ sign) - sign);
    }
    // An event when the value changes to a fault (non-zero), not for every repeat of it.
    if (value != 0 && value != status_last_[i]) {
      ++stats_.device_faults;
      const auto it = s.values.find(value);
      device_faults_.push_back(it == s.values.end()
                                   ? fmt::format("{} = {}", s.name, value)
                                   : fmt::format("{} = {}: {}", s.name, value, it->second));
      if (device_faults_.size() > 64) device_faults_.erase(device_faults_.begin());
    }
    status_last_[i] = value;
  }
}

std::size_t CanSampleAssembler::feed_opening(std::size_t index,
                                             const std::array<std::uint8_t, 8>& payload,
                                             std::vector<core::ImuSample>& out) {
  const std::uint32_t bit = std::uint32_t{1} << index;
  if (index == map_.opening_frame) {
    // A new sample; an unfinished one before it lost a frame.
    while (!partials_.empty()) drop_partial(0);
    partials_.push_back({0, 0, {}});
  } else if (partials_.empty()) {
    ++stats_.frames_discarded;  // no sample open: its opening frame was lost
    return 0;
  }
  Partial& p = partials_.front();
  if (p.received & bit) {
    ++stats_.duplicate_frames;  // the first copy stands
    return 0;
  }
  p.received |= bit;
  p.payloads[index] = payload;
  if (p.received != complete_mask_) return 0;
  if (map_.has_sequence) {
    const std::uint64_t raw = map_.sequence.extract_raw(
        std::span<const std::uint8_t, 8>(p.payloads[map_.sequence_frame]));
    if (raw >= modulus_) {
      ++stats_.invalid_samples;  // the device says its counter never gets here
      stats_.frames_discarded += map_.frames.size();
      partials_.clear();
      return 0;
    }
    p.sequence = static_cast<std::uint32_t>(raw);
  } else {
    p.sequence = opened_++;
  }
  const std::size_t before = out.size();
  deliver(0, out);
  return out.size() - before;
}

std::uint64_t CanSampleAssembler::ahead(std::uint32_t from, std::uint32_t to) const {
  return (std::uint64_t{to} + modulus_ - from) % modulus_;
}

std::size_t CanSampleAssembler::pending_frames() const {
  std::size_t n = 0;
  for (const auto& p : partials_) n += static_cast<std::size_t>(std::popcount(p.received));
  return n;
}

void CanSampleAssembler::drop_partial(std::size_t index) {
  ++stats_.incomplete_samples;
  stats_.frames_discarded += static_cast<std::uint64_t>(std::popcount(partials_[index].received));
  partials_.erase(partials_.begin() + static_cast<std::ptrdiff_t>(index));
}

void CanSampleAssembler::reset() {
  while (!partials_.empty()) drop_partial(0);
  have_newest_ = false;
  have_delivered_ = false;
  unwrapped_sequence_ = 0;
  have_time_raw_ = false;
  time_wraps_ = 0;
  opened_ = 0;
  for (auto& c : counter_last_) c.reset();
}

void CanSampleAssembler::deliver(std::size_t index, std::vector<core::ImuSample>& out) {
  // Older partial samples can no longer complete in order: drop them first.
  while (index > 0) {
    drop_partial(0);
    --index;
  }
  const Partial p = partials_.front();
  partials_.erase(partials_.begin());

  core::ImuSample s;
  s.sequence = p.sequence;
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  for (std::size_t i = 0; i < 3; ++i) {
    if (map_.absent[i]) s.gyro_dps[static_cast<Eigen::Index>(i)] = kNaN;
    if (map_.absent[3 + i]) s.accel_mps2[static_cast<Eigen::Index>(i)] = kNaN;
  }
  if (map_.absent[6]) s.temperature_c = kNaN;
  bool valid = true;
  std::optional<std::uint64_t> time_raw;
  for (std::size_t f = 0; f < map_.frames.size(); ++f) {
    const std::span<const std::uint8_t, 8> payload(p.payloads[f]);
    for (const auto& [which, field] : map_.frames[f].signals) {
      const double v = field.decode(payload);
      valid = valid && std::isfinite(v);
      switch (which) {
        case ImuSignal::kGyroX:
          s.gyro_dps.x() = v;
          break;
        case ImuSignal::kGyroY:
          s.gyro_dps.y() = v;
          break;
        case ImuSignal::kGyroZ:
          s.gyro_dps.z() = v;
          break;
        case ImuSignal::kAccelX:
          s.accel_mps2.x() = v;
          break;
        case ImuSignal::kAccelY:
          s.accel_mps2.y() = v;
          break;
        case ImuSignal::kAccelZ:
          s.accel_mps2.z() = v;
          break;
        case ImuSignal::kTemperature:
          s.temperature_c = v;
          break;
        case ImuSignal::kDeviceTime:
          s.device_time_s = v;
          if (field.type == FieldType::kUnsigned && field.length_bits < 64) {
            // Unwrap the counter: a step back by more than half its range is a wrap.
            const std::uint64_t raw = field.extract_raw(payload);
            const std::uint64_t half = std::uint64_t{1} << (field.length_bits - 1);
            if (have_time_raw_ && raw < last_time_raw_ && last_time_raw_ - raw > half)
              ++time_wraps_;
            time_raw = raw;
            const double wrap = std::ldexp(1.0, static_cast<int>(field.length_bits));
            s.device_time_s =
                (static_cast<double>(raw) + static_cast<double>(time_wraps_) * wrap) * field.scale +
                field.offset;
          }
          break;
      }
    }
  }
  const std::uint64_t frames_in_sample = map_.frames.size();
  if (!valid) {
    // A NaN or infinity would poison a calibration fit; dropping the sample is what a gap is.
    ++stats_.invalid_samples;
    stats_.frames_discarded += frames_in_sample;
    return;
  }
  if (time_raw) {
    have_time_raw_ = true;
    last_time_raw_ = *time_raw;
  }
  if (have_delivered_) {
    const std::uint64_t step = ahead(last_delivered_, s.sequence);
    if (step != 1) ++stats_.sequence_gaps;
    unwrapped_sequence_ += step;
  }
  have_delivered_ = true;
  last_delivered_ = s.sequence;
  if (!map_.has_device_time)
    s.device_time_s = static_cast<double>(unwrapped_sequence_) / sample_rate_hz_;
  ++stats_.samples;
  stats_.frames_used += frames_in_sample;
  out.push_back(s);
}

std::size_t CanSampleAssembler::feed(const can_frame& frame, std::vector<core::ImuSample>& out) {
  ++stats_.frames;
  const bool extended = (frame.can_id & CAN_EFF_FLAG) != 0;
  const canid_t id_bits = frame.can_id & CAN_EFF_MASK;
  if ((frame.can_id & (CAN_RTR_FLAG | CAN_ERR_FLAG)) != 0 || frame.len > CAN_MAX_DLEN ||
      (!extended && id_bits > CAN_SFF_MASK)) {
    ++stats_.bad_frames;
    return 0;
  }
  const canid_t id = id_bits | (extended ? CAN_EFF_FLAG : 0u);
  std::array<std::uint8_t, 8> payload{};  // bytes beyond len read as 0
  std::copy_n(frame.data, frame.len, payload.begin());
  if (!map_.status.empty()) check_status(id, payload);
  if (!map_.message_counters.empty()) check_counters(id, payload);
  const auto index = map_.frame_index(id, std::span<const std::uint8_t, 8>(payload));
  if (!index) {
    const bool status_only = std::any_of(map_.status.begin(), map_.status.end(),
                                         [&](const CanStatusSignal& s) { return s.id == id; }) ||
                             std::any_of(map_.message_counters.begin(), map_.message_counters.end(),
                                         [&](const CanMessageCounter& c) { return c.id == id; });
    ++(status_only ? stats_.status_frames : stats_.unknown_ids);
    return 0;
  }
  if (frame.len < map_.frames[*index].min_length) {
    ++stats_.bad_dlc;
    return 0;
  }
  if (map_.delimiting == CanSignalMap::Delimiting::kOpeningFrame)
    return feed_opening(*index, payload, out);
  const std::uint64_t raw_sequence =
      map_.sequence.extract_raw(std::span<const std::uint8_t, 8>(payload));
  if (raw_sequence >= modulus_) {
    ++stats_.bad_frames;  // the device says its counter never gets here
    return 0;
  }
  const auto sequence = static_cast<std::uint32_t>(raw_sequence);
  const std::uint32_t bit = std::uint32_t{1} << *index;

  auto slot = std::find_if(partials_.begin(), partials_.end(),
                           [&](const Partial& p) { return p.sequence == sequence; });
  if (slot == partials_.end()) {
    // Newer than anything seen, or far enough behind to be a restarted counter: a new sample.
    // Otherwise it belongs to a sample already delivered or dropped.
    const std::uint64_t late_window = map_.reassembly_depth + 2;
    const std::uint64_t back = have_newest_ ? ahead(sequence, newest_) : 0;
    const bool behind = have_newest_ && back <= late_window && back < (modulus_ + 1) / 2;
    if (behind) {
      ++stats_.late_frames;
      return 0;
    }
    if (have_newest_ && back != 0 && back < (modulus_ + 1) / 2) {
      // A restart: older partial samples belong to the previous run.
      while (!partials_.empty()) drop_partial(0);
    }
    have_newest_ = true;
    newest_ = sequence;
    partials_.push_back({sequence, 0, {}});
    while (partials_.size() > map_.reassembly_depth) drop_partial(0);
    slot = partials_.end() - 1;
  }
  if (slot->received & bit) {
    ++stats_.duplicate_frames;  // the first copy stands
    return 0;
  }
  slot->received |= bit;
  slot->payloads[*index] = payload;
  if (slot->received != complete_mask_) return 0;
  const std::size_t before = out.size();
  deliver(static_cast<std::size_t>(slot - partials_.begin()), out);
  return out.size() - before;
}

std::map<std::string, std::uint64_t> CanSampleAssembler::counters() const {
  return {{"frames", stats_.frames},
          {"unknown_ids", stats_.unknown_ids},
          {"bad_frames", stats_.bad_frames},
          {"bad_dlc", stats_.bad_dlc},
          {"duplicate_frames", stats_.duplicate_frames},
          {"late_frames", stats_.late_frames},
          {"frames_used", stats_.frames_used},
          {"frames_discarded", stats_.frames_discarded},
          {"samples", stats_.samples},
          {"incomplete_samples", stats_.incomplete_samples},
          {"invalid_samples", stats_.invalid_samples},
          {"sequence_gaps", stats_.sequence_gaps},
          {"status_frames", stats_.status_frames},
          {"device_faults", stats_.device_faults},
          {"counter_errors", stats_.counter_errors}};
}

}  // namespace calstand::drivers
