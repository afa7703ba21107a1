#include "drivers/line_link.hpp"

#include <fmt/format.h>

namespace calstand::drivers {

LineLink LineLink::from_json(const nlohmann::json& j, int default_baud) {
  LineLink link;
  if (j.at("transport") == "tcp") {
    link.transport = Transport::kTcp;
    link.tcp.host = j.at("host").get<std::string>();
    link.tcp.port = j.at("port").get<std::uint16_t>();
    link.tcp.connect_timeout = std::chrono::milliseconds(j.value("connect_timeout_ms", 1000));
  } else {
    link.transport = Transport::kSerial;
    link.serial.path = j.at("path").get<std::string>();
    link.serial.baud_rate = j.value("baud", default_baud);
    link.serial.parity = parity_from_name(j.value("parity", "none"));
  }
  return link;
}

std::string LineLink::describe() const {
  if (transport == Transport::kTcp) return fmt::format("tcp {}:{}", tcp.host, tcp.port);
  return "serial " + serial.path;
}

}  // namespace calstand::drivers
