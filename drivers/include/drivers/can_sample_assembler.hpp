#pragma once

#include <linux/can.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/imu_sample.hpp"
#include "drivers/can_signal_map.hpp"

namespace calstand::drivers {

/// Counters of a CanSampleAssembler since construction. Every frame fed ends up in exactly one
/// of the frame counters or is still pending:
///   frames == unknown_ids + bad_frames + bad_dlc + duplicate_frames + late_frames
///             + frames_used + frames_discarded + status_frames + pending_frames()
struct CanAssemblyCounters {
  std::uint64_t frames = 0;       ///< frames fed
  std::uint64_t unknown_ids = 0;  ///< ids the map does not use (ignored)
  std::uint64_t bad_frames = 0;   ///< remote/error frames, length > 8, id or sequence out of range
  std::uint64_t bad_dlc = 0;      ///< a known id with fewer bytes than its fields need
  std::uint64_t duplicate_frames = 0;    ///< an id again for a sample still being assembled
  std::uint64_t late_frames = 0;         ///< for a sample already delivered or dropped
  std::uint64_t frames_used = 0;         ///< frames in delivered samples
  std::uint64_t frames_discarded = 0;    ///< frames of incomplete or invalid samples
  std::uint64_t samples = 0;             ///< samples delivered
  std::uint64_t incomplete_samples = 0;  ///< partial samples dropped (a newer sequence came first)
  std::uint64_t invalid_samples = 0;     ///< complete but a value was NaN or infinite (dropped)
  std::uint64_t sequence_gaps = 0;       ///< delivered samples whose sequence was not last + 1
  std::uint64_t status_frames = 0;       ///< frames of ids used only for status or counter checks
  std::uint64_t counter_errors = 0;      ///< per-message counters that did not step by +1
  std::uint64_t device_faults = 0;       ///< status signals that turned non-zero
};

/// Turns CAN frames into IMU samples by the signal map. Frames of one sample are matched by
/// the sequence counter every frame carries; a sample is delivered when every id of the map
/// has arrived with the same sequence, in any order. At most map.reassembly_depth samples are
/// assembled at once: a newer sequence beyond that drops the oldest partial one
/// (incomplete_samples), and delivering a sample drops every older partial one, so samples
/// come out in sequence order and no value is ever invented. Never throws on bad input.
///
/// A frame up to reassembly_depth + 2 sequences behind the newest one is late; one further
/// behind means the device's counter restarted (or a long outage), and starts a new sample.
///
/// Device time: an unsigned device_time field is a counter that wraps at 2^length_bits; it is
/// unwrapped so that device time keeps increasing. A map without device_time gets device time
/// from the unwrapped sequence counter / sample_rate_hz (the device's nominal clock).
/// Not thread safe: one per stream.
class CanSampleAssembler {
 public:
  /// `sequence_modulus`: the device's counter wraps to 0 there (2 .. map.sequence_wrap()).
  CanSampleAssembler(CanSignalMap map, std::uint64_t sequence_modulus, double sample_rate_hz);

  /// Consumes one frame; appends the sample it completes (if any) to `out`. receive_time_s is
  /// left 0 for the caller to stamp. Returns the number of samples appended (0 or 1).
  std::size_t feed(const can_frame& frame, std::vector<core::ImuSample>& out);

  const CanAssemblyCounters& stats() const { return stats_; }
  /// The counters by name, for Device::fault_counters().
  std::map<std::string, std::uint64_t> counters() const;
  /// Frames held in partial samples.
  std::size_t pending_frames() const;
  /// Device faults reported by status signals since the last call, in the device's words
  /// ("XCID_Error.ErrorCode = 1: The output buffer is full, ..."); cleared by the call.
  std::vector<std::string> take_device_faults();
  /// Drops partial samples (counted incomplete) and forgets sequence and device-time history,
  /// as after a reconnect. Counters are kept.
  void reset();

 private:
  struct Partial {
    std::uint32_t sequence = 0;
    std::uint32_t received = 0;  // bit i: frame i of the map has arrived
    std::array<std::array<std::uint8_t, 8>, 31> payloads{};  // up to 31 frames per sample
  };

  std::uint64_t ahead(std::uint32_t from, std::uint32_t to) const;  // (to - from) mod modulus
  std::size_t feed_opening(std::size_t index, const std::array<std::uint8_t, 8>& payload,
                           std::vector<core::ImuSample>& out);
  void check_status(canid_t id, const std::array<std::uint8_t, 8>& payload);
  void check_counters(canid_t id, const std::array<std::uint8_t, 8>& payload);
  void drop_partial(std::size_t index);
  void deliver(std::size_t index, std::vector<core::ImuSample>& out);

  CanSignalMap map_;
  std::uint64_t modulus_;
  double sample_rate_hz_;
  std::uint32_t complete_mask_;
  std::vector<Partial> partials_;  // oldest first
  bool have_newest_ = false;
  std::uint32_t newest_ = 0;  // newest sequence that opened a partial
  bool have_delivered_ = false;
  std::uint32_t last_delivered_ = 0;
  std::uint64_t unwrapped_sequence_ = 0;
  bool have_time_raw_ = false;
  std::uint64_t last_time_raw_ = 0;
  std::uint64_t time_wraps_ = 0;
  CanAssemblyCounters stats_;
  std::uint32_t opened_ = 0;               // kOpeningFrame without a counter: samples opened
  std::vector<std::int64_t> status_last_;  // per status signal: last raw value
  std::vector<std::string> device_faults_;
  std::vector<std::optional<std::uint64_t>> counter_last_;  // per message counter
};

}  // namespace calstand::drivers
