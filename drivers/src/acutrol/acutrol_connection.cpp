#include <fmt/format.h>

#include <array>
#include <cmath>
#include <string_view>

#include "core/error.hpp"
#include "drivers/acutrol_table.hpp"

namespace calstand::drivers {
namespace {

constexpr std::string_view kWhere = "table.connection";

// Fields each transport takes; anything else is a typo the station author wants to hear about.
constexpr std::array<std::string_view, 5> kTcpFields{"transport", "host", "port", "timeout_ms",
                                                     "connect_timeout_ms"};
constexpr std::array<std::string_view, 5> kSerialFields{"transport", "path", "baud", "parity",
                                                        "timeout_ms"};

[[noreturn]] void bad(std::string_view field, const std::string& why) {
  throw core::InputError(fmt::format("{}.{}", kWhere, field), why);
}

std::string get_string(const nlohmann::json& j, std::string_view field, bool required,
                       std::string fallback = {}) {
  const auto it = j.find(field);
  if (it == j.end()) {
    if (required) bad(field, "missing");
    return fallback;
  }
  if (!it->is_string()) bad(field, "must be a string");
  return it->get<std::string>();
}

/// An integer field within [lo, hi]; `fallback` when absent and not required.
long long get_int(const nlohmann::json& j, std::string_view field, bool required,
                  long long fallback, long long lo, long long hi) {
  const auto it = j.find(field);
  if (it == j.end()) {
    if (required) bad(field, "missing");
    return fallback;
  }
  // 5025.0 is an integer in JSON's eyes too; 5025.5 is not.
  if (!it->is_number() ||
      (it->is_number_float() && std::trunc(it->get<double>()) != it->get<double>())) {
    bad(field, "must be an integer");
  }
  const double v = it->get<double>();
  if (v < static_cast<double>(lo) || v > static_cast<double>(hi)) {
    bad(field, fmt::format("{} is outside {}..{}", it->dump(), lo, hi));
  }
  return static_cast<long long>(v);
}

template <std::size_t N>
void refuse_unknown(const nlohmann::json& j, const std::array<std::string_view, N>& known,
                    std::string_view transport) {
  for (const auto& [key, value] : j.items()) {
    bool found = false;
    for (const auto k : known) found = found || k == key;
    if (!found) bad(key, fmt::format("unknown field for transport '{}'", transport));
  }
}

}  // namespace

AcutrolConnection AcutrolConnection::from_json(const nlohmann::json& j) {
  if (!j.is_object()) throw core::InputError(std::string(kWhere), "must be an object");
  AcutrolConnection c;
  const std::string transport = get_string(j, "transport", true);
  c.response_timeout = std::chrono::milliseconds(get_int(j, "timeout_ms", false, 500, 1, 60000));
  if (transport == "tcp") {
    refuse_unknown(j, kTcpFields, transport);
    c.transport = Transport::kTcp;
    c.tcp.host = get_string(j, "host", true);
    if (c.tcp.host.empty()) bad("host", "must name the controller, e.g. 127.0.0.1");
    c.tcp.port = static_cast<std::uint16_t>(get_int(j, "port", true, 0, 1, 65535));
    c.tcp.connect_timeout =
        std::chrono::milliseconds(get_int(j, "connect_timeout_ms", false, 1000, 1, 60000));
  } else if (transport == "serial") {
    refuse_unknown(j, kSerialFields, transport);
    c.transport = Transport::kSerial;
    c.serial.path = get_string(j, "path", true);
    if (c.serial.path.empty()) bad("path", "must name a device, e.g. /dev/ttyS0");
    c.serial.baud_rate = static_cast<int>(get_int(j, "baud", false, 115200, 1, 4'000'000));
    const std::string parity = get_string(j, "parity", false, "none");
    if (parity == "none") {
      c.serial.parity = Parity::kNone;
    } else if (parity == "even") {
      c.serial.parity = Parity::kEven;
    } else if (parity == "odd") {
      c.serial.parity = Parity::kOdd;
    } else {
      bad("parity", fmt::format("'{}' is not none, even or odd", parity));
    }
    try {
      c.serial.validate();
    } catch (const core::InputError& e) {
      // SerialOptions names its own fields (serial.baud_rate); say it in the station's terms.
      bad(e.where() == "serial.path" ? "path" : "baud", e.what());
    }
  } else {
    bad("transport", fmt::format("'{}' is not tcp or serial", transport));
  }
  return c;
}

std::string AcutrolConnection::describe() const {
  if (transport == Transport::kTcp) return fmt::format("tcp {}:{}", tcp.host, tcp.port);
  return "serial " + serial.path;
}

}  // namespace calstand::drivers
