#pragma once

#include <string>

#include "core/station_config.hpp"
#include "drivers/chamber_register_map.hpp"
#include "drivers/serial_port.hpp"

namespace calstand::drivers {

enum class ModbusTransport { kTcp, kRtu };

/// Everything ModbusChamber needs, parsed from the station's chamber section (limits) and its
/// `connection` object (link, map, timing). Plain value; no I/O.
struct ModbusChamberOptions {
  ModbusTransport transport = ModbusTransport::kTcp;
  std::string host = "127.0.0.1";                 ///< TCP only
  int port = 502;                                 ///< TCP only
  SerialOptions serial{"", 9600, Parity::kNone};  ///< RTU only (path, baud [bit/s], parity)
  int unit_id = 1;                                ///< Modbus unit (slave) id of the controller
  ChamberRegisterMap map = watlow_f4t_map();
  int timeout_ms = 500;        ///< response timeout per request (also TCP connect) [ms]
  int poll_period_ms = 250;    ///< wall time between polls [ms]
  double stale_after_s = 5.0;  ///< station time without a valid reading that is a fault [s]

  // From core::ChamberConfig.
  double min_c = -55.0;             ///< lowest setpoint accepted [degC]
  double max_c = 125.0;             ///< highest setpoint accepted [degC]
  double max_ramp_c_per_min = 5.0;  ///< fastest ramp accepted, and the default [degC/min]
  double ambient_c = 23.0;          ///< lab air; the F4-style standby setpoint [degC]

  /// A process value outside [min_c - margin, max_c + margin] is not believed [degC].
  static constexpr double kPlausibleMarginC = 20.0;

  /// "tcp 127.0.0.1:502" or "rtu /dev/ttyUSB0": names the link in every error and event.
  std::string link_name() const;

  /// Parses `config.connection` (fields in docs/protocols.md, "Chamber over Modbus"). Throws
  /// core::InputError naming `chamber.connection.<field>` (or `chamber.<limit>`) and why.
  static ModbusChamberOptions from_config(const core::ChamberConfig& config);
};

}  // namespace calstand::drivers
