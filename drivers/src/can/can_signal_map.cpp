#include "drivers/can_signal_map.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>

#include "core/error.hpp"
#include "core/json_schema.hpp"
#include "core/schemas.hpp"

namespace calstand::drivers {
namespace {

using nlohmann::json;

constexpr std::array<std::string_view, kImuSignalCount> kNames = {
    "gyro_x", "gyro_y", "gyro_z", "accel_x", "accel_y", "accel_z", "temperature", "device_time"};
constexpr std::array<std::string_view, kImuSignalCount> kUnits = {
    "deg/s", "deg/s", "deg/s", "m/s^2", "m/s^2", "m/s^2", "degC", "s"};

/// Field paths: "a.b" normally; a prefix ending in ':' (a file name) reads "file: b".
std::string join(const std::string& where, std::string_view key) {
  if (where.empty()) return std::string(key);
  if (where.back() == ':') return where + " " + std::string(key);
  return where + "." + std::string(key);
}

std::string hex_id(canid_t id) {
  return (id & CAN_EFF_FLAG) ? fmt::format("0x{:08X} (extended)", id & CAN_EFF_MASK)
                             : fmt::format("0x{:03X}", id);
}

ByteOrder byte_order_from_name(const std::string& name) {
  return name == "big" ? ByteOrder::kBig : ByteOrder::kLittle;
}

FieldType type_from_name(const std::string& name) {
  if (name == "signed") return FieldType::kSigned;
  if (name == "float") return FieldType::kFloat;
  return FieldType::kUnsigned;
}

/// An id as a number or a string ("0x101" or "257", as the schema allows); flags from
/// `extended`. The range is checked here: it depends on `extended`, and a schema cannot compare
/// a number written as a string.
canid_t parse_id(const json& sig, const std::string& where) {
  const std::string here = join(where, "id");
  const json& v = sig.at("id");
  std::uint64_t id = 0;
  if (v.is_string()) {
    const std::string text = v.get<std::string>();
    std::size_t used = 0;
    try {
      id = std::stoull(text, &used, 0);  // base 0: "0x" prefix means hex
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != text.size()) {
      throw core::InputError(here, "\"" + text + "\" is not a CAN id (e.g. \"0x101\" or 257)");
    }
  } else {
    id = v.get<std::uint64_t>();
  }
  const bool extended = sig.value("extended", false);
  const std::uint64_t max = extended ? CAN_EFF_MASK : CAN_SFF_MASK;
  if (id > max) {
    throw core::InputError(here, fmt::format("0x{:X} is beyond the {} ids (max 0x{:X}){}", id,
                                             extended ? "29-bit" : "11-bit", max,
                                             extended ? "" : "; set \"extended\": true"));
  }
  return static_cast<canid_t>(id) | (extended ? CAN_EFF_FLAG : 0u);
}

/// The layout keys shared by values and the sequence counter, checked by the schema one by one;
/// what involves two keys is checked here.
CanField parse_layout(const json& sig, const std::string& where, ByteOrder default_order) {
  CanField f;
  const bool by_byte = sig.contains("start_byte");
  const bool by_bit = sig.contains("start_bit");
  // A schema can require exactly one of two keys only as "matches none of the forms"; this
  // names them.
  if (by_byte == by_bit) {
    throw core::InputError(join(where, "start_byte"),
                           by_byte ? "give start_byte or start_bit, not both"
                                   : "missing (give start_byte or start_bit)");
  }
  f.start_bit = by_byte ? 8 * sig.at("start_byte").get<std::uint32_t>()
                        : sig.at("start_bit").get<std::uint32_t>();
  f.length_bits = sig.at("length_bits").get<std::uint32_t>();
  if (f.start_bit + f.length_bits > 64) {
    throw core::InputError(
        join(where, "length_bits"),
        fmt::format("start bit {} + {} bits reaches beyond the 64 bits (8 bytes) "
                    "of a CAN frame",
                    f.start_bit, f.length_bits));
  }
  f.byte_order = sig.contains("byte_order")
                     ? byte_order_from_name(sig.at("byte_order").get<std::string>())
                     : default_order;
  return f;
}

CanField parse_value(const json& sig, const std::string& where, ByteOrder default_order) {
  CanField f = parse_layout(sig, where, default_order);
  f.type = type_from_name(sig.at("type").get<std::string>());
  f.scale = sig.value("scale", 1.0);
  f.offset = sig.value("offset", 0.0);
  return f;
}

CanSignalMap map_from_json(const json& doc, const std::string& where) {
  CanSignalMap map;
  const ByteOrder default_order = byte_order_from_name(doc.value("byte_order", "little"));
  map.reassembly_depth = doc.value("reassembly_depth", map.reassembly_depth);
  const std::string sigs_where = join(where, "signals");
  const json& sigs = doc.at("signals");
  map.sequence = parse_layout(sigs.at("sequence"), join(sigs_where, "sequence"), default_order);

  // Each value's frame; the sequence occupies the same bits of every frame.
  std::map<canid_t, std::vector<std::pair<std::string, std::uint64_t>>> occupied;
  for (std::size_t i = 0; i < kImuSignalCount; ++i) {
    const auto which = static_cast<ImuSignal>(i);
    const std::string name(kNames[i]);
    const std::string here = join(sigs_where, name);
    if (!sigs.contains(name)) continue;  // device_time: optional (time from the sequence)
    const json& sig = sigs.at(name);
    const canid_t id = parse_id(sig, here);
    const CanField field = parse_value(sig, here, default_order);
    auto& used = occupied[id];
    if (used.empty()) used.emplace_back("sequence", map.sequence.occupied_mask());
    const std::uint64_t mask = field.occupied_mask();
    for (const auto& [other, other_mask] : used) {
      if (mask & other_mask) {
        throw core::InputError(here,
                               fmt::format("overlaps {} in frame {} (payload bits {}..{} "
                                           "are used twice)",
                                           other, hex_id(id), std::countr_zero(mask & other_mask),
                                           63 - std::countl_zero(mask & other_mask)));
      }
    }
    used.emplace_back(name, mask);
    auto it = std::find_if(map.frames.begin(), map.frames.end(),
                           [&](const CanFrameLayout& f) { return f.id == id; });
    if (it == map.frames.end()) {
      CanFrameLayout layout;
      layout.id = id;
      layout.min_length = static_cast<std::uint8_t>(map.sequence.bytes_needed());
      map.frames.push_back(layout);
      it = map.frames.end() - 1;
    }
    it->min_length =
        std::max<std::uint8_t>(it->min_length, static_cast<std::uint8_t>(field.bytes_needed()));
    it->signals.emplace_back(which, field);
    if (which == ImuSignal::kDeviceTime) map.has_device_time = true;
  }
  // Ids in ascending order: deterministic whatever the JSON object order.
  std::sort(map.frames.begin(), map.frames.end(),
            [](const CanFrameLayout& a, const CanFrameLayout& b) { return a.id < b.id; });
  return map;
}

}  // namespace

std::string_view signal_name(ImuSignal signal) { return kNames[static_cast<std::size_t>(signal)]; }
std::string_view signal_unit(ImuSignal signal) { return kUnits[static_cast<std::size_t>(signal)]; }

std::optional<std::size_t> CanSignalMap::frame_index(canid_t id) const {
  for (std::size_t i = 0; i < frames.size(); ++i) {
    if (frames[i].id == id) return i;
  }
  return std::nullopt;
}

std::optional<std::size_t> CanSignalMap::frame_index(
    canid_t id, std::span<const std::uint8_t, 8> payload) const {
  for (std::size_t i = 0; i < frames.size(); ++i) {
    if (frames[i].id != id) continue;
    if (!frames[i].multiplexed || frames[i].mux.extract_raw(payload) == frames[i].mux_value)
      return i;
  }
  return std::nullopt;
}

std::vector<canid_t> CanSignalMap::ids() const {
  std::vector<canid_t> out;
  for (const auto& f : frames) out.push_back(f.id);
  for (const auto& s : status) out.push_back(s.id);
  for (const auto& c : message_counters) out.push_back(c.id);
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

CanSignalMap CanSignalMap::from_json(const json& doc, const std::string& where) {
  // The schema checks the shape: the signals, every key's type and range, no unknown keys, the
  // units, float lengths; map_from_json the rules between keys.
  core::validate_part_or_throw(core::schema_definition("station.schema.json", "can_signal_map"),
                               doc, "", where);
  return map_from_json(doc, where);
}

CanSignalMap CanSignalMap::load(const std::string& path, const std::string& where) {
  std::ifstream in(path);
  if (!in) {
    throw core::InputError(
        where, path + ": cannot read the CAN signal map (" + std::strerror(errno) + ")");
  }
  std::stringstream text;
  text << in.rdbuf();
  // Errors name the station field that points at the file, then the file (with line:column
  // for a syntax error, or the JSON path within it).
  const std::string file = where + " " + path;
  json doc;
  try {
    doc = core::parse_json_text(text.str(), path);
  } catch (const core::InputError& e) {
    throw core::InputError(where, e.what());
  }
  core::validate_part_or_throw(core::schema_definition("station.schema.json", "can_signal_map"),
                               doc, file, "");
  return map_from_json(doc, file + ":");
}

std::vector<can_frame> encode_sample(const CanSignalMap& map, const core::ImuSample& sample) {
  std::vector<can_frame> out;
  out.reserve(map.frames.size());
  // A layout that delimits samples by an opening frame sends that frame first.
  std::vector<const CanFrameLayout*> order;
  if (map.delimiting == CanSignalMap::Delimiting::kOpeningFrame)
    order.push_back(&map.frames[map.opening_frame]);
  for (const auto& layout : map.frames)
    if (order.empty() || &layout != order.front()) order.push_back(&layout);
  for (const CanFrameLayout* layout_ptr : order) {
    const CanFrameLayout& layout = *layout_ptr;
    can_frame frame{};
    frame.can_id = layout.id;
    frame.len = 8;  // always the full classic payload: simpler receivers, same bus time order
    std::span<std::uint8_t, 8> payload(frame.data);
    if (layout.multiplexed) layout.mux.insert_raw(payload, layout.mux_value);
    const bool carries_sequence =
        map.delimiting == CanSignalMap::Delimiting::kSequenceInEveryFrame ||
        (map.has_sequence && &layout == &map.frames[map.sequence_frame]);
    if (carries_sequence) map.sequence.insert_raw(payload, sample.sequence % map.sequence_wrap());
    for (const auto& counter : map.message_counters) {
      // One frame of each message per sample: its counter steps with the sample's sequence.
      if (counter.id == layout.id) counter.field.insert_raw(payload, sample.sequence);
    }
    for (const auto& [which, field] : layout.signals) {
      double value = 0.0;
      switch (which) {
        case ImuSignal::kGyroX:
          value = sample.gyro_dps.x();
          break;
        case ImuSignal::kGyroY:
          value = sample.gyro_dps.y();
          break;
        case ImuSignal::kGyroZ:
          value = sample.gyro_dps.z();
          break;
        case ImuSignal::kAccelX:
          value = sample.accel_mps2.x();
          break;
        case ImuSignal::kAccelY:
          value = sample.accel_mps2.y();
          break;
        case ImuSignal::kAccelZ:
          value = sample.accel_mps2.z();
          break;
        case ImuSignal::kTemperature:
          value = sample.temperature_c;
          break;
        case ImuSignal::kDeviceTime:
          value = sample.device_time_s;
          break;
      }
      if (which == ImuSignal::kDeviceTime && field.type == FieldType::kUnsigned &&
          field.length_bits < 64) {
        // A device clock counter wraps rather than saturates (the receiver unwraps it).
        const double counts = std::round((value - field.offset) / field.scale);
        const double wrap = std::ldexp(1.0, static_cast<int>(field.length_bits));
        field.insert_raw(payload,
                         static_cast<std::uint64_t>(counts - wrap * std::floor(counts / wrap)));
        continue;
      }
      field.encode(payload, value);
    }
    out.push_back(frame);
  }
  return out;
}

}  // namespace calstand::drivers
