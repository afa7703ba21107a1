#pragma once
// The link to a controller that speaks a line protocol (the table, a bench supply): TCP or a
// serial line, as the station file's `connection` gives it.

#include <nlohmann/json.hpp>
#include <string>

#include "drivers/serial_port.hpp"
#include "drivers/tcp_client.hpp"

namespace calstand::drivers {

struct LineLink {
  enum class Transport { kTcp, kSerial };
  Transport transport = Transport::kTcp;
  TcpOptions tcp;        ///< when transport is kTcp
  SerialOptions serial;  ///< when transport is kSerial

  /// Reads `transport` and its fields from a connection the schema has checked: host, port and
  /// connect_timeout_ms (1000), or path, baud (`default_baud`) and parity ("none").
  static LineLink from_json(const nlohmann::json& connection, int default_baud);
  /// "tcp 127.0.0.1:5025" or "serial /dev/ttyS0", for messages.
  std::string describe() const;
};

}  // namespace calstand::drivers
