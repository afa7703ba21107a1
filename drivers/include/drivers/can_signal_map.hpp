#pragma once

#include <linux/can.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/imu_sample.hpp"
#include "drivers/can_field.hpp"

namespace calstand::drivers {

/// The values of an ImuSample a CAN IMU sends, in the ImuSample's units.
enum class ImuSignal {
  kGyroX,        ///< [deg/s]
  kGyroY,        ///< [deg/s]
  kGyroZ,        ///< [deg/s]
  kAccelX,       ///< [m/s^2]
  kAccelY,       ///< [m/s^2]
  kAccelZ,       ///< [m/s^2]
  kTemperature,  ///< [degC]
  kDeviceTime,   ///< [s]; optional in a map
};
inline constexpr std::size_t kImuSignalCount = 8;

/// The map's JSON name ("gyro_x", ..., "device_time") and unit ("deg/s", "m/s^2", "degC", "s").
std::string_view signal_name(ImuSignal signal);
std::string_view signal_unit(ImuSignal signal);

/// One CAN id of the map and the values it carries. Every frame also carries the sample's
/// sequence counter (CanSignalMap::sequence), which is how frames of one sample are matched.
struct CanFrameLayout {
  canid_t id = 0;               ///< 11-bit id, or 29-bit id with CAN_EFF_FLAG set (as in can_frame)
  std::uint8_t min_length = 0;  ///< payload bytes the fields need; shorter frames are refused
  std::vector<std::pair<ImuSignal, CanField>> signals;
  /// Simple multiplexing (DBC `M` / `mN`): this layout is the frames of `id` whose switch
  /// field `mux` reads `mux_value`; several layouts may share an id.
  bool multiplexed = false;
  CanField mux;
  std::uint64_t mux_value = 0;
};

/// A per-message counter of a DBC layout (an "alive counter"): each frame of `id` must carry
/// the previous frame's value + 1 modulo 2^field.length_bits, else CanAssemblyCounters::
/// counter_errors counts it (the frame is still used).
struct CanMessageCounter {
  canid_t id = 0;
  std::string name;  ///< "MESSAGE.SIGNAL"
  CanField field;
};

/// A status signal of a DBC layout (docs/protocols.md, "Signals from a DBC file"): a frame of
/// `id` whose `field` reads a value other than 0 is a device fault, reported as an event with
/// the DBC's VAL_ text for that value (the device's own words).
struct CanStatusSignal {
  canid_t id = 0;
  std::string name;  ///< "MESSAGE.SIGNAL"
  CanField field;
  std::map<std::int64_t, std::string> values;
};

/// Which CAN id carries which value of an IMU sample: configuration, not code, so that a new
/// IMU needs a JSON file rather than a driver. See docs/protocols.md, "IMU over CAN" for the
/// format. A plain value; from_json() guarantees every invariant (no overlaps, fields inside 64
/// bits, every required signal present, at least one frame).
struct CanSignalMap {
  std::vector<CanFrameLayout> frames;  ///< one per id, ascending id
  CanField sequence;                   ///< same place in every frame; unsigned, <= 32 bits
  bool has_device_time = false;
  /// Partial samples kept at once while frames arrive (1: a newer sequence drops the partial
  /// one at once; 2 tolerates a controller sending the next sample's first frame before the
  /// current sample's last, as mailbox priority can do).
  std::size_t reassembly_depth = 1;

  /// How frames of one sample are found (docs/protocols.md):
  ///   kSequenceInEveryFrame  every frame carries `sequence` at the same place (JSON maps);
  ///   kOpeningFrame          frames[opening_frame] opens a sample, which is complete when
  ///                          every other frame of the map has arrived after it (DBC layouts
  ///                          whose counter sits in one message, or that have none).
  enum class Delimiting { kSequenceInEveryFrame, kOpeningFrame };
  Delimiting delimiting = Delimiting::kSequenceInEveryFrame;
  std::size_t opening_frame = 0;
  /// kOpeningFrame: the opening frame carries `sequence`. false: the layout has no counter and
  /// the sequence counts opened samples (32 bits): a whole lost sample is then invisible.
  bool has_sequence = true;
  std::size_t sequence_frame = 0;  ///< kOpeningFrame with has_sequence: the frame carrying it
  /// Channels the device does not measure (station file `null`): delivered as NaN.
  std::array<bool, kImuSignalCount> absent{};
  /// Status signals checked in every frame of their id (not part of a sample).
  std::vector<CanStatusSignal> status;
  /// Per-message counters checked in every frame of their id.
  std::vector<CanMessageCounter> message_counters;

  /// Index into `frames` of the frame with `id` (can_id with CAN_EFF_FLAG, no RTR/ERR flags),
  /// or nullopt when the map does not use it.
  std::optional<std::size_t> frame_index(canid_t id) const;
  /// As above, for a multiplexed id the layout whose switch value the payload carries.
  std::optional<std::size_t> frame_index(canid_t id,
                                         std::span<const std::uint8_t, 8> payload) const;
  /// Every id, with CAN_EFF_FLAG for extended ids (for receive filters).
  std::vector<canid_t> ids() const;
  /// The sequence counter's natural wrap: 2^sequence.length_bits.
  std::uint64_t sequence_wrap() const { return std::uint64_t{1} << sequence.length_bits; }

  /// Parses and validates a map document. Throws core::InputError naming the field under
  /// `where` (e.g. "imus[0].connection.map.signals.gyro_x.length_bits") and why.
  static CanSignalMap from_json(const nlohmann::json& doc, const std::string& where);
  /// Reads a map file (`path` used as given: callers resolve relative paths). Errors name
  /// `where` and the file.
  static CanSignalMap load(const std::string& path, const std::string& where);
  /// The map from a DBC file and the station file's names (docs/protocols.md, "Signals from a
  /// DBC file"): `signals` is the connection's "signals" object, `options` the connection
  /// (sample_start, status, reassembly_depth). Errors name `where` (the connection) and the
  /// field, e.g. "imus[0].connection.signals.gyro_x: no signal \"X\" in message \"Y\" of F".
  static CanSignalMap from_dbc(const std::string& dbc_path, const nlohmann::json& connection,
                               const std::string& where);
};

/// The frames that carry `sample` (one per id of the map, in map order), for simulators and
/// tests. Values are quantised by each field's scale and saturated at its range; the sequence
/// is taken modulo the field's wrap, and so is an unsigned device_time counter (as a device
/// clock counter wraps); receive_time_s is not sent. A map without device_time drops the
/// sample's device time.
std::vector<can_frame> encode_sample(const CanSignalMap& map, const core::ImuSample& sample);

}  // namespace calstand::drivers
