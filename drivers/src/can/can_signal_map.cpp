#include "drivers/can_signal_map.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "core/error.hpp"

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

void refuse_unknown_keys(const json& obj, const std::string& where,
                         std::initializer_list<std::string_view> allowed) {
  for (const auto& [key, value] : obj.items()) {
    if (std::find(allowed.begin(), allowed.end(), key) != allowed.end()) continue;
    std::string list;
    for (auto a : allowed) list += (list.empty() ? "" : ", ") + std::string(a);
    throw core::InputError(join(where, key), "unknown key (expected one of: " + list + ")");
  }
}

const json& require_object(const json& v, const std::string& where) {
  if (!v.is_object()) throw core::InputError(where, "must be an object");
  return v;
}

std::uint64_t get_count(const json& obj, std::string_view key, const std::string& where,
                        std::uint64_t min, std::uint64_t max) {
  const json& v = obj.at(std::string(key));
  const std::string here = join(where, key);
  // Integers built in C++ are signed in nlohmann::json, parsed ones unsigned: accept both.
  if (!v.is_number_integer() || (!v.is_number_unsigned() && v.get<std::int64_t>() < 0)) {
    throw core::InputError(here, "must be a whole number >= 0, not " + v.dump());
  }
  const auto n = v.get<std::uint64_t>();
  if (n < min || n > max) {
    throw core::InputError(here, fmt::format("{} is out of range {}..{}", n, min, max));
  }
  return n;
}

double get_finite(const json& obj, std::string_view key, const std::string& where,
                  double fallback) {
  if (!obj.contains(std::string(key))) return fallback;
  const json& v = obj.at(std::string(key));
  if (!v.is_number() || !std::isfinite(v.get<double>())) {
    throw core::InputError(join(where, key), "must be a finite number, not " + v.dump());
  }
  return v.get<double>();
}

ByteOrder parse_byte_order(const json& v, const std::string& where) {
  if (v == "little") return ByteOrder::kLittle;
  if (v == "big") return ByteOrder::kBig;
  throw core::InputError(where,
                         "unknown byte order " + v.dump() + " (expected \"little\" or \"big\")");
}

FieldType parse_type(const json& v, const std::string& where) {
  if (v == "unsigned") return FieldType::kUnsigned;
  if (v == "signed") return FieldType::kSigned;
  if (v == "float") return FieldType::kFloat;
  throw core::InputError(
      where, "unknown type " + v.dump() + " (expected \"unsigned\", \"signed\" or \"float\")");
}

/// An id as a number or a string ("0x101" or "257"); flags from `extended`.
canid_t parse_id(const json& sig, const std::string& where) {
  const std::string here = join(where, "id");
  if (!sig.contains("id")) throw core::InputError(here, "missing (the CAN id carrying the value)");
  const json& v = sig.at("id");
  std::uint64_t id = 0;
  if (v.is_number_integer() && (v.is_number_unsigned() || v.get<std::int64_t>() >= 0)) {
    id = v.get<std::uint64_t>();
  } else if (v.is_string()) {
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
    throw core::InputError(here, "must be a number or a string such as \"0x101\", not " + v.dump());
  }
  bool extended = false;
  if (sig.contains("extended")) {
    if (!sig.at("extended").is_boolean()) {
      throw core::InputError(join(where, "extended"), "must be true or false");
    }
    extended = sig.at("extended").get<bool>();
  }
  const std::uint64_t max = extended ? CAN_EFF_MASK : CAN_SFF_MASK;
  if (id > max) {
    throw core::InputError(here, fmt::format("0x{:X} is beyond the {} ids (max 0x{:X}){}", id,
                                             extended ? "29-bit" : "11-bit", max,
                                             extended ? "" : "; set \"extended\": true"));
  }
  return static_cast<canid_t>(id) | (extended ? CAN_EFF_FLAG : 0u);
}

/// The layout keys shared by values and the sequence counter.
CanField parse_layout(const json& sig, const std::string& where, ByteOrder default_order) {
  CanField f;
  const bool by_byte = sig.contains("start_byte");
  const bool by_bit = sig.contains("start_bit");
  if (by_byte == by_bit) {
    throw core::InputError(join(where, "start_byte"),
                           by_byte ? "give start_byte or start_bit, not both"
                                   : "missing (give start_byte or start_bit)");
  }
  f.start_bit = by_byte ? static_cast<std::uint32_t>(8 * get_count(sig, "start_byte", where, 0, 7))
                        : static_cast<std::uint32_t>(get_count(sig, "start_bit", where, 0, 63));
  if (!sig.contains("length_bits")) throw core::InputError(join(where, "length_bits"), "missing");
  f.length_bits = static_cast<std::uint32_t>(get_count(sig, "length_bits", where, 1, 64));
  if (f.start_bit + f.length_bits > 64) {
    throw core::InputError(
        join(where, "length_bits"),
        fmt::format("start bit {} + {} bits reaches beyond the 64 bits (8 bytes) "
                    "of a CAN frame",
                    f.start_bit, f.length_bits));
  }
  f.byte_order = sig.contains("byte_order")
                     ? parse_byte_order(sig.at("byte_order"), join(where, "byte_order"))
                     : default_order;
  return f;
}

CanField parse_value(const json& sig, const std::string& where, ImuSignal which,
                     ByteOrder default_order) {
  refuse_unknown_keys(sig, where,
                      {"id", "extended", "start_byte", "start_bit", "length_bits", "byte_order",
                       "type", "scale", "offset", "unit", "description"});
  CanField f = parse_layout(sig, where, default_order);
  if (!sig.contains("type")) {
    throw core::InputError(join(where, "type"), "missing (\"unsigned\", \"signed\" or \"float\")");
  }
  f.type = parse_type(sig.at("type"), join(where, "type"));
  if (f.type == FieldType::kFloat && f.length_bits != 32 && f.length_bits != 64) {
    throw core::InputError(join(where, "length_bits"),
                           fmt::format("a float is 32 or 64 bits, not {}", f.length_bits));
  }
  f.scale = get_finite(sig, "scale", where, 1.0);
  if (f.scale == 0.0) throw core::InputError(join(where, "scale"), "must not be 0");
  f.offset = get_finite(sig, "offset", where, 0.0);
  if (sig.contains("unit") && sig.at("unit") != signal_unit(which)) {
    throw core::InputError(
        join(where, "unit"),
        fmt::format("{} is in {}, not {}: fold a conversion into scale", signal_name(which),
                    signal_unit(which), sig.at("unit").dump()));
  }
  return f;
}

CanField parse_sequence(const json& sig, const std::string& where, ByteOrder default_order) {
  refuse_unknown_keys(
      sig, where, {"start_byte", "start_bit", "length_bits", "byte_order", "type", "description"});
  CanField f = parse_layout(sig, where, default_order);
  if (sig.contains("type") && sig.at("type") != "unsigned") {
    throw core::InputError(join(where, "type"), "the sequence counter is \"unsigned\"");
  }
  if (f.length_bits > 32) {
    throw core::InputError(
        join(where, "length_bits"),
        fmt::format("a sequence counter has at most 32 bits, not {}", f.length_bits));
  }
  return f;
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

std::vector<canid_t> CanSignalMap::ids() const {
  std::vector<canid_t> out;
  for (const auto& f : frames) out.push_back(f.id);
  return out;
}

CanSignalMap CanSignalMap::from_json(const json& doc, const std::string& where) {
  require_object(doc, where);
  refuse_unknown_keys(doc, where, {"signals", "byte_order", "reassembly_depth", "description"});
  CanSignalMap map;
  const ByteOrder default_order =
      doc.contains("byte_order") ? parse_byte_order(doc.at("byte_order"), join(where, "byte_order"))
                                 : ByteOrder::kLittle;
  if (doc.contains("reassembly_depth")) {
    map.reassembly_depth = get_count(doc, "reassembly_depth", where, 1, 16);
  }
  const std::string sigs_where = join(where, "signals");
  if (!doc.contains("signals")) throw core::InputError(sigs_where, "missing");
  const json& sigs = require_object(doc.at("signals"), sigs_where);

  // Names first, so that a typo reads "unknown signal" rather than "missing gyro_x".
  for (const auto& [key, value] : sigs.items()) {
    const bool known =
        key == "sequence" || std::find(kNames.begin(), kNames.end(), key) != kNames.end();
    if (!known) {
      throw core::InputError(join(sigs_where, key),
                             "unknown signal (expected gyro_x, gyro_y, gyro_z, accel_x, accel_y, "
                             "accel_z, temperature, device_time or sequence)");
    }
    require_object(value, join(sigs_where, key));
  }
  if (!sigs.contains("sequence")) {
    throw core::InputError(sigs_where,
                           "missing sequence (every frame carries the sample's "
                           "sequence counter: that is how frames are matched)");
  }
  map.sequence = parse_sequence(sigs.at("sequence"), join(sigs_where, "sequence"), default_order);

  // Each value's frame; the sequence occupies the same bits of every frame.
  std::map<canid_t, std::vector<std::pair<std::string, std::uint64_t>>> occupied;
  for (std::size_t i = 0; i < kImuSignalCount; ++i) {
    const auto which = static_cast<ImuSignal>(i);
    const std::string name(kNames[i]);
    const std::string here = join(sigs_where, name);
    if (!sigs.contains(name)) {
      if (which == ImuSignal::kDeviceTime) continue;  // optional: time from the sequence instead
      throw core::InputError(sigs_where, "missing " + name +
                                             " (a map gives gyro_x/y/z, "
                                             "accel_x/y/z, temperature and sequence)");
    }
    const json& sig = sigs.at(name);
    const canid_t id = parse_id(sig, here);
    const CanField field = parse_value(sig, here, which, default_order);
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
      map.frames.push_back({id, static_cast<std::uint8_t>(map.sequence.bytes_needed()), {}});
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

CanSignalMap CanSignalMap::load(const std::string& path, const std::string& where) {
  std::ifstream in(path);
  if (!in) {
    throw core::InputError(
        where, path + ": cannot read the CAN signal map (" + std::strerror(errno) + ")");
  }
  std::stringstream text;
  text << in.rdbuf();
  json doc;
  try {
    doc = json::parse(text.str());
  } catch (const json::parse_error& e) {
    throw core::InputError(where, path + ": not valid JSON: " + e.what());
  }
  return from_json(doc, where + " " + path + ":");
}

std::vector<can_frame> encode_sample(const CanSignalMap& map, const core::ImuSample& sample) {
  std::vector<can_frame> out;
  out.reserve(map.frames.size());
  for (const auto& layout : map.frames) {
    can_frame frame{};
    frame.can_id = layout.id;
    frame.len = 8;  // always the full classic payload: simpler receivers, same bus time order
    std::span<std::uint8_t, 8> payload(frame.data);
    map.sequence.insert_raw(payload, sample.sequence % map.sequence_wrap());
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
