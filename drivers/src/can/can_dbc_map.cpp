// CanSignalMap::from_dbc: a DBC file plus the station file's signal names become a CanSignalMap
// (docs/protocols.md, "Signals from a DBC file").
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>

#include "core/error.hpp"
#include "core/json_schema.hpp"
#include "core/schemas.hpp"
#include "drivers/can_signal_map.hpp"
#include "drivers/dbc_file.hpp"

namespace calstand::drivers {
namespace {

using nlohmann::json;

constexpr std::array<std::string_view, kImuSignalCount> kDbcNames = {
    "gyro_x", "gyro_y", "gyro_z", "accel_x", "accel_y", "accel_z", "temperature", "device_time"};

/// scale and offset that take a DBC unit to the ImuSample unit: sample = dbc * scale + offset.
struct DbcUnit {
  double scale = 1.0;
  double offset = 0.0;
};

std::optional<DbcUnit> dbc_unit(ImuSignal which, const std::string& unit) {
  const std::string deg = "\xC2\xB0";    // UTF-8 degree sign
  const std::string deg1 = "\xB0";       // Latin-1 degree sign
  const std::string micro = "\xC2\xB5";  // UTF-8 micro sign
  auto is = [&](std::initializer_list<std::string> names) {
    return std::find(names.begin(), names.end(), unit) != names.end();
  };
  switch (which) {
    case ImuSignal::kGyroX:
    case ImuSignal::kGyroY:
    case ImuSignal::kGyroZ:
      if (is({"deg/s", "dps", deg + "/s", deg1 + "/s"})) return DbcUnit{1.0, 0.0};
      if (is({"rad/s"})) return DbcUnit{180.0 / std::numbers::pi, 0.0};
      if (is({"mrad/s"})) return DbcUnit{0.18 / std::numbers::pi, 0.0};
      if (is({"deg/h", deg + "/h", deg1 + "/h"})) return DbcUnit{1.0 / 3600.0, 0.0};
      return std::nullopt;
    case ImuSignal::kAccelX:
    case ImuSignal::kAccelY:
    case ImuSignal::kAccelZ:
      if (is({"m/s^2", "m/s2", "m/s/s", "m/s\xC2\xB2", "m/s\xB2"})) return DbcUnit{1.0, 0.0};
      if (is({"g"})) return DbcUnit{9.80665, 0.0};
      if (is({"mg"})) return DbcUnit{9.80665e-3, 0.0};
      return std::nullopt;
    case ImuSignal::kTemperature:
      if (is({"degC", "C", deg + "C", deg1 + "C", "deg C"})) return DbcUnit{1.0, 0.0};
      if (is({"K"})) return DbcUnit{1.0, -273.15};
      return std::nullopt;
    case ImuSignal::kDeviceTime:
      if (is({"s"})) return DbcUnit{1.0, 0.0};
      if (is({"ms"})) return DbcUnit{1e-3, 0.0};
      if (is({"us", micro + "s"})) return DbcUnit{1e-6, 0.0};
      return std::nullopt;
  }
  return std::nullopt;
}

std::string_view dbc_unit_examples(ImuSignal which) {
  switch (which) {
    case ImuSignal::kGyroX:
    case ImuSignal::kGyroY:
    case ImuSignal::kGyroZ:
      return "deg/s, rad/s, mrad/s, deg/h";
    case ImuSignal::kAccelX:
    case ImuSignal::kAccelY:
    case ImuSignal::kAccelZ:
      return "m/s^2, m/s2, g, mg";
    case ImuSignal::kTemperature:
      return "degC, C, K";
    case ImuSignal::kDeviceTime:
      return "s, ms, us";
  }
  return "";
}

struct DbcNamed {
  const DbcMessage* message = nullptr;
  const DbcSignal* signal = nullptr;
};

/// "MESSAGE.SIGNAL" looked up in the DBC; errors name `here` and the file.
DbcNamed dbc_lookup(const DbcFile& dbc, const std::string& text, const std::string& here) {
  const auto dot = text.find('.');
  if (dot == std::string::npos || dot == 0 || dot + 1 == text.size()) {
    throw core::InputError(here, fmt::format("\"{}\" is not MESSAGE.SIGNAL (e.g. "
                                             "\"XCID_RateOfTurn.gyrX\")",
                                             text));
  }
  const std::string msg = text.substr(0, dot);
  const std::string sig = text.substr(dot + 1);
  const DbcMessage* m = dbc.message(msg);
  if (!m) throw core::InputError(here, fmt::format("no message \"{}\" in {}", msg, dbc.file));
  const DbcSignal* s = m->signal(sig);
  if (!s) {
    throw core::InputError(
        here, fmt::format("no signal \"{}\" in message \"{}\" of {}", sig, msg, dbc.file));
  }
  return {m, s};
}

/// The layout key of a signal: its message, and its multiplexer value in a multiplexed one.
struct DbcLayoutKey {
  canid_t id = 0;
  bool multiplexed = false;
  std::uint64_t mux_value = 0;
  bool operator==(const DbcLayoutKey&) const = default;
};

DbcLayoutKey dbc_key(const DbcNamed& n, const std::string& here) {
  const DbcSignal* sw = n.message->multiplexer();
  if (!sw) return {n.message->id, false, 0};
  if (n.signal->mux == DbcSignal::Mux::kSwitch) {
    throw core::InputError(here, fmt::format("{}.{} is the multiplexer switch itself, not a value",
                                             n.message->name, n.signal->name));
  }
  if (n.signal->mux != DbcSignal::Mux::kMultiplexed) {
    throw core::InputError(
        here, fmt::format("{}.{} is not multiplexed but its message is: name signals of the "
                          "multiplexed groups (mN) of {}",
                          n.message->name, n.signal->name, n.message->name));
  }
  return {n.message->id, true, n.signal->mux_value};
}

std::size_t dbc_layout(CanSignalMap& map, const DbcNamed& n, const DbcLayoutKey& key) {
  for (std::size_t i = 0; i < map.frames.size(); ++i) {
    const auto& f = map.frames[i];
    if (f.id == key.id && f.multiplexed == key.multiplexed && f.mux_value == key.mux_value)
      return i;
  }
  CanFrameLayout layout;
  layout.id = key.id;
  layout.multiplexed = key.multiplexed;
  layout.mux_value = key.mux_value;
  if (key.multiplexed) {
    layout.mux = n.message->multiplexer()->field();
    layout.mux.scale = 1.0;
    layout.mux.offset = 0.0;
    layout.min_length = static_cast<std::uint8_t>(layout.mux.bytes_needed());
  }
  map.frames.push_back(layout);
  return map.frames.size() - 1;
}

}  // namespace

CanSignalMap CanSignalMap::from_dbc(const std::string& dbc_path, const json& connection,
                                    const std::string& where) {
  const DbcFile dbc = [&] {
    try {
      return DbcFile::load(dbc_path);
    } catch (const core::InputError& e) {
      throw core::InputError(where + ".dbc", e.what());
    }
  }();
  CanSignalMap map;
  map.delimiting = Delimiting::kOpeningFrame;
  const std::string sigs_where = where + ".signals";
  const json& sigs = connection.at("signals");
  std::vector<std::pair<std::size_t, std::uint64_t>> used;  // layout, occupied bits

  auto place = [&](std::size_t layout, const CanField& field, const std::string& here) {
    const std::uint64_t mask = field.occupied_mask();
    std::uint64_t taken =
        map.frames[layout].multiplexed ? map.frames[layout].mux.occupied_mask() : 0;
    for (const auto& [l, m] : used)
      if (l == layout) taken |= m;
    if (mask & taken) {
      throw core::InputError(here, "uses payload bits another named signal of its frame uses");
    }
    used.emplace_back(layout, mask);
    auto& f = map.frames[layout];
    f.min_length = std::max(f.min_length, static_cast<std::uint8_t>(field.bytes_needed()));
  };

  // The counter first: its message opens a sample unless sample_start says otherwise.
  std::optional<std::size_t> counter_layout;
  if (sigs.contains("counter")) {
    const std::string here = sigs_where + ".counter";
    const DbcNamed n = dbc_lookup(dbc, sigs.at("counter").get<std::string>(), here);
    const CanField f = n.signal->field();
    if (f.type != FieldType::kUnsigned || n.signal->factor != 1.0 || n.signal->offset != 0.0 ||
        f.length_bits > 32) {
      throw core::InputError(here, fmt::format("{}.{} is not a counter: an unsigned integer of "
                                               "at most 32 bits with factor 1 and offset 0",
                                               n.message->name, n.signal->name));
    }
    counter_layout = dbc_layout(map, n, dbc_key(n, here));
    map.sequence = f;
    map.has_sequence = true;
    map.sequence_frame = *counter_layout;
    place(*counter_layout, f, here);
  } else {
    map.has_sequence = false;
    map.sequence = CanField{};
    map.sequence.length_bits = 32;
  }

  for (std::size_t i = 0; i < kImuSignalCount; ++i) {
    const auto which = static_cast<ImuSignal>(i);
    const std::string name(kDbcNames[i]);
    const std::string here = sigs_where + "." + name;
    if (!sigs.contains(name)) continue;  // device_time (optional); the schema requires the rest
    const json& v = sigs.at(name);
    if (v.is_null()) {
      if (which == ImuSignal::kDeviceTime) continue;
      map.absent[i] = true;  // the device does not measure it: NaN
      continue;
    }
    const DbcNamed n = dbc_lookup(dbc, v.get<std::string>(), here);
    const auto unit = dbc_unit(which, n.signal->unit);
    if (!unit) {
      throw core::InputError(
          here,
          fmt::format("unit \"{}\" of {}.{} is not a unit of {} known here ({})", n.signal->unit,
                      n.message->name, n.signal->name, name, dbc_unit_examples(which)));
    }
    CanField f = n.signal->field();
    f.scale *= unit->scale;
    f.offset = f.offset * unit->scale + unit->offset;
    const std::size_t layout = dbc_layout(map, n, dbc_key(n, here));
    place(layout, f, here);
    map.frames[layout].signals.emplace_back(which, f);
    if (which == ImuSignal::kDeviceTime) map.has_device_time = true;
  }
  if (std::all_of(map.absent.begin(), map.absent.begin() + 7, [](bool a) { return a; }))
    throw core::InputError(sigs_where, "every channel is null: name at least one signal");

  // Which frame opens a sample.
  if (connection.contains("sample_start")) {
    const std::string here = where + ".sample_start";
    const std::string msg = connection.at("sample_start").get<std::string>();
    const DbcMessage* m = dbc.message(msg);
    if (!m) throw core::InputError(here, fmt::format("no message \"{}\" in {}", msg, dbc.file));
    std::optional<std::size_t> found;
    for (std::size_t i = 0; i < map.frames.size(); ++i) {
      if (map.frames[i].id != m->id) continue;
      if (found) {
        throw core::InputError(here, fmt::format("{} is multiplexed into several frames of a "
                                                 "sample: name a message with one",
                                                 msg));
      }
      found = i;
    }
    if (!found) {
      throw core::InputError(here, fmt::format("message \"{}\" carries none of the named "
                                               "signals: a sample starts with one of its frames",
                                               msg));
    }
    map.opening_frame = *found;
  } else if (counter_layout) {
    map.opening_frame = *counter_layout;
  } else {
    throw core::InputError(where + ".sample_start",
                           "is required without signals.counter: the message that starts each "
                           "sample (the device sends it first)");
  }
  if (map.frames.size() > 31) {
    throw core::InputError(sigs_where, "more than 31 frames per sample");
  }

  // Per-message counters: +1 from frame to frame of their message.
  if (connection.contains("message_counters")) {
    const json& list = connection.at("message_counters");
    for (std::size_t i = 0; i < list.size(); ++i) {
      const std::string here = fmt::format("{}.message_counters[{}]", where, i);
      const std::string text = list.at(i).get<std::string>();
      const DbcNamed n = dbc_lookup(dbc, text, here);
      const CanField f = n.signal->field();
      if (n.signal->mux != DbcSignal::Mux::kPlain || f.type != FieldType::kUnsigned ||
          n.signal->factor != 1.0 || n.signal->offset != 0.0 || f.length_bits > 32) {
        throw core::InputError(here, fmt::format("{} is not a counter: a plain unsigned integer "
                                                 "of at most 32 bits with factor 1 and offset 0",
                                                 text));
      }
      map.message_counters.push_back({n.message->id, text, f});
    }
  }

  // Status signals: any value but 0 is an event in the device's words.
  if (connection.contains("status")) {
    const json& list = connection.at("status");
    for (std::size_t i = 0; i < list.size(); ++i) {
      const std::string here = fmt::format("{}.status[{}]", where, i);
      const std::string text = list.at(i).get<std::string>();
      const DbcNamed n = dbc_lookup(dbc, text, here);
      if (n.signal->mux != DbcSignal::Mux::kPlain || n.signal->field().type == FieldType::kFloat) {
        throw core::InputError(here, fmt::format("{} is not a plain integer signal", text));
      }
      CanField f = n.signal->field();
      f.scale = 1.0;  // raw values: VAL_ tables are keyed by raw value
      f.offset = 0.0;
      map.status.push_back({n.message->id, text, f, n.signal->values});
    }
  }
  return map;
}

}  // namespace calstand::drivers
