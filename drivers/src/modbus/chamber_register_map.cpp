#include "drivers/chamber_register_map.hpp"

#include <fmt/format.h>

#include <bit>
#include <cmath>
#include <limits>

#include "core/error.hpp"
#include "core/schemas.hpp"

namespace calstand::drivers {
namespace {

using nlohmann::json;

std::string join(const std::string& where, std::string_view field) {
  return where.empty() ? std::string(field) : where + "." + std::string(field);
}

RegisterKind kind_from_name(const std::string& name) {
  return name == "input" ? RegisterKind::kInput : RegisterKind::kHolding;
}

RegisterEncoding encoding_from_name(const std::string& name) {
  if (name == "uint16") return RegisterEncoding::kUint16;
  if (name == "float32") return RegisterEncoding::kFloat32;
  return RegisterEncoding::kInt16;
}

// Reads a field the schema has checked (address, kind, encoding, scale in range).
RegisterField field_from_json(const json& j, const std::string& where) {
  RegisterField f;
  f.address = j.at("address").get<std::uint16_t>();
  f.kind = kind_from_name(j.value("kind", "holding"));
  f.encoding = encoding_from_name(j.at("encoding").get<std::string>());
  if (j.contains("scale")) {
    // Cross-field, so not in the schema: a float32 is already in engineering units.
    if (f.encoding == RegisterEncoding::kFloat32) {
      throw core::InputError(join(where, "scale"),
                             "applies to int16/uint16 only (float32 is in "
                             "engineering units)");
    }
    f.scale = j.at("scale").get<double>();
  }
  return f;
}

ModeField mode_from_json(const json& j, const std::string& where) {
  ModeField m;
  m.address = j.at("address").get<std::uint16_t>();
  m.control = j.at("control").get<std::uint16_t>();
  m.standby = j.at("standby").get<std::uint16_t>();
  // Cross-field, so not in the schema.
  if (m.control == m.standby) {
    throw core::InputError(join(where, "standby"), "must differ from control");
  }
  return m;
}

void check_field(const RegisterField& f, const std::string& where, bool written) {
  if (written && f.kind != RegisterKind::kHolding) {
    throw core::InputError(join(where, "kind"), "must be \"holding\": the driver writes it");
  }
  if (f.encoding != RegisterEncoding::kFloat32 && !(std::isfinite(f.scale) && f.scale > 0.0)) {
    throw core::InputError(join(where, "scale"),
                           fmt::format("must be positive and finite, got {}", f.scale));
  }
  if (f.encoding == RegisterEncoding::kFloat32 && f.address == 65535) {
    throw core::InputError(join(where, "address"), "float32 needs two registers: 65534 at most");
  }
}

struct Span {
  std::string name;
  RegisterKind kind;
  int first;
  int last;
};

}  // namespace

std::string_view to_string(RegisterEncoding encoding) {
  switch (encoding) {
    case RegisterEncoding::kInt16:
      return "int16";
    case RegisterEncoding::kUint16:
      return "uint16";
    case RegisterEncoding::kFloat32:
      return "float32";
  }
  return "?";
}

std::string_view to_string(WordOrder order) {
  return order == WordOrder::kHighFirst ? "high_first" : "low_first";
}

std::optional<RegisterWords> encode_value(const RegisterField& field, double value) {
  if (!std::isfinite(value)) return std::nullopt;
  RegisterWords out;
  out.count = field.register_count();
  switch (field.encoding) {
    case RegisterEncoding::kInt16: {
      const double counts = std::round(value / field.scale);
      if (counts < -32768.0 || counts > 32767.0) return std::nullopt;
      out.words[0] = static_cast<std::uint16_t>(static_cast<std::int16_t>(counts));
      return out;
    }
    case RegisterEncoding::kUint16: {
      const double counts = std::round(value / field.scale);
      if (counts < 0.0 || counts > 65535.0) return std::nullopt;
      out.words[0] = static_cast<std::uint16_t>(counts);
      return out;
    }
    case RegisterEncoding::kFloat32: {
      if (std::abs(value) > double(std::numeric_limits<float>::max())) return std::nullopt;
      const auto bits = std::bit_cast<std::uint32_t>(static_cast<float>(value));
      const auto high = static_cast<std::uint16_t>(bits >> 16);
      const auto low = static_cast<std::uint16_t>(bits & 0xFFFFu);
      const bool high_first = field.word_order == WordOrder::kHighFirst;
      out.words[0] = high_first ? high : low;
      out.words[1] = high_first ? low : high;
      return out;
    }
  }
  return std::nullopt;
}

double decode_value(const RegisterField& field, std::span<const std::uint16_t> words) {
  if (words.size() < std::size_t(field.register_count())) {
    return std::numeric_limits<double>::quiet_NaN();
  }
  switch (field.encoding) {
    case RegisterEncoding::kInt16:
      return static_cast<std::int16_t>(words[0]) * field.scale;
    case RegisterEncoding::kUint16:
      return words[0] * field.scale;
    case RegisterEncoding::kFloat32: {
      const bool high_first = field.word_order == WordOrder::kHighFirst;
      const std::uint32_t high = high_first ? words[0] : words[1];
      const std::uint32_t low = high_first ? words[1] : words[0];
      return double(std::bit_cast<float>((high << 16) | low));
    }
  }
  return std::numeric_limits<double>::quiet_NaN();
}

void ChamberRegisterMap::set_word_order(WordOrder order) {
  process_value.word_order = order;
  setpoint.word_order = order;
  if (ramp_rate) ramp_rate->word_order = order;
}

void ChamberRegisterMap::validate(const std::string& where) const {
  check_field(process_value, join(where, "process_value"), false);
  check_field(setpoint, join(where, "setpoint"), true);
  if (ramp_rate) check_field(*ramp_rate, join(where, "ramp_rate"), true);
  // Overlapping fields would make a setpoint write clobber the mode (or read back as the PV).
  std::vector<Span> spans;
  auto add = [&](std::string field_name, const RegisterField& f) {
    spans.push_back({std::move(field_name), f.kind, f.address, f.address + f.register_count() - 1});
  };
  add("process_value", process_value);
  add("setpoint", setpoint);
  if (ramp_rate) add("ramp_rate", *ramp_rate);
  if (mode) spans.push_back({"mode", RegisterKind::kHolding, mode->address, mode->address});
  for (std::size_t i = 0; i < alarms.size(); ++i) {
    spans.push_back({fmt::format("alarms[{}]", i), RegisterKind::kHolding, alarms[i].address,
                     alarms[i].address});
  }
  for (std::size_t i = 0; i < spans.size(); ++i) {
    for (std::size_t k = 0; k < i; ++k) {
      const auto& a = spans[i];
      const auto& b = spans[k];
      if (a.kind == b.kind && a.first <= b.last && b.first <= a.last) {
        throw core::InputError(join(join(where, a.name), "address"),
                               fmt::format("registers {}..{} overlap {} ({}..{})", a.first, a.last,
                                           b.name, b.first, b.last));
      }
    }
  }
  if (!sensor_fault_raw.empty() && process_value.encoding == RegisterEncoding::kFloat32) {
    throw core::InputError(join(where, "sensor_fault_raw"),
                           "applies to int16/uint16 process values only (a float32 fault is "
                           "NaN or infinity)");
  }
}

ChamberRegisterMap watlow_f4_map() {
  ChamberRegisterMap m;
  m.name = "watlow-f4";
  m.process_value = {100, RegisterKind::kHolding, RegisterEncoding::kInt16, 0.1, {}};
  m.setpoint = {300, RegisterKind::kHolding, RegisterEncoding::kInt16, 0.1, {}};
  // Full-scale words are what an int16 controller can say when it has no valid reading; a
  // chamber never sits at +-3276.7 degC, so treating them as a fault costs nothing.
  m.sensor_fault_raw = {0x7FFF, 0x8000};
  return m;
}

ChamberRegisterMap watlow_f4t_map(WordOrder order) {
  ChamberRegisterMap m;
  m.name = "watlow-f4t";
  m.process_value = {2820, RegisterKind::kHolding, RegisterEncoding::kFloat32, 1.0, order};
  m.setpoint = {2782, RegisterKind::kHolding, RegisterEncoding::kFloat32, 1.0, order};
  m.mode = ModeField{2730, 10, 62};
  return m;
}

// CSZ EZT-570i/S: the User Communication Reference Manual, section 2.4 "Control Registers"
// (docs/protocols.md, "CSZ EZT-570", cites it). Where the public material leaves a detail open
// the map takes the cautious reading; a station file's generic map can change each one:
//   - scale: the decimal point is the loop's configuration; one place (tenths) assumed;
//   - on/off: which bit of the chamber manual event word runs the chamber is not spelt out;
//     bit 0, as on CSZ's EZT-550, and the whole word compared (see below);
//   - sensor fault: reported in alarm word 55, not as a process-value sentinel; the int16 full
//     scale is treated as one too, as for the F4;
//   - alarms: which bit is which alarm is not decoded; any bit set is a fault.
ChamberRegisterMap csz_ezt570_map() {
  ChamberRegisterMap m;
  m.name = "csz-ezt570";
  // Control registers 60..119 are the loops, 12 registers each; loop 1 is the air temperature.
  m.process_value = {61, RegisterKind::kHolding, RegisterEncoding::kInt16, 0.1, {}};
  m.setpoint = {60, RegisterKind::kHolding, RegisterEncoding::kInt16, 0.1, {}};
  // The whole event word is written and compared: another event on (humidity, purge) reads as
  // neither control nor standby, which the driver reports as a fault rather than guess what
  // the chamber does.
  m.mode = ModeField{22, 1, 0};
  // No ramp register for constant mode (the controller ramps in its own programs only): the
  // driver steps the setpoint at the requested ramp.
  m.sensor_fault_raw = {0x7FFF, 0x8000};
  // EZT-570 alarm status (input sensor breaks), input, chamber and refrigeration alarm words.
  m.alarms = {{55, "controller alarms"},
              {56, "input alarms"},
              {57, "chamber alarms"},
              {58, "refrigeration alarms"}};
  return m;
}

std::string builtin_map_names() { return "watlow-f4, watlow-f4t, csz-ezt570"; }

std::optional<ChamberRegisterMap> builtin_map(std::string_view name, WordOrder word_order) {
  if (name == "watlow-f4") return watlow_f4_map();
  if (name == "watlow-f4t") return watlow_f4t_map(word_order);
  if (name == "csz-ezt570") return csz_ezt570_map();
  return std::nullopt;
}

WordOrder word_order_from_json(const json& j, const std::string& where) {
  if (j == "high_first") return WordOrder::kHighFirst;
  if (j == "low_first") return WordOrder::kLowFirst;
  throw core::InputError(where, "must be \"high_first\" or \"low_first\", got " + j.dump());
}

ChamberRegisterMap register_map_from_json(const json& j, const std::string& where,
                                          WordOrder word_order) {
  // The schema checks the shape (a built-in name or a map object, every field's type and range,
  // no unknown keys: a misspelt "adress" must not leave a default on a live chamber); the
  // cross-field rules a schema cannot state are in field_from_json, mode_from_json, validate().
  core::validate_part_or_throw(core::schema_definition("station.schema.json", "chamber_map"), j, "",
                               where);
  if (j.is_string()) {
    if (auto m = builtin_map(j.get<std::string>(), word_order)) return *m;
    throw core::InputError(where,
                           fmt::format("no built-in map {} ({})", j.dump(), builtin_map_names()));
  }
  ChamberRegisterMap m;
  m.name = j.value("name", "generic");
  m.process_value = field_from_json(j.at("process_value"), join(where, "process_value"));
  m.setpoint = field_from_json(j.at("setpoint"), join(where, "setpoint"));
  if (j.contains("mode")) m.mode = mode_from_json(j.at("mode"), join(where, "mode"));
  if (j.contains("ramp_rate")) {
    m.ramp_rate = field_from_json(j.at("ramp_rate"), join(where, "ramp_rate"));
  }
  // Signed controllers document their sentinels as negative numbers (-32768): both are words.
  for (const auto& v : j.value("sensor_fault_raw", json::array())) {
    m.sensor_fault_raw.push_back(static_cast<std::uint16_t>(v.get<std::int64_t>() & 0xFFFF));
  }
  if (j.contains("alarms")) {
    for (const auto& a : j.at("alarms")) {
      m.alarms.push_back({a.at("address").get<std::uint16_t>(), a.value("name", "alarms")});
    }
  }
  m.set_word_order(word_order);
  m.validate(where);
  return m;
}

}  // namespace calstand::drivers
